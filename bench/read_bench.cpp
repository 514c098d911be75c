// Scan reading: seconds and peak memory of read_scan() alone, per point, for the large-input
// rows of docs/benchmarks.md (issue 20: at most 32 bytes a point while reading, beyond the
// points' own arrays).
//   build/bench/tbs_read_bench SCAN...
// Prints one Markdown row per file: points, file MB, seconds, M points/s, peak resident MB
// (of the process, the program itself included: compare with an empty run), bytes per point
// of the peak over the resident memory before reading, and the bytes per point the Scan's
// arrays hold.

#include <tbs/scan.h>

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

// Resident memory now (VmRSS) and at its peak (VmHWM), in bytes, from /proc/self/status.
std::pair<double, double> resident() {
  std::ifstream f("/proc/self/status");
  std::string key;
  double now = 0, peak = 0;
  while (f >> key) {
    double kb = 0;
    if (key == "VmRSS:" && f >> kb) now = kb * 1024;
    if (key == "VmHWM:" && f >> kb) peak = kb * 1024;
    f.ignore(1 << 20, '\n');
  }
  return {now, peak};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SCAN...\n", argv[0]);
    return 2;
  }
  std::printf("| file | points | file MB | read s | M points/s | peak MB | peak over start, bytes per point | "
              "arrays, bytes per point |\n|---|---|---|---|---|---|---|---|\n");
  for (int i = 1; i < argc; ++i) {
    const auto [start, start_peak] = resident();
    const auto t0 = std::chrono::steady_clock::now();
    double arrays = 0, n = 0;
    {
      const tbs::Scan s = tbs::read_scan(argv[i]);
      n = static_cast<double>(s.positions.size());
      arrays = static_cast<double>(s.positions.capacity() * sizeof(s.positions[0]) +
                                   s.normals.capacity() * sizeof(s.normals[0]) + s.uv.capacity() * sizeof(s.uv[0]) +
                                   s.triangles.capacity() * sizeof(s.triangles[0]));
    }
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto [now, peak] = resident();
    (void)now;
    (void)start_peak;
    const double mb = static_cast<double>(std::filesystem::file_size(argv[i])) / (1 << 20);
    std::printf("| %s | %.0f | %.0f | %.2f | %.2f | %.0f | %.1f | %.1f |\n",
                std::filesystem::path(argv[i]).filename().c_str(), n, mb, sec, n / sec / 1e6, peak / (1 << 20),
                (peak - start) / n, arrays / n);
  }
  return 0;
}
