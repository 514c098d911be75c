// The `tbs` command: triangular B-spline surfaces from scans, for CAD.

#include "commands.h"

#include <tbs/errors.h>
#include <tbs/io.h>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <malloc.h>

#include <cctype>
#include <climits>
#include <cstdio>
#include <string>
#include <vector>
#include <exception>
#include <iostream>
#include <optional>

namespace {
std::string lower_ascii(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// The options that several subcommands share, each defined once. Where the subcommands'
// help texts differ, the caller completes it.

// The .tbs file a subcommand reads (positional).
CLI::Option* add_tbs_input(CLI::App* cmd, const std::string& name, std::string& file) {
  return cmd->add_option(name, file, "The .tbs file")->required();
}

// --threads, -t: bounds every parallel loop (main() sets TBB's limit from it too).
CLI::Option* add_threads(CLI::App* cmd, int& threads, const std::string& more = "") {
  return cmd->add_option("--threads,-t", threads, "Worker threads (0 = all cores)" + more)
      ->check(CLI::NonNegativeNumber);
}

// --quiet, -q: no progress on stderr (the summary still goes to stdout).
CLI::Option* add_quiet(CLI::App* cmd, bool& quiet) {
  return cmd->add_flag("--quiet,-q", quiet, "No progress messages on stderr");
}

// --report FILE: a JSON report of the run, written atomically.
CLI::Option* add_report(CLI::App* cmd, std::string& report, const std::string& help) {
  return cmd->add_option("--report", report, help);
}

// --units: a length unit of the ones .tbs files record (docs/format.md), or also unitless.
CLI::Option* add_units(CLI::App* cmd, std::string& units, const std::string& help, bool unitless) {
  std::vector<std::string> allowed{"mm", "cm", "m", "um", "in", "ft"};
  if (unitless) allowed.emplace_back("unitless");
  return cmd->add_option("--units", units, help)->check(CLI::IsMember(allowed));
}

// --max-points: a scan with more points is refused before it is read.
CLI::Option* add_max_points(CLI::App* cmd, size_t& max_points, const std::string& help) {
  return cmd->add_option("--max-points", max_points, help)->check(CLI::PositiveNumber)->capture_default_str();
}
}  // namespace

int main(int argc, char** argv) {
  using namespace tbs::cli;
  // Ctrl-C or a kill while a file is being written: remove the temporary file, keep any earlier
  // output, and end as the signal says (exit status 128 + signal in a shell).
  tbs::remove_outputs_on_signal();
#ifdef __GLIBC__
  // glibc gives every block above 32 MB back to the system when it is freed, and the next one
  // comes back as fresh pages, each faulted in and zeroed on first touch. A fit allocates and
  // frees arrays of that size in every solve (the normal equations, CHOLMOD's factor), and
  // those page faults took a third of the solve stage: 39 s -> 25 s at 200,000 points and
  // degree 4 with freed memory kept for reuse (docs/benchmarks.md, "Large scans"). The
  // library leaves malloc alone; this is the command's choice for its own process.
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, INT_MAX);
#endif
  CLI::App app{"tbs " TBS_VERSION ": triangular B-spline (DMS spline) surfaces from 3D scans, "
               "for CAD.\nThis version fits splines to scans (with parameters (u, v), or raw meshes and "
               "point clouds, which it flattens first), inspects and evaluates .tbs splines, and "
               "converts them to STEP, IGES, glTF, OBJ, PLY and OpenEXR error maps.\n"
               "Exit codes: 0 ok, 2 bad usage, 3 invalid input, 4 file I/O error, 5 internal error."};
  app.set_version_flag("--version", "tbs " TBS_VERSION);
  app.require_subcommand(1);

  InfoOptions info;
  auto* info_cmd = app.add_subcommand(
      "info", "Print a JSON summary of a .tbs spline: sizes, bounding boxes, knot conditions, "
              "continuity at features. Exit code 3 if the knot conditions fail.");
  add_tbs_input(info_cmd, "file", info.file);

  EvalOptions eval;
  auto* eval_cmd = app.add_subcommand(
      "eval", "Evaluate a .tbs spline at parameter points: reads one \"u v\" pair per line "
              "(blank lines and lines starting with # are skipped) and writes \"x y z\" per "
              "point, in input order.");
  add_tbs_input(eval_cmd, "file", eval.file);
  eval_cmd->add_option("--input,-i", eval.input, "Read points from this file instead of stdin");
  eval_cmd->add_flag("--normals,-n", eval.normals, "Append the unit normal \"nx ny nz\"");
  eval_cmd->add_flag("--derivatives,-d", eval.derivatives,
                     "Append the partial derivatives \"Fu_x Fu_y Fu_z Fv_x Fv_y Fv_z\"");
  add_threads(eval_cmd, eval.threads);
  eval_cmd->add_option("--outside", eval.outside,
                       "A point outside the domain: error (exit 3, nothing written), nan (a line of nan "
                       "values in its place) or skip (no line); nan and skip warn with their count")
      ->check(CLI::IsMember({"error", "nan", "skip"}))->capture_default_str();

  FitCommandOptions fit;
  auto* fit_cmd = app.add_subcommand(
      "fit", "Fit one triangular B-spline to a scan until the maximum error is within the "
             "tolerance, and write it as .tbs. Inputs with parameters: PLY (ASCII or binary; "
             "vertex u v, s t or texture_u texture_v), OBJ (vt), XYZ/TXT with 5 or 8 columns "
             "(x y z u v [nx ny nz]). Without parameters (meshes: PLY, OBJ, OFF, STL; point clouds: "
             "PLY, XYZ with 3 or 6 columns) the scan is repaired, meshed if it is a point cloud, cut "
             "open if closed, and flattened first (docs/fit.md). Prints a summary table on stdout, "
             "progress on stderr.");
  fit_cmd->add_option("input", fit.input, "The scan")->required();
  fit_cmd->add_option("-o,--output", fit.output, "The .tbs file to write (CAD and mesh files: --export)")->required();
  fit_cmd->add_option("--degree", fit.fit.degree, "Polynomial degree n (C^(n-1) where smooth)")
      ->check(CLI::Range(1, 8))->capture_default_str();
  fit_cmd->add_option("--tolerance", fit.fit.tolerance,
                      "Maximum error, relative to the largest side of the points' bounding box "
                      "(1e-3 = 0.1 %)")
      ->check(CLI::PositiveNumber)->capture_default_str();
  fit_cmd->add_option("--tolerance-abs", fit.fit.tolerance_abs,
                      "Maximum error in model units (overrides --tolerance)")
      ->check(CLI::PositiveNumber);
  fit_cmd->add_option("--triangles", fit.fit.triangles,
                      "Triangles of the initial domain (default: points / 200, 32 to 4000)")
      ->check(CLI::Range(1, 10'000'000));
  fit_cmd->add_option("--fairness", fit.fit.fairness,
                      "Weight of the normal fairness term (dimensionless; 0 turns it off)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  fit_cmd->add_option("--bending", fit.fit.bending,
                      "Weight of the bending (thin-plate) term that holds the surface between "
                      "points (dimensionless; 0 turns it off)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  fit_cmd->add_option("--smoothness", fit.fit.smoothness, "Weight of the third-order smoothness term that keeps the surface's curvature "
                      "between points without flattening it (dimensionless; 0 turns it off)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  auto* fa = fit_cmd->add_option("--feature-angle", fit.fit.feature_angle,
                                 "Dihedral angle in degrees above which an edge is a sharp feature "
                                 "(kept C^0)")
                 ->check(CLI::Range(1.0, 179.0))->capture_default_str();
  fit_cmd->add_flag("--no-features", fit.no_features, "Do not detect sharp features")->excludes(fa);
  fit_cmd->add_option("--max-control-points", fit.fit.max_control_points,
                      "Stop refining before exceeding this many control points (default: the "
                      "number of points)")
      ->check(CLI::PositiveNumber);
  fit_cmd->add_option("--max-iterations", fit.fit.max_iterations, "Most refinement rounds")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  fit_cmd->add_option("--knot-sweeps", fit.fit.knot_sweeps,
                      "Most knot optimisation passes per round; they stop early when one gains "
                      "less than 1 % (0 = fixed knots)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  add_units(fit_cmd, fit.units, "Length unit of the scan: mm, cm, m, um, in, ft, unitless", true)
      ->capture_default_str();
  add_report(fit_cmd, fit.report, "Also write the fit report (JSON) here");
  add_threads(fit_cmd, fit.fit.threads, "; the result does not depend on it");
  add_quiet(fit_cmd, fit.quiet);
  fit_cmd->add_option("--component", fit.component,
                      "Scans without (u, v): the mesh component to fit, 1 = the largest (default), "
                      "numbered by decreasing face count")
      ->check(CLI::PositiveNumber);
  fit_cmd->add_flag("--all-components", fit.all_components,
                    "Scans without (u, v): fit every component, each to its own files OUT-K.tbs "
                    "(and REPORT-K.json, EXPORT-K.ext)");
  fit_cmd->add_option("--flatten", fit.flatten,
                      "Scans without (u, v): auto (LSCM, relaxed toward equal areas where it shrinks "
                      "parts of the surface tenfold on average; mean-value coordinates if LSCM folds), "
                      "lscm (the conformal map alone), or mean-value")
      ->check(CLI::IsMember({"auto", "lscm", "mean-value"}))->capture_default_str();
  add_max_points(fit_cmd, fit.max_points,
                 "Refuse scans with more points than this, before reading them (a fit takes about "
                 "1 KB of memory per point)");
  fit_cmd->add_option("--max-memory", fit.max_memory,
                      "Memory limit for the fit, e.g. 8G or 512M (0 = the memory available when tbs starts, "
                      "within a container's limit): a fit estimated to need more is refused before it starts, "
                      "and refinement stops before it would need more")
      ->transform(CLI::AsSizeValue(false))->capture_default_str();
  fit_cmd->add_option("--min-points", fit.min_points,
                      "Scans without (u, v): when a mesh's vertices do not reach the tolerance within the "
                      "control-point budget, it is subdivided 1-to-4 (new points on a smooth surface through "
                      "the vertices) until it has this many points (at least once) and fitted again, the new "
                      "points as guides (a tenth of the weight, errors measured at the vertices only); once "
                      "more while the fit still stops at the budget with at most 100,000 points; 0 = never")
      ->capture_default_str();
  fit_cmd->add_option("--no-folds", fit.no_folds,
                      "A fitted surface that folds (its normal reverses in some domain triangles; the "
                      "summary's 'folds' line): warn writes it with a warning, strict refuses it (exit 3, "
                      "nothing written)")
      ->check(CLI::IsMember({"warn", "strict"}))
      ->capture_default_str();
  fit_cmd->add_flag("--keep-points", fit.keep_points,
                    "Store the points and their parameters in the .tbs, so that 'tbs convert' can make "
                    "error maps and heat maps without --points (the file grows by about 100 bytes a point)");
  fit_cmd->add_option("--export", fit.exports,
                      "Also write the result to this file, as 'tbs convert OUT.tbs FILE' does with "
                      "its defaults (.step .stp .iges .igs .glb .gltf .obj .ply, or .exr: the error map of this "
                      "scan); repeatable");

  ConvertOptions convert;
  auto* convert_cmd = app.add_subcommand(
      "convert", "Convert a .tbs spline to a CAD file: STEP (.step, .stp; AP214, or AP242 with "
                 "--schema) or IGES 5.3 (.iges, .igs), as B-spline faces in one shell with shared "
                 "edges, checked by OpenCASCADE before writing. By default each smooth region of the "
                 "surface (bounded by the boundary and the creases) becomes one trimmed B-spline face "
                 "within the CAD tolerance of the spline; --faces triangles writes Bezier patches per "
                 "domain triangle, --faces exact (or --exact) the exact polynomial pieces. Or a glTF 2.0 "
                 "mesh (.glb, .gltf) with normals, (u, v) and domain-triangle ids, or OBJ / PLY. Or an "
                 "error map of the scan (--points) as OpenEXR (.exr) with a PNG preview beside it. A "
                 "summary goes to stdout.");
  add_tbs_input(convert_cmd, "input", convert.input);
  convert_cmd->add_option("output", convert.output, "The file to write (format from the extension)")->required();
  convert_cmd->add_option("--format", convert.format, "Output format, overriding the extension: step, iges, glb, gltf, obj, ply, exr")
      ->check(CLI::IsMember({"step", "stp", "iges", "igs", "glb", "gltf", "obj", "ply", "exr"}, CLI::ignore_case));
  convert_cmd->add_option("--points", convert.points,
                          "Error maps (exr) and --color-by error: the scan the spline was fitted to (with "
                          "parameters u v); default: the points stored by 'tbs fit --keep-points'");
  add_max_points(convert_cmd, convert.max_points,
                 "Refuse a --points scan with more points than this, before reading it");
  convert_cmd->add_option("--color-by", convert.color_by,
                          "glTF meshes: none, or error (a COLOR_0 heat map of the points' error, blue 0 to "
                          "red at the fit tolerance or the largest error; needs the points)")
      ->check(CLI::IsMember({"none", "error"}))->capture_default_str();
  convert_cmd->add_option("--width", convert.width, "Error maps and --color-by error: pixels across u (the height keeps the domain's aspect)")
      ->check(CLI::Range(1, 16384))->capture_default_str();
  convert_cmd->add_option("--measure", convert.measure,
                          "Error maps: parameter (|p - F(u)| at the point's own parameter, as the fit "
                          "reports) or closest (distance to the closest surface point)")
      ->check(CLI::IsMember({"parameter", "closest"}))->capture_default_str();
  convert_cmd->add_option("--resolution", convert.resolution,
                          "Meshes (glb, gltf, obj, ply): cut every domain edge into this many segments "
                          "(default: adaptive to --chordal-tolerance)")
      ->check(CLI::Range(1, 4096));
  convert_cmd->add_option("--chordal-tolerance", convert.chordal_tolerance,
                          "Meshes: largest distance between triangles and surface, relative to the "
                          "model size")
      ->check(CLI::PositiveNumber)->capture_default_str();
  convert_cmd->add_option("--faces", convert.faces,
                          "STEP/IGES surface form: regions (one trimmed B-spline face per smooth region), "
                          "triangles (Bezier patches per domain triangle, split to the tolerance) or exact "
                          "(the exact polynomial pieces, many more faces)")
      ->check(CLI::IsMember({"regions", "triangles", "exact"}))->capture_default_str();
  convert_cmd->add_flag("--exact", convert.exact, "The same as --faces exact");
  convert_cmd->add_option("--face-degree", convert.face_degree, "Region faces: B-spline degree in u and v")
      ->check(CLI::Range(2, 9))->capture_default_str();
  convert_cmd->add_option("--max-poles", convert.max_poles,
                          "Region faces: most poles of one face; a region that needs more is split along "
                          "domain edges")
      ->check(CLI::Range(16L, 10'000'000L))->capture_default_str();
  convert_cmd->add_option("--patch-degree", convert.patch_degree,
                          "Triangle patches: degree (default: spline degree + 2; at least the spline degree)")
      ->check(CLI::Range(1, 15));
  convert_cmd->add_option("--cad-tolerance", convert.cad_tolerance,
                          "Largest distance between the faces and the spline, relative to the model size "
                          "(the diagonal of the control points' bounding box). Default: 1/20 of the fit's "
                          "tolerance recorded in the .tbs, or 1e-5 when it records none")
      ->check(CLI::PositiveNumber);
  convert_cmd->add_option("--angle-tolerance", convert.angle_tolerance,
                          "Largest angle in degrees between the normals of faces meeting where the "
                          "surface is smooth (each face keeps within half of it of the spline)")
      ->check(CLI::Range(0.001, 89.0))->capture_default_str();
  convert_cmd->add_option("--max-patches", convert.max_patches,
                          "Triangle patches: most patches; splitting stops there, with a warning if the "
                          "tolerances are not met (each patch is 3 B-spline faces with quads)")
      ->check(CLI::Range(1L, 10'000'000L))->capture_default_str();
  convert_cmd->add_option("--schema", convert.schema, "STEP schema: ap214 or ap242")
      ->check(CLI::IsMember({"ap214", "ap242"}, CLI::ignore_case))->capture_default_str();
  convert_cmd->add_option("--triangle-patch", convert.triangle_patch,
                          "Triangle patches and exact pieces: how a triangle becomes B-spline faces: quads (three, none degenerate) "
                          "or degenerate (one, with a collapsed edge)")
      ->check(CLI::IsMember({"quads", "degenerate"}))->capture_default_str();
  add_units(convert_cmd, convert.units,
            "Length unit written to the file: mm, cm, m, um, in, ft (default: the .tbs "
            "units; mm if it has none). Coordinates are not scaled.",
            false);
  convert_cmd->add_option("--product-name", convert.product_name,
                          "Product name in the file (default: the output's file name); STEP and IGES get it in "
                          "ASCII, other characters as _");
  add_report(convert_cmd, convert.report,
             "Write a JSON report: faces, regions or patches, measured deviations, CAD "
             "tolerance and where it came from, seconds per stage, file size");
  add_threads(convert_cmd, convert.threads);
  add_quiet(convert_cmd, convert.quiet);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kOk : kUsage;
  }

  // --threads bounds every parallel loop, also those inside CGAL and TBB-parallel helpers that
  // take no thread count (normal estimation, point-cloud meshing).
  const int threads = *eval_cmd ? eval.threads : *fit_cmd ? fit.fit.threads : *convert_cmd ? convert.threads : 0;
  std::optional<tbb::global_control> limit;
  if (threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));

  try {
    if (*info_cmd) return run_info(info);
    if (*eval_cmd) return run_eval(eval);
    if (*fit_cmd) return run_fit(fit);
    if (*convert_cmd) {
      convert.schema = lower_ascii(convert.schema);
      return run_convert(convert);
    }
  } catch (const tbs::IoError& e) {
    std::fprintf(stderr, "tbs: error: %s\n", e.what());
    return kIo;
  } catch (const tbs::InvalidInput& e) {
    std::fprintf(stderr, "tbs: error: %s\n", e.what());
    return kInvalidInput;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "tbs: error: out of memory\n");
    return kInternal;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tbs: internal error: %s\n", e.what());
    return kInternal;
  }
  return kUsage;
}
