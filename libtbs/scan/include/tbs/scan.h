#pragma once
/// \file
/// Scans (the input of fitting): reading them from PLY, OBJ, OFF, STL and XYZ files, and
/// estimating their normals.

#include <tbs/atlas.h>
#include <tbs/types.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace tbs {

/// A scan: points in model space, optionally with normals, parameters (u, v) and triangles.
struct Scan {
  std::vector<Point3> positions;
  std::vector<Vector3> normals;               ///< empty, or one per position (unit length)
  std::vector<Point2> uv;                     ///< empty, or one per position
  std::vector<std::array<int, 3>> triangles;  ///< empty for bare points; indices into positions
  /// Empty, or one flag per position: 1 marks a guide, a point that tbs added (a subdivided
  /// coarse mesh's new points, on a smooth surface through its vertices). Guides hold the
  /// surface between the measured points with a tenth of their weight; the error and the
  /// tolerance are measured at the other points only.
  std::vector<std::uint8_t> guide;
  /// Empty, or the seams that glue the parameters' charts (components of the uv plane) into one
  /// surface: parameterize_scan() cuts closed surfaces, handles and surfaces that one
  /// flattening would stretch into charts; the fit ties the spline across the seams.
  Atlas atlas;
  std::string source;                         ///< the path it was read from
  /// Faces the reader left out: polygons with fewer than three corners, and triangles (of a
  /// polygon's fan) with a repeated corner. (In OBJ, tinyobjloader drops faces with fewer than
  /// three corners itself: they are not counted.)
  std::size_t degenerate_faces = 0;
  bool has_normals() const { return !normals.empty(); }
  bool has_uv() const { return !uv.empty(); }
  bool has_faces() const { return !triangles.empty(); }
};

struct ScanReadOptions {
  size_t max_points = 50'000'000;  ///< larger inputs are refused before allocating
  /// How the error message names the limit, so that it says what to change.
  std::string limit_name = "ScanReadOptions::max_points";
};

/// Reads PLY (ASCII/binary), OBJ, OFF, STL and XYZ/TXT files, chosen by the extension
/// (case-insensitive: .ply .obj .off .stl .xyz .txt).
///
/// - PLY: vertex properties x y z (any numeric type), optional nx ny nz, optional parameters
///   named u v, s t or texture_u texture_v; optional faces (`vertex_indices` or `vertex_index`
///   integer lists). Other elements and properties are ignored.
/// - OBJ: `v`, `vt`, `vn`, `f`. One point per distinct (v, vt, vn) triple used by the faces, so
///   a UV seam gives two points at the same position; `v` lines used by no face become bare
///   points, which is an error when the faces carry vt or vn (those points would lack them), as
///   is a face corner without vt (vn) when other corners have one. Without faces, `vt`/`vn`
///   lines are matched to `v` lines by order when their counts equal the `v` count (and ignored
///   otherwise).
/// - OFF: ASCII OFF, NOFF (normals), 4OFF; binary OFF and the C/ST variants are refused (CGAL
///   5.5's reader gets them wrong).
/// - STL: ASCII or binary; identical corner positions are merged.
/// - XYZ/TXT: one point per line with 3, 5, 6 or 8 numbers: `x y z`, `x y z u v`,
///   `x y z nx ny nz` or `x y z u v nx ny nz`; empty lines and lines starting with `#` skipped.
///
/// Polygons are fan-triangulated; triangles with a repeated corner and polygons with fewer
/// than three corners are dropped and counted in Scan::degenerate_faces. Normals are
/// normalised. Elements are numbered as their format numbers them in messages: from 0 in PLY,
/// OFF and STL, from 1 in OBJ (`v 3`, `face 2`), by line in XYZ.
///
/// \throw IoError if the file is missing, a directory or unreadable.
/// \throw InvalidInput `<path>:<line or element>: <problem>; <what to do>` when the file is
///   empty, has an unknown extension, is malformed or truncated, has no points or more than
///   `options.max_points` (checked against header counts before allocating), a coordinate,
///   parameter or normal that is NaN, infinite or larger than 1e30 in magnitude, a zero-length
///   normal, or a face index that is negative or out of range. A failure inside a format
///   library, running out of memory included, is reported as InvalidInput as well.
Scan read_scan(const std::string& path, const ScanReadOptions& options = {});

/// Estimates unit normals: CGAL jet fitting (a degree-2 height function, CGAL's
/// Monge_via_jet_fitting as in CGAL::jet_estimate_normals) on the k nearest neighbours of each
/// point (the point itself included; all points when there are fewer than k). Neighbours are
/// distinct positions: copies of a position (UV seams) are fitted once and share the normal,
/// each copy oriented on its own. Points are processed in parallel, each independently, so the
/// result does not depend on the number of threads.
///
/// Orientation, in this order of preference:
/// - uv and triangles given: n . r > 0 where r is the sum, over the triangles at the point, of
///   the face normal times the sign of the triangle's signed area in uv, i.e. the direction of
///   P_u x P_v of the triangle's affine map (safe across UV seams, where 3D neighbours have
///   unrelated parameters);
/// - uv given (or no triangle at the point): n . (P_u x P_v) > 0 with P_u, P_v from the
///   least-squares affine fit of position against uv over the same k neighbours;
/// - no uv, triangles given: n agrees with the area-weighted normal of the faces at the point
///   (their winding);
/// - otherwise (or when the above is degenerate): n . z > 0 where z is the PCA axis of least
///   variance of all positions, signed so that its largest component is positive (for a scan
///   lying roughly in a horizontal plane that is +Z).
///
/// `progress`, when given, is called from the calling thread about every 2 seconds with the
/// fraction of the points done (a million points take about 10 s on one core); whatever it
/// throws (a cancellation, say) stops the estimate and passes through.
///
/// \pre positions finite; uv empty or one per position; triangle indices in [0, #positions).
/// \throw InvalidInput if a precondition fails, k < 6 (a degree-2 jet has 6 coefficients),
///   there are fewer than 6 distinct positions, or the neighbourhood of a point is degenerate (e.g.
///   all its neighbours coincide or are collinear).
std::vector<Vector3> estimate_normals(std::span<const Point3> positions, std::span<const Point2> uv,
                                      std::span<const std::array<int, 3>> triangles, int k = 18,
                                      const std::function<void(double)>& progress = {});

}  // namespace tbs
