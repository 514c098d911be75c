#pragma once
/// \file
/// Shape checks of a spline that CAD export and users care about: where it folds (its normal
/// reverses) and how far its parameterization stretches.

#include <tbs/atlas.h>
#include <tbs/evaluator.h>
#include <tbs/spline.h>

#include <vector>

namespace tbs {

/// The result of check_shape().
struct ShapeCheck {
  /// Domain triangles where the surface folds: it turns back over itself, its normal reversing
  /// (turning by more than 150 degrees) between points that lie within the tolerance of each
  /// other in space. Neighbouring samples of a lattice in the triangle, or the two sides of a
  /// smooth domain edge of it, whose normals are more than 90 degrees apart are looked at
  /// closely: the parameter segment between them is halved until its ends lie within the
  /// tolerance, following the halves that still turn by more than 90 degrees. A sharp turn that
  /// does not reverse within the tolerance is no fold. Ascending.
  std::vector<int> folded_triangles;
  /// The largest angle in degrees between neighbouring normals where the surface is smooth
  /// (inside triangles and across domain edges that are not feature edges).
  double max_normal_turn = 0;
  /// The largest |F_u| or |F_v| over the samples of a chart (a component of the domain),
  /// times the diameter of that chart's bounding box, over the chart's size (the diagonal of
  /// the bounding box of its surface samples); the largest over the charts. About 1 for an
  /// even parameterization; a large value means that a small part of a chart carries a large
  /// part of its surface.
  double max_stretch = 0;
  /// Samples where F_u x F_v vanishes (no normal); left out of the comparisons.
  size_t singular_samples = 0;
};

/// Samples every domain triangle on a lattice of `resolution` steps per side, strictly inside
/// it (a barycentric 1e-4 from its edges, so that each sample lies on the triangle's own
/// side of any knot line along an edge), and `resolution` points along every domain edge on
/// both sides, and compares the normals of neighbouring samples. `tolerance` (model units) is
/// the distance within which a reversal is a fold: the fit's tolerance; 0 takes
/// tol::kDefaultFoldTolerance of the model size (the diagonal of the samples' box).
/// With an atlas (charts glued along seams), only the samples inside the charts' outlines count
/// (chart_outlines()): the surface ends there, the margins of the domain beyond are not part
/// of it; the stretch then takes each chart's diameter from those samples' parameters.
/// Deterministic for any `threads` (0 = all cores).
/// \throw InvalidInput if resolution is not between 1 and 256 or the tolerance is negative or
///   not finite.
ShapeCheck check_shape(const Spline& spline, const Evaluator& eval, int resolution = 8, int threads = 0,
                       double tolerance = 0, const Atlas& atlas = {});

}  // namespace tbs
