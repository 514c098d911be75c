#pragma once
/// \file
/// Error maps and geometry images as OpenEXR files (named float channels, ZIP compression).

#include <tbs/error_map.h>

#include <string>

namespace tbs {

struct ExrOptions {
  std::string units = "unitless";  ///< Length unit of distances and positions.
  double tolerance = 0;            ///< The fit tolerance in model units (0: not written).
};

/// Writes `map` as an OpenEXR image of map.width x map.height pixels, ZIP compressed, with the
/// float channels `error`, `signed_error`, `rms`, `count`, `mask` (0 outside, 1 measured,
/// 2 interpolated), `P.X P.Y P.Z`, `N.X N.Y N.Z` and `triangle` (-1 outside), and the
/// attributes `tbs.domain` (Box2f: the parameter rectangle), `tbs.units`, `tbs.measure`
/// ("parameter" or "closest"), `tbs.tolerance`, `tbs.max`, `tbs.rms`, `tbs.p95`,
/// `tbs.points`. The file is written atomically.
/// \throw InvalidInput for an empty map or one whose mask size is not width x height; IoError
///   if the file cannot be written (any OpenEXR failure is reported as IoError).
void write_error_exr(const std::string& path, const ErrorMap& map, ErrorMeasure measure,
                     const ExrOptions& options = {});

/// Writes a PNG preview of the error map for a person to look at: each pixel's largest error
/// on a colour scale from blue (0) through green and yellow to red (`scale_max`, or the map's
/// largest error if 0), pixels outside the domain transparent, interpolated pixels lighter,
/// and a 12-pixel colour bar from 0 to scale_max along the bottom. The file is written
/// atomically. \throw InvalidInput for an empty map or one whose mask size is not
/// width x height; IoError if the PNG cannot be encoded or the file cannot be written.
void write_error_png(const std::string& path, const ErrorMap& map, double scale_max = 0);

}  // namespace tbs
