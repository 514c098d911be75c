// Smoothness across domain edges and knot lines, compared through one-sided derivatives: the
// perturbation rule evaluates the polynomial piece on either side at the very same point.

#include <tbs/evaluator.h>
#include <tbs/knots.h>
#include <tbs/reference.h>

#include "random_spline.h"

#include <gtest/gtest.h>

namespace tbs {
namespace {

// D^k F at u from the side the unit vector `side` points to, along the direction sequence.
Vector3 one_sided(const Spline& s, const Point2& u, const Vector2& side, const Vector2& along,
                  const std::vector<Vector2>& dirs) {
  const Perturbation p = Perturbation::toward(u, u + 1e-3 * side, u + 1e-3 * along);
  return reference::derivative(s, dirs, p);
}

// All direction sequences of length k from {normal, tangent}.
std::vector<std::vector<Vector2>> sequences(int k, const Vector2& nrm, const Vector2& tan) {
  std::vector<std::vector<Vector2>> out{{}};
  for (int i = 0; i < k; ++i) {
    std::vector<std::vector<Vector2>> next;
    for (const auto& s : out)
      for (const Vector2& d : {nrm, tan}) {
        auto t = s;
        t.push_back(d);
        next.push_back(t);
      }
    out = next;
  }
  return out;
}

// Largest relative jump of derivatives of order 0..max_order across the line through u with
// direction `tan`.
std::vector<double> jumps(const Spline& s, const Point2& u, const Vector2& tan, int max_order) {
  const Vector2 t = tan.normalized();
  const Vector2 nrm(-t.y(), t.x());
  std::vector<double> out;
  for (int k = 0; k <= max_order; ++k) {
    double worst = 0;
    for (const auto& seq : sequences(k, nrm, t)) {
      const Vector3 a = one_sided(s, u, nrm, t, seq);
      const Vector3 b = one_sided(s, u, -nrm, t, seq);
      worst = std::max(worst, (a - b).norm() / (1 + a.norm() + b.norm()));
    }
    out.push_back(worst);
  }
  return out;
}

class Smoothness : public ::testing::TestWithParam<int> {};

TEST_P(Smoothness, DerivativesUpToOrderNMinus1AgreeAcrossEdgesAndKnotLines) {
  const int n = GetParam();
  test::GridOptions o;
  o.nx = o.ny = 3;
  const Spline s = test::random_spline(n, o, 21);
  const Domain& d = s.domain();
  const Evaluator ev(s);
  double max_smooth = 0, max_order_n = 0;
  int lines = 0;
  // Interior domain edges.
  for (int e = 0; e < d.edge_count(); ++e) {
    if (d.is_boundary_edge(e)) continue;
    const Point2 a = d.vertex(d.edges()[e][0]), b = d.vertex(d.edges()[e][1]);
    const auto j = jumps(s, 0.5 * (a + b), b - a, n);
    for (int k = 0; k < n; ++k) max_smooth = std::max(max_smooth, j[k]);
    max_order_n = std::max(max_order_n, j[n]);
    ++lines;
  }
  // Knot lines inside triangles: segments between sub-knots of different vertices.
  for (int t = 0; t < d.triangle_count(); t += 3) {
    const auto& tri = d.triangle(t);
    for (int l = 0; l < n; ++l) {
      // t_{i0,l} and t_{i1,n-1-l} are both in V_{I,(l, n-1-l, 0)}: a knot line.
      const Point2 a = s.knot(tri[0], l), b = s.knot(tri[1], n - 1 - l);
      const Point2 u = 0.5 * (a + b);
      if (ev.locate(u) < 0) continue;
      const auto j = jumps(s, u, b - a, n - 1);
      for (int k = 0; k < n; ++k) max_smooth = std::max(max_smooth, j[k]);
      ++lines;
    }
  }
  EXPECT_GT(lines, 20);
  EXPECT_LT(max_smooth, 1e-8) << "C^" << n - 1 << " violated";
  // The test can fail: order n does jump somewhere (the pieces are different polynomials).
  EXPECT_GT(max_order_n, 1e-6);
}

TEST_P(Smoothness, FeatureEdgesAreC0WithANormalJump) {
  const int n = GetParam();
  for (bool kink : {false, true}) {
    test::GridOptions o;
    o.nx = o.ny = 4;
    o.feature_column = 2;
    o.feature_kink = kink;
    const Spline s = test::random_spline(n, o, 22);
    const Domain& d = s.domain();
    const auto cont = edge_continuity(d, n, s.knots());
    int features = 0;
    // The normal jump is a polynomial along the edge and may vanish at isolated points:
    // require it somewhere on every feature edge.
    double max_value_jump = 0, min_normal_angle = 10;
    for (int e = 0; e < d.edge_count(); ++e) {
      if (!d.is_feature_edge(e)) continue;
      EXPECT_EQ(cont[e], 0);
      const Point2 a = d.vertex(d.edges()[e][0]), b = d.vertex(d.edges()[e][1]);
      double edge_angle = 0;
      for (double f : {0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875}) {
        const Point2 u = a + f * (b - a);
        const Vector2 t = (b - a).normalized(), nrm(-t.y(), t.x());
        const Vector3 pa = one_sided(s, u, nrm, t, {}), pb = one_sided(s, u, -nrm, t, {});
        max_value_jump = std::max(max_value_jump, (pa - pb).norm());
        auto normal = [&](const Vector2& side) {
          const Vector3 fu = one_sided(s, u, side, t, {Vector2(1, 0)});
          const Vector3 fv = one_sided(s, u, side, t, {Vector2(0, 1)});
          return Vector3(fu.cross(fv).normalized());
        };
        const double angle = std::acos(std::clamp(normal(nrm).dot(normal(-nrm)), -1.0, 1.0));
        edge_angle = std::max(edge_angle, angle);
      }
      min_normal_angle = std::min(min_normal_angle, edge_angle);
      ++features;
    }
    EXPECT_GT(features, 2);
    EXPECT_LT(max_value_jump, 1e-12) << "kink " << kink;
    EXPECT_GT(min_normal_angle, 1e-3) << "kink " << kink;
  }
}

INSTANTIATE_TEST_SUITE_P(Degrees, Smoothness, ::testing::Values(2, 3, 4, 5));

}  // namespace
}  // namespace tbs
