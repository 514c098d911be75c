#pragma once
/// \file
/// How far scanned points are from the fitted surface, per point and as images over the
/// parameter domain (an error map, and a geometry image of surface positions and normals).

#include <tbs/spline.h>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace tbs {

/// Summary statistics of point distances (model units). Percentiles are of the unsigned
/// distance, by the nearest-rank rule.
struct ErrorStats {
  size_t count = 0;        ///< Points measured (inside the domain).
  double max = 0;          ///< Largest distance.
  double mean = 0;
  double rms = 0;
  double p50 = 0, p90 = 0, p95 = 0, p99 = 0;
  double min_signed = 0;   ///< Most negative signed distance (below the surface).
  double max_signed = 0;   ///< Most positive signed distance (above the surface).
};

/// How a point's distance to the surface is measured.
enum class ErrorMeasure {
  /// |p - F(u)| at the point's own parameter u: the measure the fitter minimises and its
  /// report's max / RMS error. An upper bound of the distance to the surface.
  Parameter,
  /// |p - F(u*)| at the closest surface point F(u*), found by Gauss-Newton steps from u
  /// within the domain: the geometric distance (to the nearest local foot point), the one to
  /// compare with other surfaces.
  Closest,
};

struct PointErrorOptions {
  ErrorMeasure measure = ErrorMeasure::Parameter;
  int threads = 0;  ///< Worker threads, 0 for all cores. The result does not depend on it.
};

/// Per-point errors of a fit, by the chosen measure.
struct PointErrors {
  ErrorMeasure measure = ErrorMeasure::Parameter;
  std::vector<double> distance;  ///< |p_i - F(u)|; NaN for a parameter outside the domain.
  /// (p_i - F(u)) . N(u): positive on the side the normal points to. NaN outside.
  std::vector<double> signed_distance;
  /// The parameter u measured at: the point's own, or its foot point (ErrorMeasure::Closest).
  std::vector<Point2> foot;
  size_t outside = 0;            ///< Points whose parameter is outside the domain.
  ErrorStats stats;
};

/// Measures every point. \pre points.size() == uv.size().
/// \throw InvalidInput if the sizes differ.
PointErrors point_errors(const Spline& spline, std::span<const Point3> points,
                         std::span<const Point2> uv, const PointErrorOptions& options = {});

/// Statistics of a set of distances (NaNs skipped); signed values may be empty.
/// Throws nothing but std::bad_alloc.
ErrorStats error_stats(std::span<const double> distance, std::span<const double> signed_distance);

struct ErrorMapOptions {
  int width = 512;   ///< Pixels across u.
  int height = 0;    ///< Pixels across v; 0 keeps the domain's aspect ratio.
  int threads = 0;
};

/// What a pixel holds (ErrorMap::mask).
enum class PixelKind : uint8_t {
  Outside = 0,       ///< The pixel centre is outside the domain (or in a hole).
  Measured = 1,      ///< At least one point falls into the pixel.
  Interpolated = 2,  ///< Inside the domain but without points: filled from its neighbours.
};

/// Images over the rectangle of the domain's bounding box. Pixel (x, y) covers
/// u in [u0 + x du, u0 + (x+1) du), v from the top: v in (v1 - (y+1) dv, v1 - y dv], so that
/// row 0 is the largest v (the image convention). Arrays are row-major, width * height
/// entries (3 per pixel for positions and normals).
struct ErrorMap {
  int width = 0, height = 0;
  Box2 domain;                       ///< The rectangle covered.
  std::vector<PixelKind> mask;
  /// Largest |distance| of the pixel's points (interpolated where mask is Interpolated; 0
  /// outside).
  std::vector<float> error;
  /// Signed distance of largest magnitude among the pixel's points (likewise).
  std::vector<float> signed_error;
  std::vector<float> rms;            ///< RMS distance of the pixel's points.
  std::vector<uint32_t> count;       ///< Points in the pixel.
  std::vector<float> position;       ///< F at the pixel centre (0 outside).
  std::vector<float> normal;         ///< Unit normal at the pixel centre (0 outside).
  std::vector<int32_t> triangle;     ///< Domain triangle at the pixel centre, -1 outside.
  ErrorStats stats;                  ///< Of the points (equal to the per-point statistics).
};

/// Rasterises point errors and samples the surface at pixel centres.
/// \pre errors were computed by point_errors() for the same uv.
/// \throw InvalidInput if uv.size() differs from errors.distance.size(), or the image size is
///   out of range (1 to 16384 pixels a side, height after deriving it from the aspect ratio).
ErrorMap make_error_map(const Spline& spline, std::span<const Point2> uv, const PointErrors& errors,
                        const ErrorMapOptions& options = {});

/// The map's `error` at parameter u: the value of the pixel containing u or, where that pixel
/// holds no value (its centre is outside the domain, as for u on the boundary), of the nearest
/// pixel within 3 pixels that does; NaN if there is none. u outside the map's rectangle is
/// clamped to it. Throws nothing; NaN for an empty map.
float error_at(const ErrorMap& map, const Point2& u);

/// The colour scale of error previews: t = 0 blue, then cyan, green, yellow, t = 1 red (8-bit
/// sRGB); t is clamped to [0, 1] (NaN counts as 0). Throws nothing.
std::array<uint8_t, 3> heat_colour(double t);

}  // namespace tbs
