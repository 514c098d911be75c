#pragma once
// The subcommands of the `tbs` command. Each returns the process exit code.

#include <tbs/fit.h>

#include <cstdint>
#include <string>
#include <vector>

namespace tbs::cli {

/// Documented exit codes (README.md, docs/user-guide.md#exit-codes).
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
  std::string outside = "error";  // error | nan | skip: points outside the domain
};
int run_eval(const EvalOptions& o);

// Scans with more points are refused before they are read (--max-points): a fit takes about
// 1 KB per point (docs/benchmarks.md), so this is about 10 GB.
inline constexpr size_t kDefaultMaxPoints = 10'000'000;

struct FitCommandOptions {
  std::string input;
  std::string output;
  std::string report;  // empty: none
  std::string units = "unitless";
  bool no_features = false;
  bool keep_points = false;  // store the points and their parameters in the .tbs
  // Scans without parameters:
  int component = 0;             // the mesh component to fit (1 = largest); 0: the largest
  bool all_components = false;   // fit every component, to OUT-K.tbs
  std::string flatten = "auto";  // auto, lscm or mean-value
  size_t min_points = 5000;      // subdivide coarser meshes when their vertices are not enough
  size_t max_points = kDefaultMaxPoints;  // larger scans are refused before they are read
  // Memory limit in bytes for the fit (FitOptions::max_memory); 0: the memory available when
  // the command starts (available_memory()).
  uint64_t max_memory = 0;
  bool quiet = false;
  // A fit whose surface folds (FitReport::folds): "warn" writes it with a warning, "strict"
  // refuses it (exit 3, nothing written).
  std::string no_folds = "warn";
  std::vector<std::string> exports;  // files to convert the result to, as `tbs convert` does
  FitOptions fit;  // the library's defaults are the command's defaults
};
int run_fit(const FitCommandOptions& o);

// Bytes of memory this process can still use: MemAvailable of /proc/meminfo, or less when a
// cgroup (a container, a systemd slice) limits it. 0 when neither can be read.
uint64_t available_memory();

struct ConvertOptions {
  std::string input;
  std::string output;
  std::string format;        // empty: from the output's extension
  std::string faces = "regions";  // CAD: regions, triangles or exact
  bool exact = false;        // --exact: the same as --faces exact
  int face_degree = 5;       // region faces: degree in u and v
  long max_poles = 20'000;   // region faces: most poles per face
  int patch_degree = 0;      // triangle patches: 0 for spline degree + 2
  double cad_tolerance = 0;  // relative to the model size; 0: 1/20 of the fit's (or 1e-5)
  double angle_tolerance = 1.0;
  long max_patches = 50'000;
  std::string schema = "ap214";
  std::string triangle_patch = "quads";
  std::string units;         // empty: the .tbs units (mm when unitless)
  std::string product_name;  // empty: the output's file name without extension
  std::string points;        // error maps and heat maps: the scan with parameters (empty: the .tbs's own)
  std::string color_by = "none";
  size_t max_points = kDefaultMaxPoints;  // --points scans with more points are refused
  // Points given in memory (tbs fit --export with computed parameters), used before `points`.
  std::vector<Point3> point_positions;
  std::vector<Point2> point_uv;  // meshes (glb, gltf): "error" adds a COLOR_0 heat map
  int width = 512;           // error maps: pixels across u
  std::string measure = "parameter";
  int resolution = 0;        // meshes: uniform resolution; 0 = adaptive
  double chordal_tolerance = 1e-4;
  std::string report;        // --report: the conversion report as JSON (empty: none)
  int threads = 0;
  bool quiet = false;
};
int run_convert(const ConvertOptions& o);

/// The format `tbs convert` writes for this output path. \throw InvalidInput if none.
std::string convert_format(const std::string& output, const std::string& format = "");

}  // namespace tbs::cli
