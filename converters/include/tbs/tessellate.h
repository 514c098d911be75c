#pragma once
/// \file
/// Triangle meshes of the spline surface for viewers and graphics formats.

#include <tbs/spline.h>

#include <vector>

namespace tbs {

struct TessellateOptions {
  /// Uniform mode (chordal_tolerance == 0): every domain edge is cut into `resolution`
  /// segments and every domain triangle into resolution^2 faces.
  int resolution = 8;
  /// Adaptive mode when > 0: each domain triangle is refined (doubling its resolution, up to
  /// max_resolution) until the faces are within this distance of the surface, relative to the
  /// model size (the diagonal of the control points' bounding box).
  double chordal_tolerance = 0;
  /// Adaptive mode with the distance in model units; overrides chordal_tolerance.
  double chordal_tolerance_abs = 0;
  int max_resolution = 64;
  /// Give vertices on feature edges one copy per side, each with the normal of its side, so
  /// that creases shade sharp. The copies have the same position bit for bit; the mesh is
  /// then open along feature edges (topologically), closed everywhere else.
  bool split_features = false;
  int threads = 0;  ///< Worker threads, 0 for all cores. The result does not depend on it.
};

/// A watertight triangle mesh of the surface: faces of neighbouring domain triangles share
/// their vertices along the common edge.
struct Mesh {
  std::vector<Point3> positions;   ///< #V points on the surface: positions[i] = F(parameters[i]).
  std::vector<Vector3> normals;    ///< #V unit normals of the spline (zero where singular).
  std::vector<Point2> parameters;  ///< #V parameter points (u, v).
  std::vector<std::array<int, 3>> faces;  ///< #F triangles, counter-clockwise in (u, v).
  std::vector<int> face_triangle;  ///< #F domain triangle of each face.
  /// Largest distance between a face and the surface, measured at face centroids and edge
  /// midpoints (model units).
  double max_chordal_deviation = 0;
  std::vector<int> resolution;     ///< Per domain triangle, the resolution used.
};

/// Tessellates `spline`.
/// \throw InvalidInput if resolution (uniform mode) or max_resolution (adaptive mode) is outside
///   1 to 4096, or a chordal tolerance is negative.
Mesh tessellate(const Spline& spline, const TessellateOptions& options = {});

}  // namespace tbs
