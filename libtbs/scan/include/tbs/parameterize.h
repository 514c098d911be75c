#pragma once
/// \file
/// Parameters (u, v) for scans that have none. A mesh is repaired, one connected component is
/// chosen and flattened bijectively (free-boundary conformal, LSCM, with a fallback that cannot
/// fold); a closed surface, one with handles, or one whose single flattening would stretch too
/// much is cut into charts first (an atlas: Scan::atlas), each flattened on its own. A bare point cloud is
/// first meshed by advancing-front reconstruction, and every point gets the parameter of its
/// closest point on that mesh.

#include <tbs/scan.h>

#include <functional>
#include <string>
#include <vector>

namespace tbs {

/// Topology of a triangle mesh: chi = V - E + F = 2 (components) - 2 genus - boundary loops.
struct MeshTopology {
  size_t vertices = 0, edges = 0, faces = 0;
  int components = 0;
  int boundary_loops = 0;
  int genus = 0;  ///< summed over the components
  /// For example "1 component, 2 boundary loops, genus 0". Throws nothing but std::bad_alloc.
  std::string describe() const;
};

/// The topology of a triangle mesh. \pre indices in range; the mesh is treated as given
/// (non-manifold edges count once per distinct vertex pair). Throws nothing but std::bad_alloc.
MeshTopology mesh_topology(size_t vertex_count, const std::vector<std::array<int, 3>>& triangles);

enum class FlattenMethod {
  /// LSCM; if it folds (a triangle flipped, or the boundary crossing itself), mean-value
  /// coordinates with the outer boundary on a circle, which cannot fold. A fold-free LSCM map
  /// whose mean area distortion is above 10 (a part of the surface shrunk tenfold and more, as
  /// on a near-closed surface opened at a small loop) is relaxed toward equal areas, halfway
  /// on a log scale, without folding (SLIM on the symmetric Dirichlet energy).
  Auto,
  Lscm,       ///< LSCM only, never relaxed: an error if it folds
  MeanValue,  ///< mean-value coordinates, circular outer boundary (holes filled while solving)
};

struct ParameterizeOptions {
  FlattenMethod method = FlattenMethod::Auto;
  /// The connected component to flatten, numbered from 1 by decreasing face count; 0 is the
  /// largest (the same as 1).
  int component = 0;
  /// A closed surface, or one with handles, is cut into charts (an atlas, see chart_stretch);
  /// false refuses it.
  bool cut_closed = true;
  /// The most a chart's flattening may stretch a spline over it: the largest |F_u|, |F_v|
  /// (1 over the smaller singular value of the map from the surface to the plane, scaled to
  /// the surface's area) times the diameter of the chart's (u, v) box over that of its 3D box,
  /// as FitReport::max_stretch measures the fit (leaving out the worst 0.5 % of the area). A
  /// surface that is not a disk, or whose one flattening (FlattenMethod::Auto) stretches more
  /// or folds, is cut into charts: along sharp edges (sharp_angle), across handles, between
  /// the boundary loops of a tube, and in two until each chart keeps within this.
  double chart_stretch = 4;
  /// Meshes with fewer vertices are refined by 1-to-4 subdivision until they have at least this
  /// many (at most 4 times), so that the fit has more than the vertices to go by: the new
  /// points lie on a smooth surface through the old ones (PN triangles from crease-aware
  /// normals; edges where the faces' normals turn by more than `sharp_angle` stay straight),
  /// their parameters are the midpoints in (u, v). 0: never.
  size_t min_points = 0;
  double sharp_angle = 40;  ///< degrees; see min_points
  /// Called between steps with a line for a person. May be empty.
  std::function<void(const std::string&)> progress;
};

/// Distortion of the flattening, per triangle, weighted by the triangles' 3D areas. With
/// s1 >= s2 the singular values of the map from a triangle to its (u, v) image (after scaling
/// the whole parameterization to the surface's area): angle distortion s1 / s2 (1 for a
/// conformal map), area distortion max(s1 s2, 1 / (s1 s2)) (1 where areas are kept).
struct Distortion {
  double angle_mean = 1, angle_max = 1;
  double area_mean = 1, area_max = 1;
};

struct ParameterizeReport {
  std::string input;                   ///< "mesh" or "point cloud"
  size_t input_points = 0, input_faces = 0;
  size_t reconstructed_faces = 0;      ///< point clouds: faces of the reconstructed mesh
  size_t bridge_faces_removed = 0;     ///< point clouds: reconstructed faces spanning a gap (an edge over 20 local spacings), removed
  size_t vertices_merged = 0;          ///< duplicate vertices merged
  size_t faces_removed = 0;            ///< degenerate (repeated-corner, zero-area) and duplicate faces
  size_t vertices_split = 0;           ///< copies made to repair non-manifold vertices and edges
  bool reoriented = false;             ///< faces were flipped to a consistent orientation
  size_t isolated_points = 0;          ///< mesh vertices used by no face (left out)
  MeshTopology topology;               ///< of the repaired mesh, all components
  int component = 1;                   ///< the component flattened (1 = largest)
  MeshTopology used;                   ///< of that component (before any seam cut)
  size_t seam_edges = 0;               ///< the surface was cut into charts along this many edges
  int charts = 1;                      ///< charts of the atlas (1: one flattening, no seam)
  size_t seams = 0;                    ///< seams of the atlas (chains of cut edges)
  /// The largest stretch of a chart's flattening (ParameterizeOptions::chart_stretch).
  double stretch = 0;
  std::string method;                  ///< "LSCM", "LSCM, areas relaxed" or "mean value (circular boundary)"
  std::string fallback_reason;         ///< why LSCM was not kept; empty if it was
  Distortion distortion;
  /// "LSCM, areas relaxed": the distortion of the conformal map before it was relaxed.
  Distortion conformal;
  size_t points_projected = 0;         ///< point clouds: points given the parameter of their closest mesh point
  size_t points_dropped = 0;           ///< points of other components, or not on the mesh
  int subdivisions = 0;                ///< 1-to-4 subdivisions of a coarse mesh (min_points)
  size_t points_added = 0;             ///< points those made
  double seconds = 0;
  /// The report as a JSON object (text). Throws nothing but std::bad_alloc.
  std::string to_json() const;
};

struct ParameterizedScan {
  /// The scan with parameters: for a mesh its chosen component's vertices (a vertex on a seam
  /// appears twice, once per side) and faces; for a point cloud its points without faces.
  Scan scan;
  /// The input point of each output point (an index into the input scan's positions).
  std::vector<size_t> source;
  ParameterizeReport report;
};

/// Computes parameters for a scan without them: a mesh (scan.triangles non-empty) or a point
/// cloud. Normals of the input are carried to the output, normalised.
/// \throw InvalidInput naming the scan and what was found (components, boundary loops,
///   genus) if the chosen component is closed or has handles and cut_closed is false, or a
///   chart can be neither cut nor flattened; if the component does not exist; if the scan has fewer than 3
///   points, a point cloud's points are identical or collinear, or the reconstruction or the
///   repair leaves no triangle; if LSCM folds with FlattenMethod::Lscm; or if no method gives a
///   bijective map (some of these flattening messages do not name the scan); if a position
///   is not finite or above 1e30 in magnitude, a normal is not finite or zero, the normals are
///   neither empty nor one per position, or a triangle index is out of range.
/// \throw SolverError if the mean-value system cannot be solved, or LSCM's with
///   FlattenMethod::Lscm (FlattenMethod::Auto falls back to mean value, and says why in
///   ParameterizeReport::fallback_reason). Whatever options.progress throws passes through.
ParameterizedScan parameterize_scan(const Scan& scan, const ParameterizeOptions& options = {});

}  // namespace tbs
