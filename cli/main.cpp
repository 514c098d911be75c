// The `tbs` command: triangular B-spline surfaces from scans, for CAD.

#include "commands.h"

#include <tbs/errors.h>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <iostream>

int main(int argc, char** argv) {
  using namespace tbs::cli;
  CLI::App app{"tbs " TBS_VERSION ": triangular B-spline (DMS spline) surfaces from 3D scans, "
               "for CAD.\nThis version inspects and evaluates .tbs splines; fitting and CAD export "
               "are not available yet.\n"
               "Exit codes: 0 ok, 2 bad usage, 3 invalid input, 4 file I/O error, 5 internal error."};
  app.set_version_flag("--version", "tbs " TBS_VERSION);
  app.require_subcommand(1);

  InfoOptions info;
  auto* info_cmd = app.add_subcommand(
      "info", "Print a JSON summary of a .tbs spline: sizes, bounding boxes, knot conditions, "
              "continuity at features. Exit code 3 if the knot conditions fail.");
  info_cmd->add_option("file", info.file, "The .tbs file")->required();

  EvalOptions eval;
  auto* eval_cmd = app.add_subcommand(
      "eval", "Evaluate a .tbs spline at parameter points: reads one \"u v\" pair per line "
              "(blank lines and lines starting with # are skipped) and writes \"x y z\" per "
              "point, in input order.");
  eval_cmd->add_option("file", eval.file, "The .tbs file")->required();
  eval_cmd->add_option("--input,-i", eval.input, "Read points from this file instead of stdin");
  eval_cmd->add_flag("--normals,-n", eval.normals, "Append the unit normal \"nx ny nz\"");
  eval_cmd->add_flag("--derivatives,-d", eval.derivatives,
                     "Append the partial derivatives \"Fu_x Fu_y Fu_z Fv_x Fv_y Fv_z\"");
  eval_cmd->add_option("--threads,-t", eval.threads, "Worker threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kOk : kUsage;
  }

  try {
    if (*info_cmd) return run_info(info);
    if (*eval_cmd) return run_eval(eval);
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
