#pragma once
/// \file
/// Shape checks of a spline that CAD export and users care about: where it folds (its normal
/// reverses) and how far its parameterization stretches.

#include <tbs/evaluator.h>
#include <tbs/spline.h>

#include <vector>

namespace tbs {

/// The result of check_shape().
struct ShapeCheck {
  /// Domain triangles where the surface folds: two neighbouring samples of a lattice in the
  /// triangle, or the two sides of a smooth domain edge of it, whose normals are more than 90
  /// degrees apart. Ascending.
  std::vector<int> folded_triangles;
  /// The largest angle in degrees between neighbouring normals where the surface is smooth
  /// (inside triangles and across domain edges that are not feature edges).
  double max_normal_turn = 0;
  /// The largest |F_u| or |F_v| over the samples, times the diameter of the domain's bounding
  /// box, over the model size (the diagonal of the bounding box of the surface samples). About 1 for
  /// an even parameterization; a large value means that a small part of the domain carries a
  /// large part of the surface.
  double max_stretch = 0;
  /// Samples where F_u x F_v vanishes (no normal); left out of the comparisons.
  size_t singular_samples = 0;
};

/// Samples every domain triangle on a lattice of `resolution` steps per side, strictly inside
/// it (a barycentric 1e-4 from its edges, so that each sample lies on the triangle's own
/// side of any knot line along an edge), and `resolution` points along every domain edge on
/// both sides, and compares the normals of neighbouring samples.
/// Deterministic for any `threads` (0 = all cores).
/// \throw InvalidInput if resolution is not between 1 and 256.
ShapeCheck check_shape(const Spline& spline, const Evaluator& eval, int resolution = 8, int threads = 0);

}  // namespace tbs
