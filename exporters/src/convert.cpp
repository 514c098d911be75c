// convert(): the one path from a spline to every output format (convert.h).

#include <tbs/cad_patches.h>
#include <tbs/cad_regions.h>
#include <tbs/convert.h>
#include <tbs/errors.h>
#include <tbs/extract.h>
#include <tbs/image_export.h>
#include <tbs/mesh_export.h>
#include <tbs/tessellate.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <typeinfo>

namespace tbs {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string format_number(const char* fmt, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, x);
  return buf;
}

// A short description for the CAD file header: the fit's key figures from the .tbs metadata,
// in plain ASCII without quotes (STEP and IGES strings).
std::string describe(const SplineFile& f) {
  std::string text = "tbs " TBS_VERSION " DMS spline, degree " + std::to_string(f.spline.degree()) + ", " +
                     std::to_string(f.spline.domain().triangle_count()) + " domain triangles";
  try {
    const auto meta = nlohmann::json::parse(f.metadata_json);
    if (meta.contains("source") && meta["source"].is_string()) text += ", fitted to " + meta["source"].get<std::string>();
    if (meta.contains("fit") && meta["fit"].is_object()) {
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

// The fit tolerance in model units from the .tbs metadata, 0 if it is not there.
double fit_tolerance(const SplineFile& file) {
  try {
    const auto meta = nlohmann::json::parse(file.metadata_json);
    if (meta.contains("fit") && meta["fit"].is_object()) {
      const double t = meta["fit"].value("tolerance_abs", 0.0);
      return std::isfinite(t) && t > 0 ? t : 0.0;
    }
  } catch (const std::exception&) {
  }
  return 0;
}

double model_size(const Spline& s) {
  Box3 box;
  for (const Point3& c : s.control_points()) box.extend(c);
  return box.empty() ? 1.0 : std::max((box.max - box.min).norm(), 1e-300);
}

struct Points {
  std::span<const Point3> positions;
  std::span<const Point2> uv;
  std::string source;
};

Points points_for(const SplineFile& file, const std::string& output, const ConvertOptions& o, const char* what) {
  if (!o.points.empty()) {
    if (o.points.size() != o.point_parameters.size())
      throw InvalidInput(output + ": " + what + ": the points and their parameters differ in number");
    return {o.points, o.point_parameters, o.points_source.empty() ? "the given points" : o.points_source};
  }
  if (file.points.empty())
    throw InvalidInput(output + ": " + what + " needs the scanned points: add --points SCAN (the scan "
                       "the spline was fitted to, with its parameters u v), or fit with --keep-points");
  return {file.points, file.point_parameters, "the points stored in the .tbs"};
}

struct MeasuredMap {
  PointErrors errors;
  ErrorMap map;
};

MeasuredMap measure_map(const Spline& s, const Points& pts, const ConvertOptions& o) {
  if (o.progress) o.progress("measuring " + std::to_string(pts.positions.size()) + " points");
  MeasuredMap r;
  r.errors = point_errors(s, pts.positions, pts.uv, {.measure = o.measure, .threads = o.threads});
  r.map = make_error_map(s, o.measure == ErrorMeasure::Closest ? std::span<const Point2>(r.errors.foot) : pts.uv,
                         r.errors, {.width = o.width, .threads = o.threads});
  return r;
}

uintmax_t size_of(const std::string& path) {
  std::error_code ec;
  const uintmax_t n = std::filesystem::file_size(path, ec);
  return ec ? 0 : n;
}

void convert_exr(const SplineFile& file, const std::string& output, const ConvertOptions& o, ConvertReport& r) {
  namespace fs = std::filesystem;
  const Points pts = points_for(file, output, o, "an error map");
  auto t0 = Clock::now();
  const MeasuredMap mm = measure_map(file.spline, pts, o);
  r.stage_seconds.emplace_back("measure", since(t0));
  const double tolerance = fit_tolerance(file);
  r.png = (fs::path(output).parent_path() / fs::path(output).stem()).string() + ".png";
  t0 = Clock::now();
  write_error_exr(output, mm.map, o.measure, {.units = file.units, .tolerance = tolerance});
  write_error_png(r.png, mm.map, tolerance > 0 ? std::max(tolerance, mm.errors.stats.max) : 0.0);
  r.stage_seconds.emplace_back("write", since(t0));
  r.kind = "OpenEXR error map";
  r.map_width = mm.map.width;
  r.map_height = mm.map.height;
  r.points = mm.errors.stats.count;
  r.points_outside = mm.errors.outside;
  r.points_source = pts.source;
  r.errors = mm.errors.stats;
  r.color_scale_max = tolerance > 0 ? std::max(tolerance, mm.errors.stats.max) : mm.errors.stats.max;
  r.units = file.units;
}

void convert_mesh(const SplineFile& file, const std::string& output, const ConvertOptions& o, ConvertReport& r) {
  namespace fs = std::filesystem;
  const Spline& s = file.spline;
  TessellateOptions to;
  to.threads = o.threads;
  if (o.resolution > 0) {
    to.resolution = o.resolution;
  } else {
    to.chordal_tolerance = o.chordal_tolerance;
  }
  const bool gltf = r.format == "glb" || r.format == "gltf";
  if (o.color_by_error && !gltf) throw InvalidInput(output + ": a heat map of the error needs a glTF output (.glb or .gltf)");
  if (o.progress) o.progress("tessellating");
  auto t0 = Clock::now();
  const Mesh mesh = tessellate(s, to);
  r.stage_seconds.emplace_back("tessellate", since(t0));
  GltfOptions go;
  go.generator = "tbs " TBS_VERSION;
  go.name = o.product_name.empty() ? fs::path(output).stem().string() : o.product_name;
  if (o.color_by_error) {
    const Points pts = points_for(file, output, o, "--color-by error");
    t0 = Clock::now();
    const MeasuredMap heat = measure_map(s, pts, o);
    r.stage_seconds.emplace_back("measure", since(t0));
    go.vertex_values.resize(mesh.positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v) go.vertex_values[v] = error_at(heat.map, mesh.parameters[v]);
    const double tol = fit_tolerance(file);
    go.color_scale_max = tol > 0 ? std::max(tol, heat.errors.stats.max) : heat.errors.stats.max;
    go.units = file.units;
    go.color_quantity = o.measure == ErrorMeasure::Closest ? "distance to the closest surface point"
                                                           : "distance at the point's parameter";
    r.color_scale_max = go.color_scale_max;
    r.errors = heat.errors.stats;
    r.points = heat.errors.stats.count;
    r.points_outside = heat.errors.outside;
    r.points_source = pts.source;
  }
  if (o.progress) o.progress("writing " + std::to_string(mesh.faces.size()) + " triangles to " + output);
  t0 = Clock::now();
  const MeshExportReport m = gltf ? write_gltf(output, mesh, s.domain().bounding_box(), go) : write_mesh_soup(output, mesh);
  r.stage_seconds.emplace_back("write", since(t0));
  r.kind = r.format == "glb"    ? "glTF 2.0, binary"
           : r.format == "gltf" ? "glTF 2.0, buffer in " + fs::path(output).replace_extension(".bin").filename().string()
           : r.format == "obj"  ? "OBJ"
                                : "PLY, binary";
  r.mesh_faces = m.faces;
  r.mesh_vertices = m.vertices;
  r.max_chordal_deviation = mesh.max_chordal_deviation;
  r.units = file.units;
}

void convert_cad(const SplineFile& file, const std::string& output, const ConvertOptions& o, ConvertReport& r) {
  namespace fs = std::filesystem;
  const Spline& s = file.spline;
  CadExportOptions eo;
  eo.units = o.units.empty() ? (file.units == "unitless" ? "mm" : file.units) : o.units;
  if (o.units.empty() && file.units == "unitless")
    r.warnings.push_back("the spline has no unit; writing it as millimetres (use --units to choose)");
  eo.product_name = o.product_name.empty() ? fs::path(output).stem().string() : o.product_name;
  eo.description = describe(file);
  eo.schema = o.schema;
  eo.faces = o.triangle_faces;
  eo.progress = o.progress;
  r.units = eo.units;
  const auto [tol, source] = cad_tolerance(file, o);
  r.tolerance = tol;
  r.tolerance_source = source;
  r.normal_limit = o.angle_tolerance / 2;
  const bool step = r.format == "step";
  auto write = [&](const auto& source_form) {
    return step ? write_step(output, source_form, eo) : write_iges(output, source_form, eo);
  };
  char line[400];
  const auto t0 = Clock::now();
  if (o.faces == CadFaceForm::Regions) {
    r.faces_form = "regions";
    if (o.progress) o.progress("fitting region faces (CAD tolerance " + format_number("%.3g", tol) + " " + eo.units + ")");
    CadRegionOptions co;
    co.tolerance_abs = tol;
    co.angle_tolerance = o.angle_tolerance;
    co.degree = o.face_degree;
    co.max_poles = o.max_poles;
    co.threads = o.threads;
    co.progress = o.progress;
    // The report, the warnings and the file of region faces c.
    auto finish_regions = [&](const CadRegions& c) {
      r.regions = c.faces.size();
      r.smooth_regions = static_cast<size_t>(c.smooth_regions);
      r.crease_extensions = static_cast<size_t>(c.crease_extensions);
      r.creases_left_inside = static_cast<size_t>(c.creases_left_inside);
      r.budget_splits = static_cast<size_t>(c.budget_splits);
      r.islands = static_cast<size_t>(c.islands);
      r.unsplittable = static_cast<size_t>(c.unsplittable);
      r.poles = c.poles;
      r.deviations_measured = true;
      r.max_position_deviation = c.max_position_deviation;
      r.max_normal_deviation = c.max_normal_deviation;
      r.within_tolerance = c.within_tolerance;
      r.kind = std::to_string(c.faces.size()) + " region faces, B-spline degree " + std::to_string(o.face_degree) + ", " +
               std::to_string(c.poles) + " poles";
      if (c.crease_extensions > 0)
        r.warnings.push_back(std::to_string(c.crease_extensions) +
                             " crease(s) ended inside the surface: each was extended along domain edges to its "
                             "region's border (an edge between two faces where the surface is smooth)");
      if (c.creases_left_inside > 0)
        r.warnings.push_back(std::to_string(c.creases_left_inside) +
                             " crease(s) end inside a face (no chain of domain edges reached a border): the face "
                             "approximates the crease");
      if (c.normal_stalls > 0) {
        std::snprintf(line, sizeof line,
                      "the normals of %d face(s) differ from the spline's by up to %.3g degrees (limit %.3g) along "
                      "shared borders where the spline's normal turns faster than a face can follow (a cone's tip, a "
                      "fold)",
                      c.normal_stalls, c.max_normal_deviation, o.angle_tolerance / 2);
        r.warnings.push_back(line);
      }
      if (c.unsplittable > 0) {
        std::snprintf(line, sizeof line,
                      "%d region(s) needed more than --max-poles %ld poles and could not be split further; they "
                      "may miss the tolerance (raise --max-poles or --cad-tolerance, or use --faces triangles)",
                      c.unsplittable, o.max_poles);
        r.warnings.push_back(line);
      }
      r.cad = write(c);
    };
    // Over an atlas: one face per chart, trimmed by its outline, the seams shared edges. Where
    // that fails (a fit that did not converge may leave a chart's outline outside its domain,
    // or give faces OpenCASCADE refuses), each chart's domain is written as region faces of its
    // own, as separate sheets, with a warning: a file the user can still look at.
    const size_t stages = r.stage_seconds.size();
    bool joined = false;
    if (!file.atlas.empty()) {
      try {
        const CadRegions c = make_cad_regions(s, file.atlas, co);
        r.stage_seconds.emplace_back("regions", since(t0));
        finish_regions(c);
        joined = true;
      } catch (const Error& e) {
        if (typeid(e) != typeid(Error)) throw;
        r.warnings.push_back(std::string("the atlas's charts could not be joined along their seams (") + e.what() +
                             "); each chart's domain is written as faces of its own, not as one closed shape");
        r.stage_seconds.resize(stages);
        if (o.progress) o.progress("joining the charts failed; writing each chart's domain on its own");
      }
    }
    if (!joined) {
      const CadRegions c = make_cad_regions(s, Atlas{}, co);
      r.stage_seconds.emplace_back("regions", since(t0));
      finish_regions(c);
    }
  } else if (o.faces == CadFaceForm::Triangles) {
    r.faces_form = "triangles";
    if (o.max_patches < s.domain().triangle_count())
      throw InvalidInput(output + ": the spline has " + std::to_string(s.domain().triangle_count()) +
                         " domain triangles, more than --max-patches " + std::to_string(o.max_patches) +
                         " (at least one patch per triangle); raise --max-patches");
    if (o.progress) o.progress("building triangle patches (CAD tolerance " + format_number("%.3g", tol) + " " + eo.units + ")");
    CadPatchOptions co;
    co.degree = o.patch_degree;
    co.tolerance_abs = tol;
    co.angle_tolerance = o.angle_tolerance;
    co.max_patches = o.max_patches;
    co.threads = o.threads;
    const CadPatches c = make_cad_patches(s, co);
    r.stage_seconds.emplace_back("patches", since(t0));
    r.patches = c.patches.size();
    r.deviations_measured = true;
    r.max_position_deviation = c.max_position_deviation;
    r.max_normal_deviation = c.max_normal_deviation;
    r.within_tolerance = c.within_tolerance;
    r.kind = std::to_string(c.patches.size()) + " triangle patches, degree " + std::to_string(c.degree);
    if (c.max_position_deviation > c.tolerance) {
      std::snprintf(line, sizeof line,
                    "the patches are up to %.3g from the spline, over the CAD tolerance %.3g (%s); "
                    "raise --max-patches or --cad-tolerance, or use --exact",
                    c.max_position_deviation, c.tolerance,
                    c.budget_reached ? "patch budget --max-patches reached" : "deepest split reached");
      r.warnings.push_back(line);
    }
    if (c.max_normal_deviation > c.angle_tolerance / 2) {
      std::snprintf(line, sizeof line,
                    "patch normals differ from the spline's by up to %.3g degrees (limit %.3g) where its normal "
                    "turns faster than patches can follow (a fold, or a crease that ends inside the surface)%s",
                    c.max_normal_deviation, c.angle_tolerance / 2,
                    c.budget_reached ? ", or where the patch budget --max-patches stopped splitting" : "");
      r.warnings.push_back(line);
    }
    r.cad = write(c);
  } else {
    r.faces_form = "exact";
    if (o.progress) o.progress("extracting the exact Bezier pieces");
    const Extraction x = extract_bezier(s, {.threads = o.threads});
    r.stage_seconds.emplace_back("extract", since(t0));
    r.patches = x.pieces.size();
    r.kind = std::to_string(x.pieces.size()) + " exact Bezier pieces, degree " + std::to_string(x.degree);
    r.cad = write(x);
  }
  if (r.deviations_measured && !r.within_tolerance && o.faces == CadFaceForm::Regions &&
      r.max_position_deviation > r.tolerance) {
    std::snprintf(line, sizeof line, "the faces are up to %.3g from the spline (tolerance %.3g) and their normals up to %.3g degrees (limit %.3g)",
                  r.max_position_deviation, r.tolerance, r.max_normal_deviation, r.normal_limit);
    r.warnings.push_back(line);
  }
  r.stage_seconds.emplace_back("shell", r.cad.build_seconds);
  r.stage_seconds.emplace_back("check", r.cad.check_seconds);
  if (r.cad.solid) r.stage_seconds.emplace_back("volume", r.cad.volume_seconds);
  r.stage_seconds.emplace_back("translate", r.cad.translate_seconds);
  r.stage_seconds.emplace_back("write", r.cad.write_seconds);
}

}  // namespace

std::string convert_format(const std::string& output, const std::string& format) {
  static const std::vector<std::pair<std::string, std::string>> known = {
      {"step", "step"}, {"stp", "step"}, {"iges", "iges"}, {"igs", "iges"}, {"glb", "glb"},
      {"gltf", "gltf"}, {"exr", "exr"},  {"obj", "obj"},   {"ply", "ply"}};
  std::string f = lower(format);
  if (f.empty()) {
    f = lower(std::filesystem::path(output).extension().string());
    if (!f.empty() && f[0] == '.') f.erase(0, 1);
  }
  for (const auto& [name, fmt] : known)
    if (f == name) return fmt;
  throw InvalidInput(output + ": unknown output format '" + f +
                     "': use an extension .step, .stp, .iges, .igs, .glb, .gltf, .obj, .ply or .exr, or --format");
}

std::pair<double, std::string> cad_tolerance(const SplineFile& file, const ConvertOptions& o) {
  const double size = model_size(file.spline);
  const std::string unit = file.units;
  if (o.cad_tolerance > 0)
    return {o.cad_tolerance * size, "--cad-tolerance " + format_number("%.3g", o.cad_tolerance) + " of the model size " +
                                        format_number("%.4g", size) + " " + unit};
  const double fit = fit_tolerance(file);
  if (fit > 0)
    return {kCadToleranceOfFit * fit, "1/20 of the fit tolerance " + format_number("%.4g", fit) + " " + unit +
                                          " (.tbs metadata)"};
  return {kDefaultCadTolerance * size, "the default " + format_number("%.3g", kDefaultCadTolerance) +
                                           " of the model size " + format_number("%.4g", size) + " " + unit +
                                           " (the .tbs records no fit tolerance)"};
}

ConvertReport convert(const SplineFile& file, const std::string& output, const ConvertOptions& o) {
  const auto t0 = Clock::now();
  ConvertReport r;
  r.format = convert_format(output, o.format);
  r.output = output;
  if (!(o.angle_tolerance > 0 && o.angle_tolerance < 90))
    throw InvalidInput(output + ": the angle tolerance must be between 0 and 90 degrees");
  if (o.cad_tolerance < 0 || !std::isfinite(o.cad_tolerance))
    throw InvalidInput(output + ": the CAD tolerance must be positive");
  if (o.color_by_error && r.format != "glb" && r.format != "gltf")
    throw InvalidInput(output + ": --color-by error needs a glTF output (.glb or .gltf)");
  if (r.format == "exr") {
    convert_exr(file, output, o, r);
  } else if (r.format == "step" || r.format == "iges") {
    convert_cad(file, output, o, r);
  } else {
    convert_mesh(file, output, o, r);
  }
  r.file_bytes = size_of(output);
  r.seconds = since(t0);
  return r;
}

std::string to_json(const ConvertReport& r) {
  using nlohmann::json;
  json j;
  j["output"] = valid_utf8(r.output);
  j["format"] = r.format;
  j["content"] = r.kind;
  j["file_bytes"] = r.file_bytes;
  j["seconds"] = r.seconds;
  json stages = json::object();
  for (const auto& [name, s] : r.stage_seconds) stages[name] = s;
  j["stage_seconds"] = stages;
  j["warnings"] = r.warnings;
  if (r.format == "step" || r.format == "iges") {
    j["faces_form"] = r.faces_form;
    j["units"] = r.units;
    j["cad_tolerance"] = r.tolerance;
    j["cad_tolerance_source"] = r.tolerance_source;
    j["faces"] = r.cad.faces;
    j["shells"] = r.cad.shells;
    j["edges"] = r.cad.edges;
    j["free_edges"] = r.cad.free_edges;
    j["free_loops"] = r.cad.free_loops;
    j["solid"] = r.cad.solid;
    if (r.cad.solid) j["volume"] = r.cad.volume;
    j["max_edge_tolerance"] = r.cad.max_edge_tolerance;
    if (r.faces_form == "regions") {
      j["regions"] = {{"faces", r.regions},
                      {"smooth_regions", r.smooth_regions},
                      {"crease_extensions", r.crease_extensions},
                      {"creases_left_inside", r.creases_left_inside},
                      {"budget_splits", r.budget_splits},
                      {"islands", r.islands},
                      {"unsplittable", r.unsplittable},
                      {"poles", r.poles}};
    } else {
      j["patches"] = r.patches;
    }
    if (r.deviations_measured) {
      j["max_position_deviation"] = r.max_position_deviation;
      j["max_normal_deviation_degrees"] = r.max_normal_deviation;
      j["normal_limit_degrees"] = r.normal_limit;
      j["within_tolerance"] = r.within_tolerance;
    }
  } else if (r.format == "exr") {
    j["png"] = valid_utf8(r.png);
    j["width"] = r.map_width;
    j["height"] = r.map_height;
  } else {
    j["triangles"] = r.mesh_faces;
    j["vertices"] = r.mesh_vertices;
    j["max_chordal_deviation"] = r.max_chordal_deviation;
  }
  if (r.points > 0 || r.format == "exr") {
    j["points"] = {{"count", r.points}, {"outside", r.points_outside}, {"source", valid_utf8(r.points_source)},
                   {"max_error", r.errors.max}, {"rms_error", r.errors.rms}, {"p95", r.errors.p95}};
  }
  return j.dump(2, ' ', false, json::error_handler_t::replace);
}

}  // namespace tbs
