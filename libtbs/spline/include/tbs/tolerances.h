#pragma once
/// \file
/// Every numerical tolerance of the core in one place, with the reason for its value.

namespace tbs::tol {

/// Highest supported degree. Top simplex splines of the degree n-1 form have n+2 knots; the
/// graph stores knot sets of up to kMaxDegree + 3 knots (degree-n definition, used in tests).
inline constexpr int kMaxDegree = 8;

/// Sub-knots of the default placement lie at distances between kSubKnotMin and kSubKnotMax
/// times Traas's radius r (half the smallest height at the vertex). Keeping them away from 0
/// limits the 1/|d| amplification of roundoff on tiny knot triangles (METHOD.md section 6);
/// keeping them below 1 keeps them strictly inside the circle, as Traas's scheme requires.
inline constexpr double kSubKnotMin = 0.25;
inline constexpr double kSubKnotMax = 0.8;

/// The knot check calls the intersection of all X_{I,beta} of a triangle empty when its area
/// is below this fraction of the triangle's area: clipping in floating point leaves slivers of
/// about 1e-16 relative area where the exact intersection is a point or a segment.
inline constexpr double kCommonInteriorRelArea = 1e-12;

/// A fold is a reversal of the normal (a turn above 150 degrees) between points of the surface
/// that lie within the fit tolerance of each other (the steerers' definition, issue 48); where
/// no tolerance is known, this fraction of the model size, the default relative tolerance of a
/// fit. A sharp turn that the data demands turns at about the tolerance's radius and does not
/// reverse within it.
inline constexpr double kDefaultFoldTolerance = 1e-3;

}  // namespace tbs::tol
