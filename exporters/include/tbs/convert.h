#pragma once
/// \file
/// One conversion path from a spline to every output format: `tbs convert`, `tbs fit --export`
/// and the Python module's `Spline.export` all call convert(). It chooses the format (from the
/// output's extension unless given), the surface form for CAD files, the CAD tolerance and the
/// units, runs the converter and the writer, and reports what it wrote.

#include <tbs/cad_export.h>
#include <tbs/error_map.h>
#include <tbs/io.h>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace tbs {

/// The surface form of a STEP or IGES file.
enum class CadFaceForm {
  Regions,    ///< A few trimmed B-spline faces, one per smooth region (make_cad_regions()).
  Triangles,  ///< Bezier patches per domain triangle, split to the tolerance (make_cad_patches()).
  Exact,      ///< The exact polynomial pieces (extract_bezier()).
};

/// The CAD tolerance, relative to the model size, of splines whose .tbs records no fit
/// tolerance (a spline from another producer): 1e-5 of the model size.
inline constexpr double kDefaultCadTolerance = 1e-5;
/// Without an explicit CAD tolerance, faces keep within this fraction of the fit's own
/// tolerance (the .tbs metadata): the CAD file then stays within 1.05 times the fit's error
/// from the scan.
inline constexpr double kCadToleranceOfFit = 1.0 / 20;

struct ConvertOptions {
  /// step, iges, glb, gltf, obj, ply or exr; empty: from the output's extension (also stp, igs).
  std::string format;
  CadFaceForm faces = CadFaceForm::Regions;
  /// Largest distance between the CAD faces and the spline, relative to the model size (the
  /// diagonal of the control points' bounding box); 0: kCadToleranceOfFit of the fit's
  /// tolerance from the .tbs metadata, or kDefaultCadTolerance without it.
  double cad_tolerance = 0;
  double angle_tolerance = 1.0;  ///< Degrees, see CadRegionOptions and CadPatchOptions.
  int face_degree = 5;           ///< Region faces: degree in u and v (2 to 9).
  long max_poles = 20'000;       ///< Region faces: most poles per face.
  int patch_degree = 0;          ///< Triangle patches: degree, 0 for the spline's + 2.
  long max_patches = 50'000;     ///< Triangle patches: most patches.
  TriangleFaces triangle_faces = TriangleFaces::Quads;  ///< Triangle patches and exact pieces.
  StepSchema schema = StepSchema::AP214;
  std::string units;         ///< CAD files: empty for the .tbs units (mm when it has none).
  std::string product_name;  ///< Empty: the output's file name without extension.
  // Meshes.
  int resolution = 0;  ///< Uniform resolution; 0: adaptive to chordal_tolerance.
  double chordal_tolerance = 1e-4;
  bool color_by_error = false;  ///< glTF: a COLOR_0 heat map of the points' error.
  // Error maps and heat maps: the points (with their parameters); empty: those stored in the
  // .tbs (tbs fit --keep-points).
  std::vector<Point3> points;
  std::vector<Point2> point_parameters;
  std::string points_source;  ///< Where the points came from, for the report.
  int width = 512;
  ErrorMeasure measure = ErrorMeasure::Parameter;
  int threads = 0;  ///< 0 for all cores. The output does not depend on it.
  /// A line of text at each stage. An exception it throws stops the conversion; nothing is
  /// written then.
  std::function<void(const std::string&)> progress;
};

/// What convert() wrote.
struct ConvertReport {
  std::string format;  ///< step, iges, glb, gltf, obj, ply, exr.
  std::string output;
  std::string kind;    ///< One line describing the file's content.
  std::vector<std::string> warnings;
  /// Seconds per stage, in order (e.g. "regions", "shell", "check", "translate", "write").
  std::vector<std::pair<std::string, double>> stage_seconds;
  double seconds = 0;
  uintmax_t file_bytes = 0;
  // CAD files.
  std::string faces_form;  ///< regions, triangles or exact.
  std::string units;
  double tolerance = 0;          ///< The CAD tolerance used (model units).
  std::string tolerance_source;  ///< Where it came from, in words.
  double normal_limit = 0;       ///< Degrees: half the angle tolerance.
  bool deviations_measured = false;  ///< False for exact pieces (exact by construction).
  double max_position_deviation = 0;  ///< Faces - spline (model units).
  double max_normal_deviation = 0;    ///< Degrees.
  bool within_tolerance = true;
  size_t regions = 0, smooth_regions = 0, crease_extensions = 0, creases_left_inside = 0, budget_splits = 0,
         islands = 0, unsplittable = 0, poles = 0;
  size_t patches = 0;  ///< Triangle patches or exact pieces.
  CadExportReport cad;
  // Meshes.
  size_t mesh_faces = 0, mesh_vertices = 0;
  double max_chordal_deviation = 0;
  double color_scale_max = 0;
  // Error maps (and heat maps).
  std::string png;  ///< The preview written beside an error map.
  int map_width = 0, map_height = 0;
  size_t points = 0, points_outside = 0;
  std::string points_source;
  ErrorStats errors;
};

/// The format convert() writes for this output path (step, iges, glb, gltf, obj, ply, exr).
/// \throw InvalidInput if neither `format` nor the extension names one.
std::string convert_format(const std::string& output, const std::string& format = "");

/// The CAD tolerance convert() uses for `file` (model units) and where it comes from.
/// Throws nothing but std::bad_alloc.
std::pair<double, std::string> cad_tolerance(const SplineFile& file, const ConvertOptions& options);

/// Converts `file` to `output` (written atomically).
/// \throw InvalidInput for an unknown format, options out of range, a unit the format cannot
///   write, or no points for an error map; IoError if the file cannot be written; Error if
///   OpenCASCADE fails (see write_step()).
ConvertReport convert(const SplineFile& file, const std::string& output, const ConvertOptions& options = {});

/// The report as a JSON object (the text of `tbs convert --report`). Throws nothing but
/// std::bad_alloc.
std::string to_json(const ConvertReport& report);

}  // namespace tbs
