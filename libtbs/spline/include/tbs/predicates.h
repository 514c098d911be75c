#pragma once
/// \file
/// Exact orientation predicates and the half-open rule (METHOD.md section 7).
///
/// A point u that lies exactly on a knot line, a domain edge or a vertex is classified by a
/// symbolic perturbation u' = u + eps (c - u) + eps^2 (d - u), eps -> 0+, with u, c, d not
/// collinear: u belongs to a triangle iff u' lies in its interior. For eps small enough u' is
/// on no line through two knots, so every point lies in exactly one triangle of any
/// triangulation and the partition of unity holds exactly on edges and vertices too.

#include <tbs/types.h>

#include <cmath>

namespace tbs {

/// d(a, b, c) = det[[1,1,1],[a,b,c]] in floating point: twice the signed area of abc.
inline double det3(const Point2& a, const Point2& b, const Point2& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

namespace detail {
int orientation_exact(const Point2& a, const Point2& b, const Point2& c);
}

/// The exact sign (-1, 0, +1) of d(a, b, c). A floating-point filter decides almost every
/// call; the rest go to CGAL's exact predicate.
/// Throws nothing but std::bad_alloc (CGAL's exact fallback may allocate). \pre finite points.
inline int orientation(const Point2& a, const Point2& b, const Point2& c) {
  const double l = (a.x() - c.x()) * (b.y() - c.y());
  const double r = (a.y() - c.y()) * (b.x() - c.x());
  const double det = l - r;
  // Forward error bound of this expression: (3 + 16 eps) eps (|l| + |r|), eps = 2^-53.
  constexpr double kEps = 1.1102230246251565e-16;
  constexpr double kBound = (3.0 + 16.0 * kEps) * kEps;
  const double bound = kBound * (std::fabs(l) + std::fabs(r));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return detail::orientation_exact(a, b, c);
}

/// The symbolic perturbation of an evaluation point (see the file comment).
struct Perturbation {
  Point2 u;  ///< The point itself.
  Point2 c;  ///< First-order direction: u' moves toward c.
  Point2 d;  ///< Second-order direction, not collinear with u and c.

  /// The default rule: first along +x, then along +y.
  static Perturbation standard(const Point2& u) {
    const double s = std::max({1.0, std::fabs(u.x()), std::fabs(u.y())});
    return {u, Point2(u.x() + s, u.y()), Point2(u.x(), u.y() + s)};
  }
  /// Toward the point c first, then toward d (u, c, d must not be collinear).
  static Perturbation toward(const Point2& u, const Point2& c, const Point2& d) { return {u, c, d}; }
};

/// Sign of d(a, b, u'), where u' is the perturbed point. Zero only if a == b.
/// Throws as orientation().
inline int perturbed_orientation(const Point2& a, const Point2& b, const Perturbation& p) {
  if (int s = orientation(a, b, p.u)) return s;
  if (int s = orientation(a, b, p.c)) return s;
  return orientation(a, b, p.d);
}

/// Half-open containment: true iff the perturbed point lies in the interior of triangle abc
/// (either orientation). A degenerate triangle contains nothing. Throws as orientation().
inline bool half_open_contains(const Point2& a, const Point2& b, const Point2& c,
                               const Perturbation& p) {
  const int o = orientation(a, b, c);
  if (o == 0) return false;
  if (o > 0) {
    return perturbed_orientation(a, b, p) > 0 && perturbed_orientation(b, c, p) > 0 &&
           perturbed_orientation(c, a, p) > 0;
  }
  return perturbed_orientation(a, c, p) > 0 && perturbed_orientation(c, b, p) > 0 &&
         perturbed_orientation(b, a, p) > 0;
}

/// Closed containment for a counter-clockwise triangle abc (exact). Throws as orientation().
inline bool closed_contains_ccw(const Point2& a, const Point2& b, const Point2& c,
                                const Point2& u) {
  return orientation(a, b, u) >= 0 && orientation(b, c, u) >= 0 && orientation(c, a, u) >= 0;
}

}  // namespace tbs
