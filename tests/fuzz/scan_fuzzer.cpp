// libFuzzer harness for one scan reader (tbs::read_scan). TBS_FUZZ_EXTENSION (".ply", ".obj",
// ".off", ".stl" or ".xyz") picks the reader: the readers take a path, so each input is written
// to a private temporary file with that extension first.
//
// A reader may accept the bytes or throw tbs::InvalidInput / tbs::IoError; anything else (another
// exception, a crash, a sanitizer report, a scan that breaks the documented invariants) is a bug.

#include <tbs/errors.h>
#include <tbs/scan.h>

#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#ifndef TBS_FUZZ_EXTENSION
#error "define TBS_FUZZ_EXTENSION"
#endif

namespace {

const std::string& scratch_path() {
  static const std::string path =
      (std::filesystem::temp_directory_path() /
       ("tbs-fuzz-" + std::to_string(::getpid()) + TBS_FUZZ_EXTENSION))
          .string();
  return path;
}

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "scan_fuzzer: accepted scan breaks an invariant: %s\n", what);
    std::abort();
  }
}

// TBS_FUZZ_VERBOSE=1: say whether each input was accepted, or refused and why (for triage).
bool verbose() {
  static const bool on = std::getenv("TBS_FUZZ_VERBOSE") != nullptr;
  return on;
}

bool finite_within(const auto& v, double bound) {
  for (int i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]) || std::abs(v[i]) > bound) return false;
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = scratch_path();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out) {
      std::fprintf(stderr, "scan_fuzzer: cannot write %s\n", path.c_str());
      std::abort();
    }
  }
  tbs::ScanReadOptions options;
  options.max_points = 100'000;  // larger counts must be refused before allocating
  try {
    const tbs::Scan scan = tbs::read_scan(path, options);
    const size_t n = scan.positions.size();
    check(n > 0 && n <= options.max_points, "point count");
    check(scan.normals.empty() || scan.normals.size() == n, "normal count");
    check(scan.uv.empty() || scan.uv.size() == n, "uv count");
    for (const auto& p : scan.positions) check(finite_within(p, 1e30), "finite positions");
    for (const auto& q : scan.uv) check(finite_within(q, 1e30), "finite uv");
    for (const auto& m : scan.normals)
      check(finite_within(m, 1.0 + 1e-9) && std::abs(m.norm() - 1.0) < 1e-9, "unit normals");
    for (const auto& t : scan.triangles) {
      for (int c : t) check(c >= 0 && static_cast<size_t>(c) < n, "face index in range");
      check(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "no repeated corner");
    }
    if (verbose()) std::fprintf(stderr, "scan_fuzzer: accepted, %zu points, %zu triangles\n", n, scan.triangles.size());
  } catch (const tbs::InvalidInput& e) {
    if (verbose()) std::fprintf(stderr, "scan_fuzzer: refused: %s\n", e.what());
  } catch (const tbs::IoError& e) {
    if (verbose()) std::fprintf(stderr, "scan_fuzzer: refused: %s\n", e.what());
  }
  std::remove(path.c_str());
  return 0;
}
