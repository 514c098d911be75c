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
  auto say = [&](const std::string& line) {
    if (!o.quiet) std::fprintf(stderr, "tbs convert: %s\n", line.c_str());
  };
  const SplineFile file = read_tbs(o.input);
  const Spline& s = file.spline;

  if (format == "exr") {
    if (o.points.empty())
      throw InvalidInput(o.output + ": an error map needs the scanned points: add --points SCAN (the scan "
                         "the spline was fitted to, with its parameters u v)");
    say("reading " + o.points);
    const Scan scan = read_scan(o.points);
    if (scan.uv.empty())
      throw InvalidInput(o.points + ": these points have no parameters (u, v); an error map needs the "
                         "scan the spline was fitted to");
    const ErrorMeasure measure = o.measure == "closest" ? ErrorMeasure::Closest : ErrorMeasure::Parameter;
    say("measuring " + std::to_string(scan.positions.size()) + " points");
    const PointErrors e = point_errors(s, scan.positions, scan.uv, {.measure = measure, .threads = o.threads});
    const ErrorMap map = make_error_map(s, measure == ErrorMeasure::Closest ? std::span<const Point2>(e.foot)
                                                                           : std::span<const Point2>(scan.uv),
                                       e, {.width = o.width, .threads = o.threads});
    double tolerance = 0;
    try {
      const auto meta = nlohmann::json::parse(file.metadata_json);
      if (meta.contains("fit")) tolerance = meta["fit"].value("tolerance_abs", 0.0);
    } catch (const std::exception&) {
    }
    const std::string png = (fs::path(o.output).parent_path() / fs::path(o.output).stem()).string() + ".png";
    write_error_exr(o.output, map, measure, {.units = file.units, .tolerance = tolerance});
    write_error_png(png, map, tolerance > 0 ? std::max(tolerance, e.stats.max) : 0.0);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const char* u = file.units.c_str();
    std::printf("%-18s %s\n", "input", o.input.c_str());
    std::printf("%-18s %s (OpenEXR, %d x %d) and %s (preview)\n", "output", o.output.c_str(), map.width,
                map.height, png.c_str());
    std::printf("%-18s %zu (%zu outside the domain)\n", "points", e.stats.count, e.outside);
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
    say("writing " + std::to_string(mesh.faces.size()) + " triangles to " + o.output);
    const bool gltf = format == "glb" || format == "gltf";
    const MeshExportReport r = gltf ? write_gltf(o.output, mesh, s.domain().bounding_box(), go)
                                    : write_mesh_soup(o.output, mesh);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%-18s %s\n", "input", o.input.c_str());
    const char* kind = format == "glb" ? "glTF 2.0, binary" : format == "gltf" ? "glTF 2.0" : format == "obj" ? "OBJ" : "PLY, binary";
    std::printf("%-18s %s (%s)\n", "output", o.output.c_str(), kind);
    std::printf("%-18s %zu triangles, %zu vertices\n", "mesh", r.faces, r.vertices);
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
  double deviation = 0, normal_deviation = 0, tolerance = 0;
  bool within = true;
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
    co.threads = o.threads;
    const CadPatches c = make_cad_patches(s, co);
    patches = patch_set(c);
    kind = "compact patches, degree " + std::to_string(c.degree);
    deviation = c.max_position_deviation;
    normal_deviation = c.max_normal_deviation;
    tolerance = c.tolerance;
    within = c.within_tolerance;
    if (!within)
      say("warning: the patches are not within the CAD tolerance everywhere (deepest split "
          "reached); see 'max deviation' below, or use --exact");
  }
  say("writing " + std::to_string(patches.size()) + " patches to " + o.output);
  const CadExportReport r = format == "step" ? write_step(o.output, patches, eo) : write_iges(o.output, patches, eo);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::printf("%-18s %s\n", "input", o.input.c_str());
  std::printf("%-18s %s (%s)\n", "output", o.output.c_str(), format == "step" ? (o.schema == "ap242" ? "STEP AP242" : "STEP AP214") : "IGES 5.3");
  std::printf("%-18s %zu %s\n", "patches", patches.size(), kind.c_str());
  std::printf("%-18s %zu B-spline faces, %zu shell%s, %zu free edges\n", "shape", r.faces, r.shells,
              r.shells == 1 ? "" : "s", r.free_edges);
  if (!o.exact) {
    std::printf("%-18s %.3g %s (tolerance %.3g)%s\n", "max deviation", deviation, eo.units.c_str(), tolerance,
                within ? "" : "  NOT WITHIN TOLERANCE");
    std::printf("%-18s %.3g degrees\n", "max normal dev.", normal_deviation);
  }
  std::printf("%-18s %s\n", "units", eo.units.c_str());
  std::printf("%-18s %.2f s\n", "time", seconds);
  return kOk;
}

}  // namespace tbs::cli
