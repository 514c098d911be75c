#pragma once
// The subcommands of the `tbs` command. Each returns the process exit code.

#include <string>

namespace tbs::cli {

/// Documented exit codes (README.md, docs/cli.md).
enum Exit : int {
  kOk = 0,
  kUsage = 2,         // bad command line
  kInvalidInput = 3,  // malformed or invalid input data, point outside the domain
  kIo = 4,            // a file cannot be read or written
  kInternal = 5,      // a bug or an unexpected failure
};

struct InfoOptions {
  std::string file;
};
int run_info(const InfoOptions& o);

struct EvalOptions {
  std::string file;
  std::string input;  // empty or "-": stdin
  bool normals = false;
  bool derivatives = false;
  int threads = 0;
};
int run_eval(const EvalOptions& o);

struct FitCommandOptions {
  std::string input;
  std::string output;
  std::string report;  // empty: none
  std::string units = "unitless";
  int degree = 3;
  double tolerance = 1e-3;
  double tolerance_abs = 0;
  int triangles = 0;
  double fairness = 1e-3;
  double feature_angle = 40;
  bool no_features = false;
  int max_control_points = 0;
  int max_iterations = 25;
  int knot_sweeps = 1;
  int threads = 0;
  bool quiet = false;
};
int run_fit(const FitCommandOptions& o);

}  // namespace tbs::cli
