// `tbs convert`: a .tbs spline to CAD files.

#include "commands.h"

#include <tbs/cad_export.h>
#include <tbs/cad_patches.h>
#include <tbs/errors.h>
#include <tbs/extract.h>
#include <tbs/error_map.h>
#include <tbs/image_export.h>
#include <tbs/io.h>
#include <tbs/scan.h>
#include <tbs/mesh_export.h>
#include <tbs/tessellate.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>

namespace tbs::cli {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

}  // namespace

// The format named by --format or by the output's extension.
std::string convert_format(const std::string& output, const std::string& format) {
  ConvertOptions o;
  o.output = output;
  o.format = format;
  static const std::vector<std::pair<std::string, std::string>> known = {
      {"step", "step"}, {"stp", "step"}, {"iges", "iges"}, {"igs", "iges"}, {"glb", "glb"}, {"gltf", "gltf"}, {"exr", "exr"}, {"obj", "obj"}, {"ply", "ply"}};
  std::string f = lower(o.format);
  if (f.empty()) {
    f = lower(std::filesystem::path(o.output).extension().string());
    if (!f.empty() && f[0] == '.') f.erase(0, 1);
  }
  for (const auto& [name, format] : known)
    if (f == name) return format;
  throw InvalidInput(o.output + ": unknown output format '" + f +
                     "': use an extension .step, .stp, .iges, .igs, .glb, .gltf, .obj, .ply or .exr, or --format");
}

namespace {

// A short description for the file header: the fit's key figures from the .tbs metadata,
// in plain ASCII without quotes (STEP and IGES strings).
std::string describe(const SplineFile& f) {
  std::string text = "tbs " TBS_VERSION " DMS spline, degree " + std::to_string(f.spline.degree()) + ", " +
                     std::to_string(f.spline.domain().triangle_count()) + " domain triangles";
  try {
    const auto meta = nlohmann::json::parse(f.metadata_json);
    if (meta.contains("source")) text += ", fitted to " + meta["source"].get<std::string>();
    if (meta.contains("fit")) {
      const auto& fit = meta["fit"];
      char buf[160];
      std::snprintf(buf, sizeof buf, ", max error %.3g, RMS error %.3g (relative), tolerance %.3g",
                    fit.value("max_error", 0.0), fit.value("rms_error", 0.0), fit.value("tolerance", 0.0));
      text += buf;
    }
  } catch (const std::exception&) {
    // Metadata is free text for other producers: leave it out.
  }
  std::string clean;
  for (char c : text)
    if (c >= 32 && c < 127 && c != '\'' && c != '"') clean += c;
  return clean;
}

// The points an error map or heat map needs: from --points, else those stored in the .tbs.
struct Points {
  std::vector<Point3> positions;
  std::vector<Point2> uv;
  std::string source;
};

Points points_for(const ConvertOptions& o, const SplineFile& file, const std::string& what,
                  const std::function<void(const std::string&)>& say) {
  Points p;
  if (!o.point_positions.empty()) {
    p.positions = o.point_positions;
    p.uv = o.point_uv;
    p.source = "the fitted points";
    return p;
  }
  if (o.points.empty()) {
    if (file.points.empty())
      throw InvalidInput(o.output + ": " + what + " needs the scanned points: add --points SCAN (the scan "
                         "the spline was fitted to, with its parameters u v), or fit with --keep-points");
    p.positions = file.points;
    p.uv = file.point_parameters;
    p.source = o.input + " (stored points)";
    return p;
  }
  say("reading " + o.points);
  Scan scan = read_scan(o.points, {.max_points = o.max_points, .limit_name = "--max-points"});
  if (scan.uv.empty())
    throw InvalidInput(o.points + ": these points have no parameters (u, v); " + what +
                       " needs the scan the spline was fitted to");
  p.positions = std::move(scan.positions);
  p.uv = std::move(scan.uv);
  p.source = o.points;
  return p;
}

// The fit tolerance in model units from the .tbs metadata, 0 if it is not there.
double fit_tolerance(const SplineFile& file) {
  try {
    const auto meta = nlohmann::json::parse(file.metadata_json);
    if (meta.contains("fit")) return meta["fit"].value("tolerance_abs", 0.0);
  } catch (const std::exception&) {
  }
  return 0;
}

struct MeasuredMap {
  PointErrors errors;
  ErrorMap map;
};

MeasuredMap measure_map(const ConvertOptions& o, const Spline& s, const Points& pts,
                        const std::function<void(const std::string&)>& say) {
  const ErrorMeasure measure = o.measure == "closest" ? ErrorMeasure::Closest : ErrorMeasure::Parameter;
  say("measuring " + std::to_string(pts.positions.size()) + " points");
  MeasuredMap r;
  r.errors = point_errors(s, pts.positions, pts.uv, {.measure = measure, .threads = o.threads});
  r.map = make_error_map(s, measure == ErrorMeasure::Closest ? std::span<const Point2>(r.errors.foot)
                                                             : std::span<const Point2>(pts.uv),
                         r.errors, {.width = o.width, .threads = o.threads});
  return r;
}

}  // namespace

int run_convert(const ConvertOptions& o) {
  namespace fs = std::filesystem;
  const auto t0 = std::chrono::steady_clock::now();
  std::error_code ec;
  if (fs::exists(o.output, ec) && fs::equivalent(o.input, o.output, ec))
    throw InvalidInput(o.output + ": the output would overwrite the input; choose another path");
  std::string format;
  try {
    format = convert_format(o.output, o.format);
  } catch (const InvalidInput& e) {
    // A file name tbs cannot write is a usage error, like an unknown option.
    std::fprintf(stderr, "tbs: error: %s\n", e.what());
    return kUsage;
  }
  if (o.color_by == "error" && format != "glb" && format != "gltf") {
    std::fprintf(stderr, "tbs: error: %s: --color-by error needs a glTF output (.glb or .gltf)\n", o.output.c_str());
    return kUsage;
  }
  if (format == "gltf") {
    const std::string bin = fs::path(o.output).replace_extension(".bin").string();
    if ((fs::exists(bin, ec) && fs::equivalent(o.input, bin, ec)) ||
        (!o.points.empty() && fs::exists(bin, ec) && fs::exists(o.points, ec) && fs::equivalent(o.points, bin, ec)))
      throw InvalidInput(bin + ": the glTF buffer file would overwrite an input; choose another output name");
  }
  auto say = [&](const std::string& line) {
    if (!o.quiet) std::fprintf(stderr, "tbs convert: %s\n", line.c_str());
  };
  check_output_path(o.output);  // before the work, not after it
  const SplineFile file = read_tbs(o.input);
  const Spline& s = file.spline;

  if (format == "exr") {
    const Points pts = points_for(o, file, "an error map", say);
    const MeasuredMap mm = measure_map(o, s, pts, say);
    const PointErrors& e = mm.errors;
    const ErrorMap& map = mm.map;
    const ErrorMeasure measure = e.measure;
    const double tolerance = fit_tolerance(file);
    const std::string png = (fs::path(o.output).parent_path() / fs::path(o.output).stem()).string() + ".png";
    write_error_exr(o.output, map, measure, {.units = file.units, .tolerance = tolerance});
    write_error_png(png, map, tolerance > 0 ? std::max(tolerance, e.stats.max) : 0.0);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const char* u = file.units.c_str();
    std::printf("%-18s %s\n", "input", o.input.c_str());
    std::printf("%-18s %s (OpenEXR, %d x %d) and %s (preview)\n", "output", o.output.c_str(), map.width,
                map.height, png.c_str());
    std::printf("%-18s %zu (%zu outside the domain), from %s\n", "points", e.stats.count, e.outside, pts.source.c_str());
    std::printf("%-18s %s\n", "measure", measure == ErrorMeasure::Closest ? "closest surface point" : "at the point's parameter");
    std::printf("%-18s %.4g %s\n", "max error", e.stats.max, u);
    std::printf("%-18s %.4g %s\n", "RMS error", e.stats.rms, u);
    std::printf("%-18s %.4g / %.4g / %.4g %s\n", "p50 / p95 / p99", e.stats.p50, e.stats.p95, e.stats.p99, u);
    std::printf("%-18s %.4g .. %.4g %s\n", "signed range", e.stats.min_signed, e.stats.max_signed, u);
    std::printf("%-18s 0 (blue) .. %.4g %s (red)\n", "PNG colour scale", tolerance > 0 ? std::max(tolerance, e.stats.max) : e.stats.max, u);
    std::printf("%-18s %.2f s\n", "time", seconds);
    return kOk;
  }

  if (format == "glb" || format == "gltf" || format == "obj" || format == "ply") {
    TessellateOptions to;
    to.threads = o.threads;
    if (o.resolution > 0) {
      to.resolution = o.resolution;
    } else {
      to.chordal_tolerance = o.chordal_tolerance;
    }
    say("tessellating");
    const Mesh mesh = tessellate(s, to);
    GltfOptions go;
    go.generator = "tbs " TBS_VERSION;
    go.name = o.product_name.empty() ? fs::path(o.output).stem().string() : o.product_name;
    const bool gltf = format == "glb" || format == "gltf";
    std::optional<MeasuredMap> heat;
    if (o.color_by == "error") {
      const Points pts = points_for(o, file, "--color-by error", say);
      heat = measure_map(o, s, pts, say);
      go.vertex_values.resize(mesh.positions.size());
      for (size_t v = 0; v < mesh.positions.size(); ++v) go.vertex_values[v] = error_at(heat->map, mesh.parameters[v]);
      const double tol = fit_tolerance(file);
      go.color_scale_max = tol > 0 ? std::max(tol, heat->errors.stats.max) : heat->errors.stats.max;
      go.units = file.units;
      go.color_quantity = heat->errors.measure == ErrorMeasure::Closest ? "distance to the closest surface point"
                                                                        : "distance at the point's parameter";
    }
    say("writing " + std::to_string(mesh.faces.size()) + " triangles to " + o.output);
    const MeshExportReport r = gltf ? write_gltf(o.output, mesh, s.domain().bounding_box(), go)
                                    : write_mesh_soup(o.output, mesh);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%-18s %s\n", "input", o.input.c_str());
    const std::string kind = format == "glb"    ? "glTF 2.0, binary"
                             : format == "gltf" ? "glTF 2.0, buffer in " + fs::path(o.output).replace_extension(".bin").filename().string()
                             : format == "obj"  ? "OBJ"
                                                : "PLY, binary";
    std::printf("%-18s %s (%s)\n", "output", o.output.c_str(), kind.c_str());
    std::printf("%-18s %zu triangles, %zu vertices\n", "mesh", r.faces, r.vertices);
    if (heat)
      std::printf("%-18s COLOR_0: error 0 (blue) .. %.4g %s (red); max error %.4g, RMS %.4g %s\n", "colours",
                  go.color_scale_max, file.units.c_str(), heat->errors.stats.max, heat->errors.stats.rms,
                  file.units.c_str());
    std::printf("%-18s %.3g %s%s\n", "max chordal dev.", mesh.max_chordal_deviation,
                file.units.c_str(), o.resolution > 0 ? "" : " (adaptive)");
    std::printf("%-18s %.2f s\n", "time", seconds);
    return kOk;
  }

  CadExportOptions eo;
  eo.units = o.units.empty() ? (file.units == "unitless" ? "mm" : file.units) : o.units;
  if (o.units.empty() && file.units == "unitless")
    say("the spline has no unit; writing it as millimetres (use --units to choose)");
  eo.product_name = o.product_name.empty() ? fs::path(o.output).stem().string() : o.product_name;
  eo.description = describe(file);
  eo.schema = o.schema == "ap242" ? StepSchema::AP242 : StepSchema::AP214;
  eo.faces = o.triangle_patch == "degenerate" ? TriangleFaces::Collapsed : TriangleFaces::Quads;

  TrianglePatchSet patches;
  std::string kind;
  double deviation = 0, normal_deviation = 0, tolerance = 0, normal_limit = 0;
  if (o.exact) {
    say("extracting the exact Bezier pieces");
    const Extraction x = extract_bezier(s, {.threads = o.threads});
    patches = patch_set(x);
    kind = "exact Bezier pieces, degree " + std::to_string(x.degree);
  } else {
    say("building compact CAD patches");
    CadPatchOptions co;
    co.degree = o.patch_degree;
    co.tolerance = o.cad_tolerance;
    co.angle_tolerance = o.angle_tolerance;
    co.max_patches = o.max_patches;
    co.threads = o.threads;
    if (o.max_patches < s.domain().triangle_count())
      throw InvalidInput(o.input + ": the spline has " + std::to_string(s.domain().triangle_count()) +
                         " domain triangles, more than --max-patches " + std::to_string(o.max_patches) +
                         " (at least one patch per triangle); raise --max-patches");
    const CadPatches c = make_cad_patches(s, co);
    patches = patch_set(c);
    kind = "compact patches, degree " + std::to_string(c.degree);
    deviation = c.max_position_deviation;
    normal_deviation = c.max_normal_deviation;
    tolerance = c.tolerance;
    normal_limit = c.angle_tolerance / 2;
    char line[400];
    if (c.max_position_deviation > c.tolerance) {
      std::snprintf(line, sizeof line,
                    "warning: the patches are up to %.3g from the spline, over the CAD tolerance %.3g (%s); "
                    "raise --max-patches or --cad-tolerance, or use --exact",
                    c.max_position_deviation, c.tolerance,
                    c.budget_reached ? "patch budget --max-patches reached" : "deepest split reached");
      say(line);
    }
    if (c.max_normal_deviation > c.angle_tolerance / 2) {
      std::snprintf(line, sizeof line,
                    "warning: patch normals differ from the spline's by up to %.3g degrees (limit %.3g) "
                    "where its normal turns faster than patches can follow (a fold, or a crease that "
                    "ends inside the surface)%s",
                    c.max_normal_deviation, c.angle_tolerance / 2,
                    c.budget_reached ? ", or where the patch budget --max-patches stopped splitting" : "");
      say(line);
    }
  }
  say("writing " + std::to_string(patches.size()) + " patches to " + o.output +
      (patches.size() > 10'000 ? " (many patches take minutes: OpenCASCADE sews every face; a larger --cad-tolerance "
                                 "gives fewer)"
                               : ""));
  eo.progress = say;
  const CadExportReport r = format == "step" ? write_step(o.output, patches, eo) : write_iges(o.output, patches, eo);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::printf("%-18s %s\n", "input", o.input.c_str());
  std::printf("%-18s %s (%s)\n", "output", o.output.c_str(), format == "step" ? (o.schema == "ap242" ? "STEP AP242" : "STEP AP214") : "IGES 5.3");
  std::printf("%-18s %zu %s\n", "patches", patches.size(), kind.c_str());
  std::printf("%-18s %zu B-spline faces, %zu shell%s, %zu free edges\n", "shape", r.faces, r.shells,
              r.shells == 1 ? "" : "s", r.free_edges);
  if (!o.exact) {
    // Each line marks the tolerance it misses.
    std::printf("%-18s %.3g %s (tolerance %.3g)%s\n", "max deviation", deviation, eo.units.c_str(), tolerance,
                deviation > tolerance ? "  NOT WITHIN TOLERANCE" : "");
    std::printf("%-18s %.3g degrees (limit %.3g)%s\n", "max normal dev.", normal_deviation, normal_limit,
                normal_deviation > normal_limit ? "  NOT WITHIN TOLERANCE" : "");
  }
  std::printf("%-18s %s\n", "units", eo.units.c_str());
  std::printf("%-18s %.2f s\n", "time", seconds);
  return kOk;
}

}  // namespace tbs::cli
