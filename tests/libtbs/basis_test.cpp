// Partition of unity, non-negativity, linear precision, and the degree n-1 form against the
// degree-n definition, on random valid knot clouds.

#include <tbs/evaluator.h>
#include <tbs/knots.h>
#include <tbs/reference.h>

#include "random_spline.h"

#include <gtest/gtest.h>

#include <random>

namespace tbs {
namespace {

struct Config {
  int degree;
  uint64_t seed;
  bool hole;
  int feature_column;
};

std::string name(const ::testing::TestParamInfo<Config>& i) {
  return "n" + std::to_string(i.param.degree) + "_seed" + std::to_string(i.param.seed) +
         (i.param.hole ? "_hole" : "") + (i.param.feature_column >= 0 ? "_feature" : "");
}

std::vector<Config> configs() {
  std::vector<Config> c;
  for (int n = 1; n <= 5; ++n)
    for (uint64_t seed = 1; seed <= 3; ++seed) c.push_back({n, seed, seed == 2, seed == 3 ? 3 : -1});
  return c;
}

test::GridOptions grid(const Config& c) {
  test::GridOptions o;
  o.nx = o.ny = c.hole ? 6 : 5;
  o.hole = c.hole;
  o.feature_column = c.feature_column;
  return o;
}

class Basis : public ::testing::TestWithParam<Config> {};

// The graph's basis rows: every control point's weight is >= 0 and they sum to 1.
void expect_partition(const Evaluator& ev, const std::vector<Point2>& pts, const char* what) {
  BasisRow row;
  int failures = 0;
  for (const auto& u : pts) {
    ASSERT_TRUE(ev.basis_row(u, row)) << what << " (" << u.x() << ", " << u.y() << ")";
    double sum = 0, sum_u = 0, sum_v = 0, min = 0;
    for (size_t k = 0; k < row.index.size(); ++k) {
      sum += row.value[k];
      sum_u += row.du[k];
      sum_v += row.dv[k];
      min = std::min(min, row.value[k]);
    }
    if (std::fabs(sum - 1) > 1e-10 || min < -1e-10 || std::fabs(sum_u) > 1e-8 ||
        std::fabs(sum_v) > 1e-8) {
      if (++failures < 5)
        ADD_FAILURE() << what << " at (" << u.x() << ", " << u.y() << "): sum " << sum - 1
                      << " min " << min << " d/du " << sum_u << " d/dv " << sum_v;
    }
  }
  EXPECT_EQ(failures, 0) << what;
}

TEST_P(Basis, PartitionOfUnityAtRandomPoints) {
  const Config c = GetParam();
  const Spline s = test::random_spline(c.degree, grid(c), c.seed);
  const Evaluator ev(s);
  expect_partition(ev, test::random_domain_points(s.domain(), 10000, c.seed), "random point");
}

TEST_P(Basis, PartitionOfUnityOnKnotLinesEdgesAndVertices) {
  const Config c = GetParam();
  const Spline s = test::random_spline(c.degree, grid(c), c.seed);
  const Evaluator ev(s);
  const auto pts = test::special_points(s, ev, 20000);
  ASSERT_GT(pts.size(), 500u);
  // The points really are on knot lines or edges: each is collinear with two knots.
  expect_partition(ev, pts, "special point");
}

// The degree-n definition (plain recursion, n+3 knots) gives non-negative basis functions
// that sum to 1, and per control point the same weights as the graph's degree n-1 form.
TEST_P(Basis, DegreeNDefinitionMatchesDegreeNMinus1Form) {
  const Config c = GetParam();
  const Spline s = test::random_spline(c.degree, grid(c), c.seed);
  const Evaluator ev(s);
  auto pts = test::random_domain_points(s.domain(), c.degree >= 5 ? 300 : 1000, c.seed + 5);
  const auto special = test::special_points(s, ev, c.degree >= 5 ? 300 : 1000);
  pts.insert(pts.end(), special.begin(), special.end());
  const int n = s.degree();
  BasisRow row;
  std::vector<double> weight(s.control_point_count());
  double worst = 0;
  for (const auto& u : pts) {
    const auto p = ev.perturbation(u);
    ASSERT_TRUE(p.has_value());
    std::fill(weight.begin(), weight.end(), 0.0);
    double sum = 0;
    for (int t = 0; t < s.domain().triangle_count(); ++t)
      for (int i = 0; i < beta_count(n); ++i) {
        const double b = reference::basis_degree_n(s, t, beta_at(n, i), *p);
        EXPECT_GE(b, -1e-12);
        sum += b;
        weight[s.control_point_index(t, i)] += b;
      }
    EXPECT_NEAR(sum, 1.0, 1e-10) << "(" << u.x() << ", " << u.y() << ")";
    ASSERT_TRUE(ev.basis_row(u, row));
    std::vector<double> graph(s.control_point_count(), 0.0);
    for (size_t k = 0; k < row.index.size(); ++k) graph[row.index[k]] = row.value[k];
    for (size_t k = 0; k < weight.size(); ++k) worst = std::max(worst, std::fabs(graph[k] - weight[k]));
  }
  EXPECT_LT(worst, 1e-10);
}

TEST_P(Basis, LinearPrecision) {
  const Config c = GetParam();
  Spline s = test::random_spline(c.degree, grid(c), c.seed);
  std::mt19937_64 rng(c.seed);
  std::uniform_real_distribution<double> uni(-2, 2);
  Eigen::Matrix<double, 3, 2> A;
  for (int i = 0; i < 6; ++i) A.data()[i] = uni(rng);
  const double bz = uni(rng), by = uni(rng);  // z, y, x: GCC's order, for any compiler
  const Vector3 b(uni(rng), by, bz);
  const int n = s.degree();
  for (int t = 0; t < s.domain().triangle_count(); ++t)
    for (int i = 0; i < beta_count(n); ++i)
      s.control_points()[s.control_point_index(t, i)] = A * s.blossom_point(t, beta_at(n, i)) + b;
  const Evaluator ev(s);
  auto pts = test::random_domain_points(s.domain(), 5000, c.seed);
  const auto special = test::special_points(s, ev, 5000);
  pts.insert(pts.end(), special.begin(), special.end());
  for (const auto& u : pts) {
    const SurfacePoint f = ev.evaluate(u);
    ASSERT_LT((f.position - (A * u + b)).norm(), 1e-10) << u.transpose();
    ASSERT_LT((f.du - A.col(0)).norm(), 1e-9) << u.transpose();
    ASSERT_LT((f.dv - A.col(1)).norm(), 1e-9) << u.transpose();
  }
  // The identity itself: F(u) = u for control points at the blossom points.
  for (int t = 0; t < s.domain().triangle_count(); ++t)
    for (int i = 0; i < beta_count(n); ++i) {
      const Point2 q = s.blossom_point(t, beta_at(n, i));
      s.control_points()[s.control_point_index(t, i)] = Point3(q.x(), q.y(), 0);
    }
  const Evaluator id(s);
  for (size_t k = 0; k < pts.size(); k += 7)
    ASSERT_LT((id.value(pts[k]).head<2>() - pts[k]).norm(), 1e-10);
}

// F does not depend on the last knots t_{i,n}.
TEST_P(Basis, LastKnotsDoNotChangeTheSurface) {
  const Config c = GetParam();
  const Spline s = test::random_spline(c.degree, grid(c), c.seed);
  const int n = s.degree();
  // Other valid knots: a new random cloud; keep levels < n from s, take level n from it.
  const auto other = test::random_knots(s.domain(), n, c.seed + 1000);
  Spline moved = s;
  int changed = 0;
  for (int v = 0; v < s.domain().vertex_count(); ++v)
    if (moved.knot(v, n) != other[v * (n + 1) + n]) {
      moved.set_knot(v, n, other[v * (n + 1) + n]);
      ++changed;
    }
  ASSERT_GT(changed, 0);
  if (!check_knot_conditions(moved.domain(), n, moved.knots()).ok()) GTEST_SKIP() << "mixed knots invalid";
  const Evaluator ev(s);
  const auto pts = test::random_domain_points(s.domain(), c.degree >= 5 ? 100 : 300, c.seed + 3);
  for (const auto& u : pts) {
    const auto p = ev.perturbation(u);
    const Point3 a = reference::value_degree_n(s, *p);
    const Point3 b = reference::value_degree_n(moved, *p);
    ASSERT_LT((a - b).norm(), 1e-10) << u.transpose();
    // And both equal the fast degree n-1 form.
    ASSERT_LT((a - ev.value(u)).norm(), 1e-10) << u.transpose();
  }
}

INSTANTIATE_TEST_SUITE_P(Configs, Basis, ::testing::ValuesIn(configs()), name);

}  // namespace
}  // namespace tbs
