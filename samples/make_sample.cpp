// Writes the bundled sample spline: a wavy sheet, 200 x 100 mm, with a hole and a crease.
//   tbs_make_sample OUT.tbs [DEGREE]
// The domain is a 16 x 8 grid over [0,2] x [0,1] with a rectangular hole; the vertical grid
// line u = 0.75 carries feature edges. Control points sample a height field with a kink along
// that line at the blossom points (METHOD.md section 3), so the surface follows the field and
// keeps the kink as a C^0 crease.

#include <tbs/io.h>
#include <tbs/knots.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: tbs_make_sample OUT.tbs [DEGREE]\n");
    return 2;
  }
  const int degree = argc > 2 ? std::stoi(argv[2]) : 3;
  const int nx = 16, ny = 8;
  auto inside_hole = [](int i, int j) { return i >= 10 && i < 13 && j >= 3 && j < 5; };
  std::vector<int> id((nx + 1) * (ny + 1), -1);
  std::vector<tbs::Point2> verts;
  std::vector<std::array<int, 3>> tris;
  auto vid = [&](int i, int j) {
    int& v = id[j * (nx + 1) + i];
    if (v < 0) {
      v = static_cast<int>(verts.size());
      verts.emplace_back(2.0 * i / nx, 1.0 * j / ny);
    }
    return v;
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (inside_hole(i, j)) continue;
      const int a = vid(i, j), b = vid(i + 1, j), c = vid(i + 1, j + 1), d = vid(i, j + 1);
      if ((i + j) % 2 == 0) {
        tris.push_back({a, b, c});
        tris.push_back({a, c, d});
      } else {
        tris.push_back({a, b, d});
        tris.push_back({b, c, d});
      }
    }
  std::vector<std::array<int, 2>> features;
  for (int j = 0; j < ny; ++j) features.push_back({vid(6, j), vid(6, j + 1)});

  tbs::Domain domain(verts, tris, features);
  auto knots = tbs::default_knots(domain, degree);
  tbs::Spline s = tbs::Spline::with_canonical_map(degree, std::move(domain), std::move(knots));
  auto height = [](const tbs::Point2& p) {
    return 12.0 * std::sin(std::numbers::pi * p.x()) * std::cos(std::numbers::pi * p.y()) +
           25.0 * std::fabs(p.x() - 0.75);
  };
  const int nb = tbs::beta_count(degree);
  for (int t = 0; t < s.domain().triangle_count(); ++t)
    for (int i = 0; i < nb; ++i) {
      const tbs::Beta b = tbs::beta_at(degree, i);
      const tbs::Point2 q = s.blossom_point(t, b);
      s.control_points()[s.control_point_index(t, i)] = {100.0 * q.x(), 100.0 * q.y(), height(q)};
    }
  tbs::SplineFile f{std::move(s), "mm",
                    R"({"source":"samples/make_sample.cpp","description":"wavy sheet with a hole and a crease along u = 0.75"})"};
  tbs::write_tbs(argv[1], f);
  return 0;
}
