#pragma once
/// \file
/// Compact CAD patches: the spline as few triangular Bezier patches of one degree m >= n as
/// a tolerance allows, with shared boundary curves, for STEP and IGES export.
///
/// Each domain triangle starts as one patch and is split 1-to-4 only where the patch, or one
/// of its boundary curves, is further than the tolerance from the spline. Patches of
/// different size may meet along a side (a "T-junction"): the longer side then carries the
/// curve, and the shorter sides use pieces of it. Every boundary curve is computed once, from
/// the spline, and every patch that touches it takes its boundary control points from it, so
/// the patch set is watertight by construction.

#include <tbs/spline.h>

#include <span>
#include <vector>

namespace tbs {

struct CadPatchOptions {
  /// Patch degree m; 0 means the spline's degree + 2. Must be at least the spline's degree
  /// (a patch of lower degree cannot reproduce even one polynomial piece) and at most 15.
  int degree = 0;
  /// Largest allowed distance between patch and spline, relative to the model size (the
  /// diagonal of the control points' bounding box).
  double tolerance = 1e-6;
  /// If > 0, the largest allowed distance in model units; overrides `tolerance`.
  double tolerance_abs = 0;
  /// Largest allowed angle, in degrees, between the normals of two patches that meet where
  /// the spline is smooth. Each patch keeps within half of it of the spline's normal (on its
  /// own side of a feature edge, so creases keep their angle), except on a patch split 4 times
  /// or more whose last two splits did not bring its normal deviation below 3/4 of what it
  /// was: there the spline's normal
  /// turns faster than patches can follow (a crease ending inside the surface, a fold), and
  /// the patch is kept (max_normal_deviation then says by how much it misses).
  double angle_tolerance = 1.0;
  /// Deepest 1-to-4 split (a patch then spans 4^-max_level of its domain triangle). Where the
  /// tolerance is not met at this depth, the result says so (within_tolerance = false).
  int max_level = 10;
  /// Most patches. A round that would exceed it splits only the patches furthest out of
  /// tolerance (relative to the tolerances), as many as fit, and splitting stops there (the
  /// result says budget_reached and, where the tolerances are not met, within_tolerance =
  /// false). Must be at least the number of domain triangles.
  long max_patches = 50'000;
  int threads = 0;  ///< Worker threads, 0 for all cores. The result does not depend on it.
};

/// One patch: a triangle of the parameter plane inside one domain triangle.
struct CadPatch {
  int triangle = -1;            ///< The domain triangle.
  int level = 0;                ///< Number of 1-to-4 splits from the domain triangle.
  std::array<int, 3> corners{};  ///< Indices into CadPatches::vertices, counter-clockwise.
};

/// A boundary curve between two patch corners: one BRep edge. Every patch side is a chain
/// of these (more than one where smaller patches meet it on the other side).
struct CadEdge {
  std::array<int, 2> vertices{};      ///< From, to (indices into CadPatches::vertices).
  int domain_edge = -1;               ///< The domain edge it lies on, -1 inside a triangle.
  bool feature = false;               ///< It lies on a feature edge (C^0 crease).
  std::vector<Point3> control_points;  ///< degree + 1 points, from vertices[0] to vertices[1].
};

/// A patch side's piece: edge `edge`, traversed backwards if `reversed`.
struct CadEdgeUse {
  int edge = -1;
  bool reversed = false;
};

/// The result of make_cad_patches().
struct CadPatches {
  int degree = 0;                       ///< m.
  double tolerance = 0;                 ///< The absolute position tolerance used.
  double angle_tolerance = 0;           ///< Degrees.
  std::vector<Point2> vertex_parameters;  ///< Parameter point of each vertex.
  std::vector<Point3> vertices;           ///< Model-space position of each vertex.
  std::vector<CadPatch> patches;          ///< Grouped by domain triangle, in triangle order.
  std::vector<int> patch_start;           ///< Patches of triangle t: [patch_start[t], patch_start[t+1]).
  /// beta_count(degree) control points per patch, in beta order; b_j goes with corners[j].
  std::vector<Point3> control_points;
  std::vector<CadEdge> edges;
  /// Per patch, the edges along its boundary, counter-clockwise from corners[1] (the side
  /// opposite corner 0 first, then the sides opposite corners 1 and 2).
  std::vector<std::vector<CadEdgeUse>> boundaries;
  /// Largest distance between a patch and the spline over the check samples (model units).
  double max_position_deviation = 0;
  /// Largest angle in degrees between a patch normal and the spline normal on the same side
  /// (at most angle_tolerance / 2 when within_tolerance).
  double max_normal_deviation = 0;
  /// Both deviations are within the tolerances.
  bool within_tolerance = false;
  /// Splitting stopped at CadPatchOptions::max_patches.
  bool budget_reached = false;
  int rounds = 0;  ///< Split rounds performed.

  std::span<const Point3> net(int patch) const {
    const size_t k = static_cast<size_t>(beta_count(degree));
    return {control_points.data() + k * static_cast<size_t>(patch), k};
  }
};

/// Approximates `spline` by compact Bezier patches (see the file comment).
/// \throw InvalidInput if the spline has no triangles or an option is out of range: degree below
///   the spline's or above 15, no positive tolerance, angle_tolerance outside (0, 90), max_level
///   outside 0 to 16, or max_patches below the number of domain triangles.
CadPatches make_cad_patches(const Spline& spline, const CadPatchOptions& options = {});

}  // namespace tbs
