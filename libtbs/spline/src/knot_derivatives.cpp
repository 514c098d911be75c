// Derivatives of the surface with respect to one knot (knot_derivatives.h), through the
// reference evaluator.

#include <tbs/errors.h>
#include <tbs/knot_derivatives.h>
#include <tbs/reference.h>

#include <cmath>
#include <vector>

namespace tbs {

Eigen::Matrix<double, 3, 2> knot_derivative(const Spline& s, const Perturbation& p, int vertex,
                                            int level) {
  const int n = s.degree();
  const Domain& d = s.domain();
  if (vertex < 0 || vertex >= d.vertex_count())
    throw InvalidInput("knot_derivative: vertex " + std::to_string(vertex) + " out of range");
  if (level < 0 || level >= n)
    throw InvalidInput("knot_derivative: level " + std::to_string(level) +
                       " is not a free knot (0 to " + std::to_string(n - 1) + ")");
  const Point2 t = s.knot(vertex, level);
  const Point2& u = p.u;
  const Vector2 dirs[2] = {Vector2(1, 0), Vector2(0, 1)};
  Eigen::Matrix<double, 3, 2> result = Eigen::Matrix<double, 3, 2>::Zero();

  for (int tri_id : d.vertex_triangles(vertex)) {
    const auto& tri = d.triangle(tri_id);
    const int k = tri[0] == vertex ? 0 : (tri[1] == vertex ? 1 : 2);
    for (int i = 0; i < beta_count(n - 1); ++i) {
      const Beta g = beta_at(n - 1, i);
      if (g[k] < level) continue;  // t is neither in V_{I,g} nor in X_{I,g}
      std::vector<Point2> v;
      int pos_t = -1;
      for (int j = 0; j < 3; ++j)
        for (int l = 0; l <= g[j]; ++l) {
          if (j == k && l == level) pos_t = static_cast<int>(v.size());
          v.push_back(s.knot(tri[j], l));
        }
      const std::array<Point2, 3> x{s.knot(tri[0], g[0]), s.knot(tri[1], g[1]), s.knot(tri[2], g[2])};
      std::array<Point3, 3> c;
      for (int j = 0; j < 3; ++j) {
        Beta h = g;
        ++h[j];
        c[j] = s.control_points()[s.control_point_index(tri_id, h)];
      }
      Vector3 P = Vector3::Zero();
      for (int j = 0; j < 3; ++j) {
        auto y = x;
        y[j] = u;
        P += det3(y[0], y[1], y[2]) * c[j];
      }
      const double m = reference::simplex_spline(v, p);

      // Split set containing t: t and the pair of other knots spanning the largest triangle.
      int a = -1, b = -1;
      double best = 0;
      for (int q = 0; q < static_cast<int>(v.size()); ++q)
        for (int r = q + 1; r < static_cast<int>(v.size()); ++r) {
          if (q == pos_t || r == pos_t) continue;
          const double area = std::fabs(det3(t, v[q], v[r]));
          if (area > best) best = area, a = q, b = r;
        }
      double ma = 0, mb = 0;
      double dw = 0;
      if (a >= 0 && orientation(t, v[a], v[b]) != 0) {
        dw = det3(t, v[a], v[b]);
        auto swap_in = [&](int skip) {
          std::vector<Point2> w = v;
          w[skip] = t;  // V + {t} - {v[skip]}
          return reference::simplex_spline(w, p);
        };
        ma = swap_in(a);
        mb = swap_in(b);
      }

      for (int col = 0; col < 2; ++col) {
        const Vector2& dir = dirs[col];
        Vector3 term = Vector3::Zero();
        // Derivative of P through X (only when X contains t): d(Y) with Y = X[j <- u] for j != k
        // changes with y_k = t by dir x (y_{k+1} - y_{k+2}).
        if (g[k] == level && m != 0) {
          for (int j = 0; j < 3; ++j) {
            if (j == k) continue;
            auto y = x;
            y[j] = u;
            const Vector2 e = y[(k + 1) % 3] - y[(k + 2) % 3];
            term += (dir.x() * e.y() - dir.y() * e.x()) * m * c[j];
          }
        }
        // Derivative of M(u | V): -(mu_t M(V) + mu_a M(V+t-a) + mu_b M(V+t-b)).
        if (dw != 0) {
          const Point2 o = Point2::Zero();
          const double mu_t = (det3(o + dir, v[a], v[b]) - det3(o, v[a], v[b])) / dw;
          const double mu_a = (det3(t, o + dir, v[b]) - det3(t, o, v[b])) / dw;
          const double mu_b = (det3(t, v[a], o + dir) - det3(t, v[a], o)) / dw;
          term -= (mu_t * m + mu_a * ma + mu_b * mb) * P;
        }
        result.col(col) += term;
      }
    }
  }
  return result;
}

}  // namespace tbs
