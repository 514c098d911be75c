#pragma once
/// \file
/// Region faces: the spline as a few trimmed tensor-product B-spline surfaces, for CAD.
///
/// The domain is split into smooth regions, bordered by the boundary loops and the chains of
/// feature edges (creases). A crease that ends inside the surface is extended along domain
/// edges to the border of its region, so that every region is smooth inside. Each region
/// becomes one clamped B-spline surface in the domain's own parameters (u, v), over the
/// region's bounding rectangle, fitted by least squares to dense samples of the spline (with
/// a thin-plate term that keeps the part of the rectangle outside the region smooth), and
/// refined by knot insertion until it is within the tolerance everywhere inside the region.
/// A region that needs more poles than the budget is split along a chain of domain edges and
/// each part is fitted again.
///
/// The trims are the domain's own polylines: straight segments in (u, v), so the same
/// parameter line is exact on both faces of a shared edge. Each trim edge has a 3D curve
/// fitted to the spline along it and the measured gap to the faces it bounds.
///
/// A spline over an atlas (with seams) becomes one face per chart, fitted over
/// the chart's domain triangles (its margin included) and trimmed by the chart's outline: each
/// seam is one edge with a polyline trim in each chart it glues, each border a free edge.
/// Creases inside a chart are not split out, and a chart over the pole budget is not split: it
/// is fitted to the whole budget (counted in `unsplittable` if it then misses the tolerance).

#include <tbs/atlas.h>
#include <tbs/spline.h>

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace tbs {

/// A clamped B-spline curve in model space: `knots` is the full knot vector (the first and
/// last values repeated degree + 1 times), poles.size() == knots.size() - degree - 1.
struct BSplineCurve3 {
  int degree = 0;
  std::vector<double> knots;
  std::vector<Point3> poles;
  /// C(t) for t in [knots.front(), knots.back()]. Throws nothing but std::bad_alloc.
  Point3 value(double t) const;
};

/// A clamped tensor-product B-spline surface: knot vectors as BSplineCurve3, poles row by
/// row: pole (i, j) is poles[i + pole_count_u() * j], i along u.
struct BSplineSurface3 {
  int degree_u = 0, degree_v = 0;
  std::vector<double> knots_u, knots_v;
  std::vector<Point3> poles;
  int pole_count_u() const { return static_cast<int>(knots_u.size()) - degree_u - 1; }
  int pole_count_v() const { return static_cast<int>(knots_v.size()) - degree_v - 1; }
  /// S(u, v) and its partial derivatives; (u, v) is clamped to the knot rectangle.
  /// Throws nothing but std::bad_alloc.
  void evaluate(const Point2& uv, Point3& value, Vector3& du, Vector3& dv) const;
  Point3 value(const Point2& uv) const;
};

struct CadRegionOptions {
  /// Largest allowed distance between a face and the spline, relative to the model size (the
  /// diagonal of the control points' bounding box).
  double tolerance = 1e-5;
  /// If > 0, the same in model units; overrides `tolerance`.
  double tolerance_abs = 0;
  /// Largest allowed angle in degrees between the normals of two faces that meet: along every
  /// border shared by two faces (creases, their extensions, splits) each face keeps within
  /// half of it of the spline's normal on its own side, where the spline is regular (its
  /// tangents at least 0.6 degrees apart). Not at the triangles around the end of a crease
  /// inside the surface: the spline's normal is not continuous at that vertex, and no smooth
  /// face can follow it there. Inside a face only the position tolerance applies.
  double angle_tolerance = 1.0;
  /// Degree of the faces in u and in v (2 to 9). Quintic faces are C^4: CAD kernels offset,
  /// thicken and intersect them much faster than cubic ones with as many knots (FreeCAD
  /// thickened the bracket's two faces in 2 s at degree 5, in 85 s at degree 3).
  int degree = 5;
  /// Most poles of one face. A region that needs more is split along domain edges.
  long max_poles = 20'000;
  int threads = 0;  ///< Worker threads, 0 for all cores. The result does not depend on it.
  /// If set, called with a line of progress while the regions are fitted (every 2 s at most,
  /// from a worker thread, one call at a time) and once when they all are.
  std::function<void(const std::string&)> progress = nullptr;
};

/// How a trim edge came about.
enum class RegionEdgeKind {
  Boundary,         ///< On a boundary loop of the domain (outer boundary or hole).
  Crease,           ///< On feature edges: the spline is C^0 across it.
  CreaseExtension,  ///< Extends a crease that ended inside the surface to its region's border.
  Split,            ///< Cuts a region that needed more poles than the budget allowed.
  Seam,             ///< A seam of the atlas: where two charts (or one chart and itself) meet.
};

/// One trim edge between two topological vertices. Over one planar domain: a straight segment
/// in (u, v), made of collinear domain edges, the same trim on both faces it separates. Over an
/// atlas: a seam (a polyline in each of the two charts it glues) or a border of a chart.
struct RegionEdge {
  std::array<int, 2> vertices{};  ///< From, to (indices into CadRegions::vertices).
  /// Domain vertices along the segment, from vertices[0] to vertices[1] (empty over an atlas).
  std::vector<int> chain;
  /// The face on the left of the segment (from -> to in (u, v)) and the one on the right (-1
  /// for a free edge: boundary edges have the domain on their left).
  std::array<int, 2> faces{-1, -1};
  RegionEdgeKind kind = RegionEdgeKind::Boundary;
  /// The spline along the segment, parameterised by the (u, v) arc length from vertices[0]:
  /// t in [0, length]. Over an atlas: the middle of the seam's two sides (their mean arc
  /// length), t at the polylines' points given by `at`.
  BSplineCurve3 curve;
  double length = 0;
  /// Over an atlas: the edge's polyline in the parameters of faces[0] (trims[0], the face on
  /// its left) and of faces[1] (trims[1], the face on its right; empty for a border), both
  /// with the curve parameter `at` at their points (at.front() 0, at.back() length). Empty
  /// for the straight trims of one planar domain.
  std::array<std::vector<Point2>, 2> trims;
  std::vector<double> at;
  /// Largest distance measured between the curve and each face's surface at the same
  /// parameter point (model units).
  double gap = 0;
};

/// An edge in a face's loop, traversed backwards if `reversed`.
struct RegionEdgeUse {
  int edge = -1;
  bool reversed = false;
};

/// One face: a region of domain triangles and its B-spline surface.
struct RegionFace {
  BSplineSurface3 surface;
  std::vector<int> triangles;  ///< The domain triangles of the region, ascending.
  /// Loops with the region on their left: loops[0] is the outer one (counter-clockwise in
  /// (u, v)), the others are holes (clockwise).
  std::vector<std::vector<RegionEdgeUse>> loops;
  double max_position_deviation = 0;  ///< Largest distance face - spline (model units).
  /// Degrees, along the borders this face shares with other faces.
  double max_normal_deviation = 0;
  bool within_tolerance = false;
};

/// The result of make_cad_regions().
struct CadRegions {
  double tolerance = 0;        ///< The absolute position tolerance used.
  double angle_tolerance = 0;  ///< Degrees.
  std::vector<int> vertex_ids;  ///< Domain vertex of each topological vertex (-1 over an atlas).
  /// The parameter point of each topological vertex (over an atlas: in the first chart met).
  std::vector<Point2> vertex_parameters;
  std::vector<Point3> vertices;           ///< F at each topological vertex.
  std::vector<RegionFace> faces;
  std::vector<RegionEdge> edges;
  /// Smooth regions bounded by the boundary and the creases (before splits for the budget).
  int smooth_regions = 0;
  /// Creases that ended inside the surface and were extended to their region's border.
  int crease_extensions = 0;
  /// Creases still ending inside a face (no chain of domain edges reached a border): the
  /// face then approximates the crease, and its deviation says how well.
  int creases_left_inside = 0;
  /// Regions split because they needed more poles than CadRegionOptions::max_poles.
  int budget_splits = 0;
  /// Small regions cut out around a spot where the spline turns much faster than in the rest
  /// of its region (a fold, a cone's tip): the triangles around the spot, as their own face,
  /// so that the knots that spot needs do not run across the whole region.
  int islands = 0;
  /// Regions over the budget that could not be split (a single triangle, or no chain of
  /// domain edges across): they keep the budget's poles and may miss the tolerance.
  int unsplittable = 0;
  /// Faces whose normals, along a shared border, two rounds of refinement did not bring
  /// below 3/4 of what they were: the spline's normal turns faster there than a face can
  /// follow (near the tip of a cone, at a fold). Refinement stops for the normals there;
  /// max_normal_deviation says by how much the limit is missed.
  int normal_stalls = 0;
  size_t poles = 0;                   ///< Poles of all faces.
  double max_position_deviation = 0;  ///< Over all faces (model units).
  double max_normal_deviation = 0;    ///< Degrees, over all shared borders.
  double max_gap = 0;                 ///< Largest edge gap (model units).
  bool within_tolerance = false;      ///< Every face within both tolerances.
  /// The spline has an atlas: one face per chart, trimmed by the chart's outline, with the
  /// seams as edges shared by the faces they glue.
  bool atlas = false;
  /// The atlas is closed: the faces bound a solid.
  bool closed = false;
};

/// Approximates `spline` by region faces (see the file comment).
/// \throw InvalidInput if the spline has no triangles or an option is out of range: no
///   positive tolerance, angle_tolerance outside (0, 90), degree outside 2 to 9, or
///   max_poles below (degree + 1)^2.
CadRegions make_cad_regions(const Spline& spline, const CadRegionOptions& options = {});

/// The same over the atlas of the spline's file (SplineFile::atlas): with seams, one face per
/// chart trimmed by its outline (see the file comment); with none, as above.
/// \throw InvalidInput as above, or if the atlas is malformed (check_atlas_structure());
///   Error if a chart's outline does not close or leaves the domain.
CadRegions make_cad_regions(const Spline& spline, const Atlas& atlas, const CadRegionOptions& options = {});

/// The name of an edge kind, as the reports write it ("boundary", "crease",
/// "crease extension", "split"). Throws nothing.
const char* to_string(RegionEdgeKind kind);

}  // namespace tbs
