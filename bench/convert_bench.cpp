// Converter figures for docs/benchmarks.md: exact Bezier extraction (time, pieces per domain
// triangle) and compact CAD patches (time, patches per triangle, deviations) for .tbs files.
//
//   tbs_convert_bench FILE.tbs [FILE.tbs ...] [--cad-degrees 3,4,5] [--cad-tolerance 1e-6]

#include <tbs/cad_patches.h>
#include <tbs/extract.h>
#include <tbs/io.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> files;
  std::vector<int> degrees;
  double tolerance = 1e-6;
  bool extract = true;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--cad-degrees" && i + 1 < argc) {
      std::stringstream ss(argv[++i]);
      for (std::string d; std::getline(ss, d, ',');) degrees.push_back(std::stoi(d));
    } else if (a == "--cad-tolerance" && i + 1 < argc) {
      tolerance = std::stod(argv[++i]);
    } else if (a == "--no-extract") {
      extract = false;
    } else {
      files.push_back(a);
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: tbs_convert_bench FILE.tbs... [--cad-degrees 3,4,5] [--cad-tolerance T] [--no-extract]\n");
    return 2;
  }
  if (extract) {
    std::printf("| file | degree | domain triangles | pieces | pieces per triangle (mean / max) | cells per triangle (mean / max) | time (s) |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    for (const auto& f : files) {
      const tbs::SplineFile sf = tbs::read_tbs(f);
      const auto t0 = std::chrono::steady_clock::now();
      const tbs::Extraction x = tbs::extract_bezier(sf.spline);
      const double sec = seconds_since(t0);
      const int nt = sf.spline.domain().triangle_count();
      int max_pieces = 0, max_cells = 0;
      long cells = 0;
      for (int t = 0; t < nt; ++t) {
        max_pieces = std::max(max_pieces, x.piece_start[t + 1] - x.piece_start[t]);
        max_cells = std::max(max_cells, x.cells[t]);
        cells += x.cells[t];
      }
      std::printf("| %s | %d | %d | %zu | %.1f / %d | %.1f / %d | %.2f |\n", f.c_str(),
                  sf.spline.degree(), nt, x.pieces.size(), double(x.pieces.size()) / nt, max_pieces,
                  double(cells) / nt, max_cells, sec);
      std::fflush(stdout);
    }
  }
  if (!degrees.empty()) {
    std::printf("\n| file | spline degree | patch degree | domain triangles | patches | patches per triangle (mean / max) | max deviation / tolerance | max normal deviation (deg) | within | time (s) |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
    for (const auto& f : files) {
      const tbs::SplineFile sf = tbs::read_tbs(f);
      for (int m : degrees) {
        if (m != 0 && m < sf.spline.degree()) continue;
        const auto t0 = std::chrono::steady_clock::now();
        const tbs::CadPatches c = tbs::make_cad_patches(sf.spline, {.degree = m, .tolerance = tolerance});
        const double sec = seconds_since(t0);
        const int nt = sf.spline.domain().triangle_count();
        int max_patches = 0;
        for (int t = 0; t < nt; ++t) max_patches = std::max(max_patches, c.patch_start[t + 1] - c.patch_start[t]);
        std::printf("| %s | %d | %d | %d | %zu | %.1f / %d | %.2f | %.3f | %s | %.2f |\n", f.c_str(),
                    sf.spline.degree(), m, nt, c.patches.size(), double(c.patches.size()) / nt, max_patches,
                    c.max_position_deviation / c.tolerance, c.max_normal_deviation,
                    c.within_tolerance ? "yes" : "no", sec);
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
