#include "commands.h"

#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/fit.h>
#include <tbs/io.h>
#include <tbs/knots.h>
#include <tbs/parameterize.h>
#include <tbs/scan.h>
#include <tbs/shape_check.h>

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <functional>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <cstdio>
#include <iostream>
#include <iterator>
#include <limits>
#include <sstream>

namespace tbs::cli {
namespace {

// A mesh fit of more points is not subdivided again when it does not reach the tolerance:
// the next fit would need four times the points, memory and time.
constexpr size_t kMaxDensifyPoints = 100'000;

using json = nlohmann::ordered_json;

json box_json(const Point2& lo, const Point2& hi) {
  return {{"min", {lo.x(), lo.y()}}, {"max", {hi.x(), hi.y()}}};
}
json box_json(const Box3& b) {
  return {{"min", {b.min.x(), b.min.y(), b.min.z()}}, {"max", {b.max.x(), b.max.y(), b.max.z()}}};
}

// The surface's bounding box from samples: every triangle on a barycentric lattice.
Box3 sampled_surface_box(const Spline& s) {
  const int k = 8;
  std::vector<Point2> pts;
  const Domain& d = s.domain();
  for (int t = 0; t < d.triangle_count(); ++t) {
    const auto& tri = d.triangle(t);
    for (int i = 0; i <= k; ++i)
      for (int j = 0; i + j <= k; ++j) {
        const double a = double(i) / k, b = double(j) / k;
        pts.push_back(a * d.vertex(tri[0]) + b * d.vertex(tri[1]) + (1 - a - b) * d.vertex(tri[2]));
      }
  }
  std::vector<Point3> pos(pts.size());
  Evaluator ev(s);
  ev.evaluate_batch(pts, pos, {}, {}, {});
  Box3 box;
  for (const auto& p : pos)
    if (p.allFinite()) box.extend(p);
  return box;
}

bool parse_double(std::string_view s, double& x) {
  const auto* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, x);
  return ec == std::errc() && ptr == end;
}

}  // namespace

int run_info(const InfoOptions& o) {
  ReadOptions ro;
  ro.check_knots = false;
  const SplineFile f = read_tbs(o.file, ro);
  const Spline& s = f.spline;
  const Domain& d = s.domain();
  const int n = s.degree();
  const KnotCheck check = check_knot_conditions(d, n, s.knots());

  json j;
  j["file"] = o.file;
  j["degree"] = n;
  j["units"] = f.units;
  j["vertices"] = d.vertex_count();
  j["triangles"] = d.triangle_count();
  j["edges"] = d.edge_count();
  j["control_points"] = s.control_point_count();
  int holes = 0;
  for (const auto& loop : d.boundary_loops()) {
    double area = 0;
    for (size_t i = 0; i < loop.size(); ++i) {
      const Point2& p = d.vertex(loop[i]);
      const Point2& q = d.vertex(loop[(i + 1) % loop.size()]);
      area += p.x() * q.y() - p.y() * q.x();
    }
    if (area < 0) ++holes;
  }
  j["boundary_loops"] = d.boundary_loops().size();
  j["holes"] = holes;
  {
    int sharp = 0;
    for (const Seam& seam : f.atlas.seams) sharp += seam.sharp;
    j["atlas"] = {{"charts", domain_charts(d).count},
                  {"seams", f.atlas.seams.size()},
                  {"sharp_seams", sharp},
                  {"closed", f.atlas.closed},
                  {"genus", f.atlas.genus}};
  }
  j["feature_edges"] = d.feature_edges().size();
  const Box2 db = d.bounding_box();
  j["domain_bbox"] = box_json(db.min, db.max);
  Box3 net;
  for (const auto& c : s.control_points()) net.extend(c);
  j["control_net_bbox"] = box_json(net);

  json kc;
  kc["ok"] = check.ok();
  kc["issues"] = json::array();
  for (const auto& issue : check.issues) {
    json i;
    i["condition"] = issue.condition;
    if (issue.triangle >= 0) i["triangle"] = issue.triangle;
    if (issue.vertex >= 0) i["vertex"] = issue.vertex;
    i["message"] = issue.message;
    kc["issues"].push_back(i);
  }
  j["knot_conditions"] = kc;

  const auto cont = edge_continuity(d, n, s.knots());
  int smooth = n - 1;
  json feat = json::array();
  bool features_c0 = true;
  for (int e = 0; e < d.edge_count(); ++e) {
    if (d.is_feature_edge(e)) {
      feat.push_back({{"edge", {d.edges()[e][0], d.edges()[e][1]}}, {"continuity", cont[e]}});
      features_c0 = features_c0 && cont[e] <= 0;
    } else {
      smooth = std::min(smooth, cont[e]);
    }
  }
  j["continuity"] = {{"smooth_edges_min", smooth},
                     {"features_at_most_c0", features_c0},
                     {"feature_edges", feat},
                     {"note", "lower bounds C^k from collinear knots (METHOD.md section 3)"}};
  if (check.ok()) {
    j["surface_bbox"] = box_json(sampled_surface_box(s));
    const Evaluator eval(s);
    // Folds are reversals within the fit's tolerance, where the metadata gives it.
    double fold_tolerance = 0;
    {
      const json meta = json::parse(f.metadata_json);
      if (meta.contains("fit") && meta["fit"].is_object() && meta["fit"].contains("tolerance_abs") &&
          meta["fit"]["tolerance_abs"].is_number() && meta["fit"]["tolerance_abs"].get<double>() > 0)
        fold_tolerance = meta["fit"]["tolerance_abs"].get<double>();
    }
    const ShapeCheck shape = check_shape(s, eval, 8, 0, fold_tolerance, f.atlas);
    j["shape"] = {{"folds", shape.folded_triangles.size()},
                  {"folded_triangles", shape.folded_triangles},
                  {"max_normal_turn_degrees", shape.max_normal_turn},
                  {"max_stretch", shape.max_stretch},
                  {"note", "folds: domain triangles where the surface turns back over itself (its normal turns by "
                           "more than 150 degrees between points within the fit's tolerance, or 1e-3 of the model "
                           "size; 8 x 8 samples per triangle and across smooth edges, looked at closely where they "
                           "turn by more than 90 degrees); max_stretch: largest |F_u|, |F_v| x chart diameter / "
                           "chart size"}};
    if (!f.atlas.empty()) {
      const SeamCheck seams = check_seams(s, eval, f.atlas, 1000);
      j["atlas"]["seam_gap"] = seams.max_gap;
      j["atlas"]["seam_normal_jump_degrees"] = seams.max_normal_jump;
      j["atlas"]["seam_crease_degrees"] = {seams.min_crease, seams.max_crease};
      j["atlas"]["seam_samples"] = seams.samples;
      j["atlas"]["seam_samples_outside"] = seams.outside;
    }
  }
  j["metadata"] = json::parse(f.metadata_json);

  std::cout << j.dump(2, ' ', false, json::error_handler_t::replace) << "\n";
  if (!check.ok()) {
    std::fprintf(stderr, "tbs: error: %s: %zu knot condition(s) fail; first: %s\n", o.file.c_str(),
                 check.issues.size(), check.issues[0].message.c_str());
    return kInvalidInput;
  }
  return kOk;
}

int run_eval(const EvalOptions& o) {
  const SplineFile f = read_tbs(o.file);
  const std::string input_name = o.input.empty() || o.input == "-" ? "<stdin>" : o.input;
  std::string text;
  if (input_name == "<stdin>") {
    text.assign(std::istreambuf_iterator<char>(std::cin), std::istreambuf_iterator<char>());
  } else {
    text = read_file(o.input);
  }

  std::vector<Point2> pts;
  std::vector<size_t> line_of;
  size_t line = 0;
  for (size_t pos = 0; pos < text.size();) {
    size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view l(text.data() + pos, end - pos);
    pos = end + 1;
    ++line;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    std::vector<std::string_view> tok;
    for (size_t i = 0; i < l.size();) {
      while (i < l.size() && (l[i] == ' ' || l[i] == '\t' || l[i] == ',')) ++i;
      size_t k = i;
      while (k < l.size() && l[k] != ' ' && l[k] != '\t' && l[k] != ',') ++k;
      if (k > i) tok.push_back(l.substr(i, k - i));
      i = k;
    }
    if (tok.empty() || tok[0][0] == '#') continue;
    double u = 0, v = 0;
    const std::string where = input_name + ":" + std::to_string(line) + ": ";
    if (tok.size() != 2 || !parse_double(tok[0], u) || !parse_double(tok[1], v))
      throw InvalidInput(where + "expected two numbers \"u v\", got \"" +
                         std::string(l.substr(0, 80)) + "\"");
    if (!std::isfinite(u) || !std::isfinite(v))
      throw InvalidInput(where + "coordinates must be finite numbers");
    pts.emplace_back(u, v);
    line_of.push_back(line);
  }

  Evaluator ev(f.spline);
  std::vector<Point3> pos(pts.size());
  std::vector<Vector3> du(pts.size()), dv(pts.size());
  std::vector<uint8_t> inside(pts.size());
  const bool need_d = o.normals || o.derivatives;
  ev.evaluate_batch(pts, pos, need_d ? std::span<Vector3>(du) : std::span<Vector3>(),
                    need_d ? std::span<Vector3>(dv) : std::span<Vector3>(), inside, o.threads);
  size_t outside = 0, first_outside = 0;
  for (size_t i = 0; i < pts.size(); ++i)
    if (!inside[i] && outside++ == 0) first_outside = i;
  if (outside > 0) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s:%zu: parameter point (%.17g, %.17g) is outside the domain",
                  input_name.c_str(), line_of[first_outside], pts[first_outside].x(), pts[first_outside].y());
    if (o.outside == "error")
      throw OutsideDomain(std::string(buf) + "; 'tbs info " + o.file +
                          "' shows the domain_bbox (--outside nan or skip evaluates the others)");
    std::fprintf(stderr, "tbs eval: warning: %zu of %zu point(s) outside the domain %s, the first %s\n", outside,
                 pts.size(), o.outside == "nan" ? "written as nan" : "left out", buf);
  }

  std::string out;
  out.reserve(pts.size() * (need_d ? 200 : 64));
  char buf[64];
  auto put = [&](double x, bool first) {
    const int len = std::snprintf(buf, sizeof buf, first ? "%.17g" : " %.17g", x);
    out.append(buf, static_cast<size_t>(len));
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Vector3 nan3(nan, nan, nan);
  for (size_t i = 0; i < pts.size(); ++i) {
    if (!inside[i]) {
      if (o.outside == "skip") continue;
      // evaluate_batch leaves NaN there; written explicitly so that every column says nan.
      pos[i] = nan3;
      du[i] = dv[i] = nan3;
    }
    put(pos[i].x(), true);
    put(pos[i].y(), false);
    put(pos[i].z(), false);
    if (o.normals) {
      Vector3 nrm = du[i].cross(dv[i]);
      const double len = nrm.norm();
      nrm = len > 0 || !inside[i] ? Vector3(nrm / len) : Vector3::Zero();
      for (int k = 0; k < 3; ++k) put(nrm[k], false);
    }
    if (o.derivatives) {
      for (int k = 0; k < 3; ++k) put(du[i][k], false);
      for (int k = 0; k < 3; ++k) put(dv[i][k], false);
    }
    out += '\n';
  }
  std::fwrite(out.data(), 1, out.size(), stdout);
  std::fflush(stdout);
  return kOk;
}

}  // namespace tbs::cli

namespace tbs::cli {

namespace {

// PATH with "-K" before its extension: out.tbs -> out-2.tbs.
std::string numbered(const std::string& path, int k) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  return (p.parent_path() / (p.stem().string() + "-" + std::to_string(k) + p.extension().string())).string();
}

struct Say {
  bool quiet, tty;
  void operator()(const std::string& line) const {
    if (quiet) return;
    if (tty)
      std::fprintf(stderr, "\r\033[K%s", line.c_str());
    else
      std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
  }
};

void print_parameterization(const ParameterizeReport& p) {
  std::printf("%-18s %s, %zu points%s; %s\n", "parameterized", p.input.c_str(), p.input_points,
              p.input == "mesh" ? (", " + std::to_string(p.input_faces) + " faces").c_str()
                                : (", reconstructed " + std::to_string(p.reconstructed_faces) + " faces" +
                                   (p.bridge_faces_removed ? " (" + std::to_string(p.bridge_faces_removed) +
                                                                 " spanning gaps removed)" : std::string()))
                                      .c_str(),
              p.topology.describe().c_str());
  std::string repairs;
  auto add = [&](size_t n, const char* what) {
    if (n) repairs += (repairs.empty() ? "" : ", ") + std::to_string(n) + " " + what;
  };
  add(p.vertices_merged, "duplicate vertices merged");
  add(p.faces_removed, "degenerate or duplicate faces removed");
  add(p.vertices_split, "non-manifold vertices split");
  add(p.isolated_points, "unused vertices left out");
  if (p.reoriented) repairs += (repairs.empty() ? "" : ", ") + std::string("faces reoriented");
  if (!repairs.empty()) std::printf("%-18s %s\n", "mesh repairs", repairs.c_str());
  std::printf("%-18s %d of %d: %zu vertices, %zu faces, %d boundary loop%s\n", "component", p.component,
              p.topology.components, p.used.vertices, p.used.faces, p.used.boundary_loops,
              p.used.boundary_loops == 1 ? "" : "s");
  if (p.subdivisions)
    std::printf("%-18s %d x 1-to-4: %zu points added on a smooth surface through the vertices (--min-points)\n",
                "subdivided", p.subdivisions, p.points_added);
  if (p.charts > 1 || p.seams > 0)
    std::printf("%-18s %d charts, cut along %zu edges (%zu seams); flattening stretch %.3g\n", "charts", p.charts,
                p.seam_edges, p.seams, p.stretch);
  std::printf("%-18s %s%s\n", "flattening", p.method.c_str(),
              p.fallback_reason.empty() ? "" : (" (" + p.fallback_reason + ")").c_str());
  std::printf("%-18s angle %.3f mean, %.3g max; area %.3f mean, %.3g max (1 = none)\n", "distortion",
              p.distortion.angle_mean, p.distortion.angle_max, p.distortion.area_mean, p.distortion.area_max);
  if (p.method == "LSCM, areas relaxed")
    std::printf("%-18s angle %.3f mean, %.3g max; area %.3f mean, %.3g max (LSCM before relaxing)\n", "",
                p.conformal.angle_mean, p.conformal.angle_max, p.conformal.area_mean, p.conformal.area_max);
  if (p.points_projected) std::printf("%-18s %zu (parameter of the closest mesh point)\n", "points projected", p.points_projected);
  if (p.points_dropped) std::printf("%-18s %zu (other components, unused or merged vertices)\n", "points dropped", p.points_dropped);
}

// Every point the fit counts as fitted (finite error) must evaluate, at the (u, v) it was
// fitted at, on the spline as the .tbs stores it: the spline is formatted and parsed back (the
// points the file may keep play no part) and each point located. A failure is a bug; it names
// the first such point and nothing is written.
void check_round_trip(const SplineFile& file, const FitResult& r, const std::string& input,
                      const std::string& output) {
  const SplineFile back = parse_tbs(format_tbs(SplineFile{file.spline, file.units, file.metadata_json}), output);
  const Evaluator ev(back.spline);
  for (size_t i = 0; i < r.uv.size(); ++i) {
    if (!std::isfinite(r.error[i]) || ev.locate(r.uv[i]) >= 0) continue;
    char buf[160];
    std::snprintf(buf, sizeof buf, "point %zu at (u, v) = (%.17g, %.17g)", i + 1, r.uv[i].x(), r.uv[i].y());
    throw SolverError(output + ": internal check failed: " + buf + " of " + input +
                      " was fitted but lies outside the domain of the spline as written; nothing was "
                      "written. Please report this with the scan");
  }
}

// Fits one scan with parameters and writes the .tbs, the report and the exports. A flattened
// coarse mesh whose vertices alone cannot be fitted within the control-point budget is
// subdivided (`densify`, which replaces *pscan) and fitted again.
int fit_and_write(const FitCommandOptions& o, ParameterizedScan* pscan, const Scan* plain,
                  const std::function<bool(ParameterizedScan&)>& densify, const std::string& output,
                  const std::string& report, const std::vector<std::string>& exports, const Say& say,
                  const std::string& points_file, std::size_t degenerate_faces) {
  namespace fs = std::filesystem;
  FitOptions fo = o.fit;
  fo.features = !o.no_features;
  fo.progress = [&](const FitProgress& p) {
    std::string line = "tbs fit: [" + p.stage + "] ";
    if (say.tty && p.stage == "refine") {
      // A bar toward the tolerance (log scale of the maximum error).
      const int width = 20, done = static_cast<int>(std::lround(std::clamp(p.fraction, 0.0, 1.0) * width));
      line += "[" + std::string(done, '#') + std::string(width - done, ' ') + "] ";
    }
    say(line + p.message);
  };
  FitResult r = fit(pscan ? pscan->scan : *plain, fo);
  while (pscan && !r.report.converged && r.report.stop_reason.find("budget") != std::string::npos && densify) {
    const size_t before = pscan->scan.positions.size();
    if (!densify(*pscan)) break;
    say("tbs fit: " + std::to_string(before) + " points did not reach the tolerance within the control-point "
        "budget; fitting the subdivided mesh (" + std::to_string(pscan->scan.positions.size()) + " points)");
    r = fit(pscan->scan, fo);
  }
  if (say.tty && !say.quiet) std::fprintf(stderr, "\n");
  const Scan& scan = pscan ? pscan->scan : *plain;
  const ParameterizeReport* param = pscan ? &pscan->report : nullptr;

  const FitReport& rep = r.report;
  if (rep.folds > 0) {
    const std::string what = o.input + ": the fitted surface folds in " + std::to_string(rep.folds) +
                             " domain triangle(s): its normal reverses there (see 'folds' in the report)";
    if (o.no_folds == "strict")
      throw InvalidInput(what + "; nothing was written (--no-folds strict). A larger --bending smooths the "
                         "surface between the points");
    if (!o.quiet)
      std::fprintf(stderr, "tbs fit: warning: %s; CAD faces cannot follow it there. A larger --bending "
                   "smooths the surface between the points\n", what.c_str());
  }
  json meta;
  meta["source"] = valid_utf8(fs::path(o.input).filename().string());
  meta["fit"] = json::parse(rep.to_json(false));
  if (param) {
    json pj = json::parse(param->to_json());
    pj.erase("seconds");  // the .tbs stays reproducible
    meta["parameterization"] = pj;
  }
  SplineFile file{r.spline, o.units, meta.dump(-1, ' ', false, json::error_handler_t::replace)};
  file.atlas = r.atlas;
  const bool keep = o.keep_points;
  // The measured points and their parameters, without the guides of a subdivided mesh (they
  // come after the vertices): what --keep-points stores and error maps show. Copied only
  // where there are guides to leave out.
  std::vector<Point3> measured_copy;
  std::vector<Point2> measured_uv_copy;
  if (!scan.guide.empty())
    for (size_t i = 0; i < scan.positions.size(); ++i)
      if (!scan.guide[i]) measured_copy.push_back(scan.positions[i]), measured_uv_copy.push_back(r.uv[i]);
  const std::vector<Point3>& measured = scan.guide.empty() ? scan.positions : measured_copy;
  const std::vector<Point2>& measured_uv = scan.guide.empty() ? r.uv : measured_uv_copy;
  if (keep) {
    file.points = measured;
    file.point_parameters = measured_uv;
  }
  check_round_trip(file, r, o.input, output);
  write_tbs(output, file);
  if (!report.empty()) {
    json full = json::parse(rep.to_json(true));
    json excluded = json::array();
    for (size_t i = 0; i < r.error.size(); ++i)
      if (!std::isfinite(r.error[i])) excluded.push_back(i);
    full["excluded_points"] = std::move(excluded);
    if (param) full["parameterization"] = json::parse(param->to_json());
    write_file_atomic(report, full.dump(2, ' ', false, json::error_handler_t::replace) + "\n");
  }

  std::printf("%-18s %s\n", "input", o.input.c_str());
  std::printf("%-18s %s\n", "output", output.c_str());
  if (degenerate_faces)
    std::printf("%-18s %zu left out (fewer than three distinct corners)\n", "degenerate faces", degenerate_faces);
  if (param) print_parameterization(*param);
  std::printf("%-18s %zu\n", "points", rep.points);
  if (rep.guide_points > 0)
    std::printf("%-18s %zu of them (added by the subdivision; held with a tenth of the weight, errors not counted)\n",
                "guide points", rep.guide_points);
  if (rep.points_excluded > 0)
    std::printf("%-18s %zu (outside the largest parameter region)\n", "points left out", rep.points_excluded);
  std::printf("%-18s %d\n", "degree", rep.degree);
  std::printf("%-18s %d\n", "domain triangles", rep.domain_triangles);
  std::printf("%-18s %d\n", "control points", rep.control_points);
  std::printf("%-18s %.3e (%.4g %s)\n", "max error", rep.max_error, rep.max_error_abs, o.units.c_str());
  std::printf("%-18s %.3e (%.4g %s)\n", "RMS error", rep.rms_error, rep.rms_error_abs, o.units.c_str());
  std::printf("%-18s %.3e (%.4g %s)\n", "tolerance", rep.tolerance, rep.tolerance_abs, o.units.c_str());
  std::printf("%-18s %s (%s)\n", "converged", rep.converged ? "yes" : "no", rep.stop_reason.c_str());
  std::printf("%-18s %d domain triangle(s)%s\n", "folds", rep.folds, rep.folds > 0 ? " (the normal reverses)" : "");
  std::printf("%-18s %.3g (largest |F_u|, |F_v| x chart diameter / chart size)\n", "max stretch", rep.max_stretch);
  std::printf("%-18s %d chart%s, %d seam%s; %s, genus %d\n", "atlas", rep.charts, rep.charts == 1 ? "" : "s", rep.seams,
              rep.seams == 1 ? "" : "s", rep.closed ? "closed" : "open", rep.genus);
  if (rep.seams > 0)
    std::printf("%-18s gap %.3e (%.4g %s), normal jump %.3g degrees (smooth seams)%s\n", "seams", rep.seam_gap,
                rep.seam_gap_abs, o.units.c_str(), rep.seam_normal_jump,
                rep.seam_crease_max > 0 ? (", creases " + std::to_string(static_cast<int>(std::lround(rep.seam_crease_min))) +
                                           " to " + std::to_string(static_cast<int>(std::lround(rep.seam_crease_max))) +
                                           " degrees").c_str()
                                        : "");
  std::printf("%-18s %.2f s\n", "time", rep.seconds + (param ? param->seconds : 0.0));
  // --export: each file as `tbs convert OUT.tbs FILE` would write it (error maps from the scan
  // or from the points kept in the .tbs).
  for (const std::string& e : exports) {
    ConvertOptions c;
    c.input = output;
    c.output = e;
    if (param) {
      // Computed parameters are not in the scan file: hand the points over directly.
      c.point_positions = measured;
      c.point_uv = measured_uv;
    } else if (!keep) {
      c.points = points_file;
    }
    c.threads = o.fit.threads;
    c.quiet = o.quiet;
    std::printf("\n");
    std::fflush(stdout);
    const int code = run_convert(c);
    if (code != kOk) return code;
  }
  return kOk;
}

}  // namespace

uint64_t available_memory() {
  auto read_number = [](const char* path, uint64_t& value) {
    std::ifstream f(path);
    std::string text;
    if (!(f >> text)) return false;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    return ec == std::errc() && end == text.data() + text.size();
  };
  uint64_t available = 0;
  {
    std::ifstream f("/proc/meminfo");
    std::string key, unit;
    uint64_t kib = 0;
    while (f >> key >> kib) {
      std::getline(f, unit);
      if (key == "MemAvailable:") {
        available = kib * 1024;
        break;
      }
    }
  }
  // cgroup v2, then v1: limit minus usage.
  uint64_t limit = 0, used = 0;
  if ((read_number("/sys/fs/cgroup/memory.max", limit) && read_number("/sys/fs/cgroup/memory.current", used)) ||
      (read_number("/sys/fs/cgroup/memory/memory.limit_in_bytes", limit) &&
       read_number("/sys/fs/cgroup/memory/memory.usage_in_bytes", used))) {
    const uint64_t room = limit > used ? limit - used : 0;
    if (room > 0 && (available == 0 || room < available)) available = room;
  }
  return available;
}

int run_fit(const FitCommandOptions& given) {
  namespace fs = std::filesystem;
  FitCommandOptions o = given;
  o.fit.max_memory = given.max_memory > 0 ? given.max_memory : available_memory();
  o.fit.max_memory_name = "--max-memory";
  std::error_code ec;
  if (fs::exists(o.output, ec) && fs::exists(o.input, ec) && fs::equivalent(o.input, o.output, ec))
    throw InvalidInput(o.output + ": the output would overwrite the input; choose another -o path");
  // -o is the spline (.tbs, JSON); a CAD or mesh name there is a slip for --export.
  {
    std::string ext = fs::path(o.output).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    bool export_name = false;
    try {
      convert_format(o.output);
      export_name = true;
    } catch (const InvalidInput&) {
    }
    if (export_name) {
      std::fprintf(stderr, "tbs: error: %s: -o writes the fitted spline (.tbs); to write %s too, give -o NAME.tbs --export %s\n",
                   o.output.c_str(), ext.c_str(), o.output.c_str());
      return kUsage;
    }
  }
  // Outputs checked before the work, not after it.
  check_output_path(o.output);
  if (!o.report.empty()) check_output_path(o.report);
  for (const std::string& e : o.exports) check_output_path(e);
  for (const std::string& e : o.exports) {
    try {
      convert_format(e);
    } catch (const InvalidInput& err) {
      std::fprintf(stderr, "tbs: error: %s\n", err.what());
      return kUsage;
    }
  }
  for (const std::string& e : o.exports)
    if ((fs::exists(e, ec) && fs::equivalent(o.input, e, ec)) || fs::path(e) == fs::path(o.output))
      throw InvalidInput(e + ": an --export file would overwrite the scan or the .tbs; choose another path");
  const Say say{o.quiet, isatty(fileno(stderr)) != 0};

  say("tbs fit: reading " + o.input);
  const Scan scan = read_scan(o.input, {.max_points = o.max_points, .limit_name = "--max-points"});
  // Refused before parameterization and fitting; fit() checks again (subdivided meshes grow).
  check_fit_memory(o.input, scan.positions.size(), o.fit);
  if (scan.degenerate_faces && !scan.has_faces() && !o.quiet)  // a note, not a progress line
    std::fprintf(stderr, "tbs fit: every face of %s is degenerate (fewer than three distinct corners); its points "
                 "are fitted as a point cloud\n", o.input.c_str());
  if (scan.has_uv()) {
    if (o.component > 0 || o.all_components)
      say("tbs fit: the scan has parameters (u, v); --component and --all-components apply only to scans without them");
    return fit_and_write(o, nullptr, &scan, nullptr, o.output, o.report, o.exports, say, o.input, scan.degenerate_faces);
  }

  // No parameters: flatten a mesh, or reconstruct and flatten a point cloud.
  ParameterizeOptions po;
  po.method = o.flatten == "lscm" ? FlattenMethod::Lscm : o.flatten == "mean-value" ? FlattenMethod::MeanValue : FlattenMethod::Auto;
  po.progress = [&](const std::string& line) { say("tbs fit: [parameterize] " + line); };
  po.component = o.component;
  po.sharp_angle = o.fit.feature_angle;
  // Vertices first; a coarse mesh is subdivided only if they are not enough (see fit_and_write).
  auto densify = [&](ParameterizedScan& p) {
    const size_t points = p.scan.positions.size();
    if (p.report.input != "mesh" || o.min_points == 0 || points > kMaxDensifyPoints) return false;
    ParameterizeOptions dense = po;
    dense.component = p.report.component;
    // One more subdivision than now (each about quadruples the points), more up to --min-points.
    dense.min_points = std::max(o.min_points, 2 * points);
    p = parameterize_scan(scan, dense);
    // Subdivision stops at 4 levels: a mesh that already has them gains no point, and fitting
    // it again would give the same fit forever.
    return p.scan.positions.size() > points;
  };
  ParameterizedScan first = parameterize_scan(scan, po);
  if (!o.all_components)
    return fit_and_write(o, &first, nullptr, densify, o.output, o.report, o.exports, say, o.input, scan.degenerate_faces);

  // Every component to its own files: OUT-K.tbs, REPORT-K.json, EXPORT-K.ext.
  const int count = first.report.topology.components;
  int failed = 0;
  for (int k = 1; k <= count; ++k) {
    std::vector<std::string> exports;
    for (const auto& e : o.exports) exports.push_back(numbered(e, k));
    say("tbs fit: component " + std::to_string(k) + " of " + std::to_string(count));
    if (k > 1) std::printf("\n");
    try {
      po.component = k;
      ParameterizedScan p = k == 1 ? std::move(first) : parameterize_scan(scan, po);
      const int code = fit_and_write(o, &p, nullptr, densify, numbered(o.output, k),
                                     o.report.empty() ? "" : numbered(o.report, k), exports, say, o.input, scan.degenerate_faces);
      if (code != kOk) return code;
    } catch (const InvalidInput& e) {
      // A component that cannot be fitted (too small, wrong topology) does not stop the others.
      std::fprintf(stderr, "tbs: error: component %d: %s\n", k, e.what());
      std::printf("%-18s component %d not fitted: %s\n", "skipped", k, e.what());
      ++failed;
    }
  }
  return failed ? kInvalidInput : kOk;
}

}  // namespace tbs::cli
