// `tbs convert`: a .tbs spline to CAD files, meshes and error maps, through tbs::convert().

#include "commands.h"

#include <tbs/convert.h>
#include <tbs/errors.h>
#include <tbs/io.h>
#include <tbs/scan.h>

#include <cstdio>
#include <filesystem>

namespace tbs::cli {

std::string convert_format(const std::string& output, const std::string& format) {
  return tbs::convert_format(output, format);
}

namespace {

void print_summary(const ConvertOptions& o, const ConvertReport& r) {
  const char* u = r.units.c_str();
  std::printf("%-18s %s\n", "input", o.input.c_str());
  if (r.format == "exr") {
    std::printf("%-18s %s (OpenEXR, %d x %d) and %s (preview)\n", "output", o.output.c_str(), r.map_width,
                r.map_height, r.png.c_str());
    std::printf("%-18s %zu (%zu outside the domain), from %s\n", "points", r.points, r.points_outside,
                r.points_source.c_str());
    std::printf("%-18s %s\n", "measure", o.measure == "closest" ? "closest surface point" : "at the point's parameter");
    std::printf("%-18s %.4g %s\n", "max error", r.errors.max, u);
    std::printf("%-18s %.4g %s\n", "RMS error", r.errors.rms, u);
    std::printf("%-18s %.4g / %.4g / %.4g %s\n", "p50 / p95 / p99", r.errors.p50, r.errors.p95, r.errors.p99, u);
    std::printf("%-18s %.4g .. %.4g %s\n", "signed range", r.errors.min_signed, r.errors.max_signed, u);
    std::printf("%-18s 0 (blue) .. %.4g %s (red)\n", "PNG colour scale", r.color_scale_max, u);
  } else if (r.format == "step" || r.format == "iges") {
    std::printf("%-18s %s (%s, %.3g MB)\n", "output", o.output.c_str(),
                r.format == "step" ? (o.schema == "ap242" ? "STEP AP242" : "STEP AP214") : "IGES 5.3",
                static_cast<double>(r.file_bytes) / 1e6);
    std::printf("%-18s %s\n", "content", r.kind.c_str());
    if (r.faces_form == "regions")
      std::printf("%-18s %zu smooth, %zu crease extension(s), %zu split(s) and %zu island(s) for the pole budget\n",
                  "regions", r.smooth_regions, r.crease_extensions, r.budget_splits, r.islands);
    std::printf("%-18s %zu B-spline faces, %zu shell%s, %zu edges, %zu free edges in %zu loop%s\n", "shape",
                r.cad.faces, r.cad.shells, r.cad.shells == 1 ? "" : "s", r.cad.edges, r.cad.free_edges,
                r.cad.free_loops, r.cad.free_loops == 1 ? "" : "s");
    if (r.cad.solid)
      std::printf("%-18s a closed solid, volume %.6g %s^3\n", "solid", r.cad.volume, u);
    std::printf("%-18s %.3g %s (%s)\n", "CAD tolerance", r.tolerance, u, r.tolerance_source.c_str());
    if (r.deviations_measured) {
      // Each line marks the tolerance it misses.
      std::printf("%-18s %.3g %s (tolerance %.3g)%s\n", "max deviation", r.max_position_deviation, u, r.tolerance,
                  r.max_position_deviation > r.tolerance ? "  NOT WITHIN TOLERANCE" : "");
      std::printf("%-18s %.3g degrees (limit %.3g)%s\n", "max normal dev.", r.max_normal_deviation, r.normal_limit,
                  r.max_normal_deviation > r.normal_limit ? "  NOT WITHIN TOLERANCE" : "");
    }
    std::printf("%-18s %.3g %s\n", "max edge gap", r.cad.max_edge_tolerance, u);
    std::printf("%-18s %s\n", "units", u);
  } else {
    std::printf("%-18s %s (%s)\n", "output", o.output.c_str(), r.kind.c_str());
    std::printf("%-18s %zu triangles, %zu vertices\n", "mesh", r.mesh_faces, r.mesh_vertices);
    if (r.points > 0)
      std::printf("%-18s COLOR_0: error 0 (blue) .. %.4g %s (red); max error %.4g, RMS %.4g %s\n", "colours",
                  r.color_scale_max, u, r.errors.max, r.errors.rms, u);
    std::printf("%-18s %.3g %s%s\n", "max chordal dev.", r.max_chordal_deviation, u,
                o.resolution > 0 ? "" : " (adaptive)");
  }
  std::printf("%-18s %.2f s\n", "time", r.seconds);
}

}  // namespace

int run_convert(const ConvertOptions& o) {
  namespace fs = std::filesystem;
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
  if (!o.report.empty()) {
    if (fs::exists(o.report, ec) && (fs::equivalent(o.input, o.report, ec) || fs::equivalent(o.output, o.report, ec)))
      throw InvalidInput(o.report + ": the report would overwrite the input or the output; choose another path");
    check_output_path(o.report);
  }
  auto say = [&](const std::string& line) {
    if (!o.quiet) std::fprintf(stderr, "tbs convert: %s\n", line.c_str());
  };
  check_output_path(o.output);  // before the work, not after it
  const SplineFile file = read_tbs(o.input);
  const bool triangles = !o.exact && o.faces == "triangles";
  if (triangles && o.max_patches < file.spline.domain().triangle_count())
    throw InvalidInput(o.input + ": the spline has " + std::to_string(file.spline.domain().triangle_count()) +
                       " domain triangles, more than --max-patches " + std::to_string(o.max_patches) +
                       " (at least one patch per triangle); raise --max-patches");

  tbs::ConvertOptions c;
  c.format = format;
  c.faces = o.exact || o.faces == "exact" ? CadFaceForm::Exact
            : triangles                   ? CadFaceForm::Triangles
                                          : CadFaceForm::Regions;
  c.cad_tolerance = o.cad_tolerance;
  c.angle_tolerance = o.angle_tolerance;
  c.face_degree = o.face_degree;
  c.max_poles = o.max_poles;
  c.patch_degree = o.patch_degree;
  c.max_patches = o.max_patches;
  c.triangle_faces = o.triangle_patch == "degenerate" ? TriangleFaces::Collapsed : TriangleFaces::Quads;
  c.schema = o.schema == "ap242" ? StepSchema::AP242 : StepSchema::AP214;
  c.units = o.units;
  c.product_name = o.product_name;
  c.resolution = o.resolution;
  c.chordal_tolerance = o.chordal_tolerance;
  c.color_by_error = o.color_by == "error";
  c.width = o.width;
  c.measure = o.measure == "closest" ? ErrorMeasure::Closest : ErrorMeasure::Parameter;
  c.threads = o.threads;
  c.progress = say;
  const bool needs_points = format == "exr" || c.color_by_error;
  if (needs_points && !o.point_positions.empty()) {
    c.points = o.point_positions;
    c.point_parameters = o.point_uv;
    c.points_source = "the fitted points";
  } else if (needs_points && !o.points.empty()) {
    say("reading " + o.points);
    Scan scan = read_scan(o.points, {.max_points = o.max_points, .limit_name = "--max-points"});
    if (scan.uv.empty())
      throw InvalidInput(o.points + ": these points have no parameters (u, v); " +
                         std::string(format == "exr" ? "an error map" : "--color-by error") +
                         " needs the scan the spline was fitted to");
    c.points = std::move(scan.positions);
    c.point_parameters = std::move(scan.uv);
    c.points_source = o.points;
  }
  const ConvertReport r = convert(file, o.output, c);
  for (const std::string& w : r.warnings) say("warning: " + w);
  if (!o.report.empty()) write_file_atomic(o.report, to_json(r) + "\n");
  print_summary(o, r);
  return kOk;
}

}  // namespace tbs::cli
