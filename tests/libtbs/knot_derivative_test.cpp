#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/knot_derivatives.h>

#include "random_spline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace tbs {
namespace {

class KnotDerivative : public ::testing::TestWithParam<int> {};

TEST_P(KnotDerivative, MatchesCentralDifferencesForEveryFreeKnotLevel) {
  const int n = GetParam();
  test::GridOptions o;
  o.nx = o.ny = 4;
  const Spline s = test::random_spline(n, o, 31);
  const Domain& d = s.domain();
  const Evaluator ev(s);
  std::mt19937_64 rng(5);
  std::vector<double> ratios;
  int checked = 0;
  for (int v = 0; v < d.vertex_count(); ++v) {
    for (int level = 0; level < n; ++level) {
      if (level == 0 && d.is_boundary_vertex(v)) continue;  // moving it moves the boundary
      // Points in the triangles around v, where the knot's basis functions live.
      std::vector<Point2> pts;
      for (int t : d.vertex_triangles(v)) {
        const auto& tri = d.triangle(t);
        std::uniform_real_distribution<double> uni(0.05, 0.9);
        double a = uni(rng), b = uni(rng) * (1 - a);
        pts.push_back(d.vertex(tri[0]) + a * (d.vertex(tri[1]) - d.vertex(tri[0])) +
                      b * (d.vertex(tri[2]) - d.vertex(tri[0])));
      }
      for (const auto& u : pts) {
        const auto p = ev.perturbation(u);
        ASSERT_TRUE(p);
        const auto exact = knot_derivative(s, *p, v, level);
        const auto fd = test::knot_derivative_fd(s, u, v, level, 1e-7);
        ASSERT_LT((exact - fd).norm(), 1e-5 * (1 + exact.norm()))
            << "vertex " << v << " level " << level << " at " << u.transpose() << "\nexact\n"
            << exact << "\nfd\n" << fd;
        if (n >= 2) {
          const double e1 = (test::knot_derivative_fd(s, u, v, level, 2e-3) - exact).norm();
          const double e2 = (test::knot_derivative_fd(s, u, v, level, 1e-3) - exact).norm();
          if (e1 > 1e-9) ratios.push_back(e1 / e2);
        }
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 50);
  if (n >= 2) {
    ASSERT_GT(ratios.size(), 20u);
    std::nth_element(ratios.begin(), ratios.begin() + ratios.size() / 2, ratios.end());
    const double median = ratios[ratios.size() / 2];
    EXPECT_GT(median, 3.5) << "error should shrink like h^2";
    EXPECT_LT(median, 4.5);
  }
}

INSTANTIATE_TEST_SUITE_P(Degrees, KnotDerivative, ::testing::Values(1, 2, 3, 4));

TEST(KnotDerivative, RejectsTheLastKnotAndBadVertices) {
  test::GridOptions o;
  const Spline s = test::random_spline(3, o, 32);
  const Perturbation p = Perturbation::standard({0.4, 0.4});
  EXPECT_THROW(knot_derivative(s, p, 0, 3), InvalidInput);
  EXPECT_THROW(knot_derivative(s, p, -1, 0), InvalidInput);
  EXPECT_THROW(knot_derivative(s, p, s.domain().vertex_count(), 1), InvalidInput);
}

}  // namespace
}  // namespace tbs
