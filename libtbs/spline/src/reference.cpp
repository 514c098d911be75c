// Plain-recursion evaluation of simplex splines and of the surface (reference.h): the
// independent computation the Evaluator is tested against.

#include <tbs/reference.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace tbs::reference {
namespace {

// Picks a split set W = (w0, w1, w2) of positions in `k`: w0 = the first knot, w1 = the knot
// farthest from it, w2 = the knot farthest from the line w0 w1. False if all are collinear.
bool choose_split(std::span<const Point2> k, std::array<int, 3>& w) {
  w = {0, 0, 0};
  double best = -1;
  for (int i = 1; i < static_cast<int>(k.size()); ++i) {
    const double dist = (k[i] - k[0]).squaredNorm();
    if (dist > best) best = dist, w[1] = i;
  }
  best = -1;
  for (int i = 1; i < static_cast<int>(k.size()); ++i) {
    const double a = std::fabs(det3(k[w[0]], k[w[1]], k[i]));
    if (a > best && i != w[1]) best = a, w[2] = i;
  }
  if (w[1] == 0 || w[2] == 0) return false;
  return orientation(k[w[0]], k[w[1]], k[w[2]]) != 0;
}

std::vector<Point2> without(std::span<const Point2> k, int skip) {
  std::vector<Point2> r;
  r.reserve(k.size() - 1);
  for (int i = 0; i < static_cast<int>(k.size()); ++i)
    if (i != skip) r.push_back(k[i]);
  return r;
}

// Knot set V_{I,beta} (levels 0..b_j of each corner).
std::vector<Point2> knot_set(const Spline& s, int t, const Beta& b) {
  std::vector<Point2> v;
  const auto& tri = s.domain().triangle(t);
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k <= b[j]; ++k) v.push_back(s.knot(tri[j], k));
  return v;
}

}  // namespace

double simplex_spline(std::span<const Point2> k, const Perturbation& p) {
  return simplex_spline_derivative(k, {}, p);
}

double simplex_spline_derivative(std::span<const Point2> k, std::span<const Vector2> dirs,
                                 const Perturbation& p) {
  const int m = static_cast<int>(k.size()) - 3;
  // M vanishes outside the convex hull of its knots, so outside their closed bounding box.
  Box2 box;
  for (const auto& q : k) box.extend(q);
  if (!box.contains(p.u)) return 0.0;
  if (m == 0) {
    if (!dirs.empty()) return 0.0;
    const double d = det3(k[0], k[1], k[2]);
    if (orientation(k[0], k[1], k[2]) == 0) return 0.0;
    return half_open_contains(k[0], k[1], k[2], p) ? 1.0 / std::fabs(d) : 0.0;
  }
  std::array<int, 3> w;
  if (!choose_split(k, w)) return 0.0;
  const Point2 &w0 = k[w[0]], &w1 = k[w[1]], &w2 = k[w[2]];
  const double d = det3(w0, w1, w2);
  std::array<double, 3> coef;
  if (dirs.empty()) {
    // Barycentric coordinates of u with respect to W.
    coef = {det3(p.u, w1, w2) / d, det3(w0, p.u, w2) / d, det3(w0, w1, p.u) / d};
  } else {
    // Coordinates of the vector v: mu_j with sum 0 and sum mu_j w_j = v.
    const Vector2& v = dirs[0];
    const Point2 o = Point2::Zero();
    coef = {(det3(o + v, w1, w2) - det3(o, w1, w2)) / d, (det3(w0, o + v, w2) - det3(w0, o, w2)) / d,
            (det3(w0, w1, o + v) - det3(w0, w1, o)) / d};
    for (double& c : coef) c *= m;
  }
  const auto rest = dirs.empty() ? dirs : dirs.subspan(1);
  double sum = 0;
  for (int j = 0; j < 3; ++j) {
    if (coef[j] == 0) continue;
    const auto child = without(k, w[j]);
    sum += coef[j] * simplex_spline_derivative(child, rest, p);
  }
  return sum;
}

double basis_degree_n(const Spline& s, int t, const Beta& b, const Perturbation& p) {
  const auto& tri = s.domain().triangle(t);
  const double d = det3(s.knot(tri[0], b[0]), s.knot(tri[1], b[1]), s.knot(tri[2], b[2]));
  const auto v = knot_set(s, t, b);
  return std::fabs(d) * simplex_spline(v, p);
}

Point3 value_degree_n(const Spline& s, const Perturbation& p) {
  Point3 f = Point3::Zero();
  const int n = s.degree();
  for (int t = 0; t < s.domain().triangle_count(); ++t)
    for (int i = 0; i < beta_count(n); ++i) {
      const double nb = basis_degree_n(s, t, beta_at(n, i), p);
      if (nb != 0) f += nb * s.control_points()[s.control_point_index(t, i)];
    }
  return f;
}

Vector3 derivative(const Spline& s, std::span<const Vector2> dirs, const Perturbation& p) {
  const int n = s.degree();
  const int k = static_cast<int>(dirs.size());
  Vector3 f = Vector3::Zero();
  for (int t = 0; t < s.domain().triangle_count(); ++t) {
    const auto& tri = s.domain().triangle(t);
    for (int i = 0; i < beta_count(n - 1); ++i) {
      const Beta g = beta_at(n - 1, i);
      const auto v = knot_set(s, t, g);
      const std::array<Point2, 3> x{s.knot(tri[0], g[0]), s.knot(tri[1], g[1]), s.knot(tri[2], g[2])};
      std::array<Point3, 3> c;
      for (int j = 0; j < 3; ++j) {
        Beta h = g;
        ++h[j];
        c[j] = s.control_points()[s.control_point_index(t, h)];
      }
      // P(u) = sum_j d(X[j <- u]) c_j is affine in u; D_w P = sum_j (d(X[j <- w]) - d(X[j <- 0])) c_j.
      auto P = [&](const Point2& u) {
        Vector3 r = Vector3::Zero();
        for (int j = 0; j < 3; ++j) {
          auto y = x;
          y[j] = u;
          r += det3(y[0], y[1], y[2]) * c[j];
        }
        return r;
      };
      const Vector3 p0 = P(Point2::Zero());
      Vector3 term = P(p.u) * simplex_spline_derivative(v, dirs, p);
      for (int q = 0; q < k; ++q) {
        std::vector<Vector2> rest;
        for (int r = 0; r < k; ++r)
          if (r != q) rest.push_back(dirs[r]);
        const double m = simplex_spline_derivative(v, rest, p);
        if (m != 0) term += (P(dirs[q]) - p0) * m;
      }
      f += term;
    }
  }
  return f;
}

}  // namespace tbs::reference
