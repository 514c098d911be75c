#include "random_spline.h"

#include <tbs/knots.h>
#include <tbs/predicates.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace tbs::test {

Domain grid_domain(const GridOptions& o, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const double hx = 1.0 / o.nx, hy = 1.0 / o.ny;
  auto in_hole = [&](int i, int j) {
    return o.hole && i >= o.nx / 4 + 1 && i < o.nx - o.nx / 4 - 1 && j >= o.ny / 4 + 1 &&
           j < o.ny - o.ny / 4 - 1;
  };
  std::vector<int> id((o.nx + 1) * (o.ny + 1), -1);
  std::vector<Point2> verts;
  auto vid = [&](int i, int j) {
    int& v = id[j * (o.nx + 1) + i];
    if (v >= 0) return v;
    Point2 p(i * hx, j * hy);
    const bool boundary = i == 0 || j == 0 || i == o.nx || j == o.ny;
    const bool feature = i == o.feature_column;
    // Vertices next to the hole stay on the grid so the hole stays a clean rectangle.
    bool near_hole = false;
    for (int a = -1; a <= 0; ++a)
      for (int b = -1; b <= 0; ++b) near_hole = near_hole || in_hole(i + a, j + b);
    if (!boundary && !near_hole) {
      if (feature) {
        if (o.feature_kink) p.x() += (j % 2 ? 0.3 : -0.3) * hx;
        p.y() += o.jitter * hy * uni(rng);
      } else {
        // y first: the order GCC evaluated the arguments in when these fixtures were made,
        // written out so that every compiler builds the same domains.
        const double dy = o.jitter * hy * uni(rng);
        p += Point2(o.jitter * hx * uni(rng), dy);
      }
    }
    v = static_cast<int>(verts.size());
    verts.push_back(dyadic(p));
    return v;
  };
  std::vector<std::array<int, 3>> tris;
  for (int j = 0; j < o.ny; ++j)
    for (int i = 0; i < o.nx; ++i) {
      if (in_hole(i, j)) continue;
      const int a = vid(i, j), b = vid(i + 1, j), c = vid(i + 1, j + 1), d = vid(i, j + 1);
      if ((i + j + static_cast<int>(seed)) % 2 == 0) {
        tris.push_back({a, b, c});
        tris.push_back({a, c, d});
      } else {
        tris.push_back({a, b, d});
        tris.push_back({b, c, d});
      }
    }
  std::vector<std::array<int, 2>> features;
  if (o.feature_column > 0 && o.feature_column < o.nx)
    for (int j = 0; j < o.ny; ++j)
      features.push_back({vid(o.feature_column, j), vid(o.feature_column, j + 1)});
  return Domain(verts, tris, features);
}

std::vector<Point2> random_knots(const Domain& d, int n, uint64_t seed) {
  std::mt19937_64 rng(seed * 7919 + 17);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const auto server = feature_servers(d);
  std::vector<Point2> knots(static_cast<size_t>(d.vertex_count()) * (n + 1));
  for (int v = 0; v < d.vertex_count(); ++v) {
    const Point2 p = d.vertex(v);
    double r = 1e300;
    for (int t : d.vertex_triangles(v)) {
      const auto& tri = d.triangle(t);
      const int k = tri[0] == v ? 0 : (tri[1] == v ? 1 : 2);
      const Point2& a = d.vertex(tri[(k + 1) % 3]);
      const Point2& b = d.vertex(tri[(k + 2) % 3]);
      r = std::min(r, 0.5 * std::fabs(det3(p, a, b)) / (b - a).norm());
    }
    double mid = 0, half = std::numbers::pi;
    if (d.is_boundary_vertex(v)) {
      const Vector2 ein = (p - d.vertex(d.boundary_prev(v))).normalized();
      const Vector2 eout = (d.vertex(d.boundary_next(v)) - p).normalized();
      const Vector2 rin(ein.y(), -ein.x()), rout(eout.y(), -eout.x());
      const Vector2 bis = rin + rout;
      mid = std::atan2(bis.y(), bis.x());
      half = 0.5 * (std::numbers::pi - std::acos(std::clamp(rin.dot(rout), -1.0, 1.0)));
    }
    knots[static_cast<size_t>(v) * (n + 1)] = p;
    std::vector<double> along;
    for (int k = 1; k < n; ++k) along.push_back(0.15 + 0.7 * uni(rng));
    std::sort(along.begin(), along.end());
    for (int k = 1; k <= n; ++k) {
      Point2 q;
      if (server[v] >= 0 && k < n) {
        Vector2 dir = (d.vertex(server[v]) - p).normalized();
        if (d.is_boundary_vertex(v)) dir = -dir;
        q = p + along[k - 1] * r * dir;
        // Keep it exactly on the feature line: interpolate between dyadic endpoints.
        const Point2 far = d.is_boundary_vertex(v) ? Point2(2 * p - d.vertex(server[v])) : d.vertex(server[v]);
        const double s = std::ldexp(std::round(std::ldexp((q - p).norm() / (far - p).norm(), 8)), -8);
        q = p + s * (far - p);
      } else {
        const double ang = mid + (d.is_boundary_vertex(v) ? 0.85 * half * (2 * uni(rng) - 1)
                                                          : 2 * std::numbers::pi * uni(rng));
        const double dist = r * (0.2 + 0.7 * uni(rng));
        q = dyadic(p + dist * Vector2(std::cos(ang), std::sin(ang)));
      }
      knots[static_cast<size_t>(v) * (n + 1) + k] = q;
    }
  }
  const KnotCheck check = check_knot_conditions(d, n, knots);
  if (!check.ok()) {
    ADD_FAILURE() << "random_knots produced invalid knots:\n" << check.summary();
    throw std::runtime_error("invalid random knots");
  }
  return knots;
}

Spline random_spline(int degree, const GridOptions& o, uint64_t seed) {
  Domain d = grid_domain(o, seed);
  auto knots = random_knots(d, degree, seed);
  Spline s = Spline::with_canonical_map(degree, std::move(d), std::move(knots));
  std::mt19937_64 rng(seed + 99);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  // Drawn z, y, x: the order GCC evaluated the constructor arguments in when these fixtures
  // were made; written out so that every compiler builds the same splines.
  for (auto& c : s.control_points()) {
    const double z = uni(rng), y = uni(rng);
    c = Point3(uni(rng), y, z);
  }
  return s;
}

std::vector<Point2> random_domain_points(const Domain& d, size_t count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::uniform_int_distribution<int> pick(0, d.triangle_count() - 1);
  std::vector<Point2> pts;
  pts.reserve(count);
  while (pts.size() < count) {
    const auto& tri = d.triangle(pick(rng));
    double a = uni(rng), b = uni(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    pts.push_back(d.vertex(tri[0]) + a * (d.vertex(tri[1]) - d.vertex(tri[0])) +
                  b * (d.vertex(tri[2]) - d.vertex(tri[0])));
  }
  return pts;
}

std::vector<Point2> special_points(const Spline& s, const Evaluator& ev, size_t max_count) {
  const Domain& d = s.domain();
  const int n = s.degree();
  std::vector<Point2> pts;
  auto add = [&](const Point2& p) {
    if (pts.size() < max_count && ev.locate(p) >= 0) pts.push_back(p);
  };
  for (const auto& v : d.vertices()) add(v);
  for (const auto& e : d.edges()) {
    const Point2 &a = d.vertex(e[0]), &b = d.vertex(e[1]);
    add(0.5 * (a + b));
    add(0.25 * (3 * a + b));
  }
  for (int t = 0; t < d.triangle_count() && pts.size() < max_count; ++t) {
    std::vector<Point2> k;
    for (int v : d.triangle(t))
      for (int l = 0; l <= n; ++l) k.push_back(s.knot(v, l));
    for (size_t i = 0; i < k.size(); ++i) {
      add(k[i]);
      for (size_t j = i + 1; j < k.size(); ++j) {
        add(0.5 * (k[i] + k[j]));
        add(0.25 * (3 * k[i] + k[j]));
      }
    }
  }
  return pts;
}

Eigen::Matrix<double, 3, 2> knot_derivative_fd(const Spline& s, const Point2& u, int v, int l,
                                               double h) {
  Eigen::Matrix<double, 3, 2> r;
  for (int col = 0; col < 2; ++col) {
    const Vector2 dir = col == 0 ? Vector2(1, 0) : Vector2(0, 1);
    Spline plus = s, minus = s;
    plus.set_knot(v, l, s.knot(v, l) + h * dir);
    minus.set_knot(v, l, s.knot(v, l) - h * dir);
    const Evaluator ep(plus), em(minus);
    r.col(col) = (ep.value(u) - em.value(u)) / (2 * h);
  }
  return r;
}

}  // namespace tbs::test
