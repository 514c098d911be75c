#include <tbs/bezier.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/extract.h>
#include <tbs/predicates.h>

#include "random_spline.h"

#include <gtest/gtest.h>

#include <map>

namespace tbs {
namespace {

struct Case {
  int degree;
  bool features;
  bool hole;
};

std::string name(const ::testing::TestParamInfo<Case>& i) {
  return "Degree" + std::to_string(i.param.degree) + (i.param.features ? "Features" : "") +
         (i.param.hole ? "Hole" : "");
}

Spline make_spline(const Case& c, uint64_t seed) {
  test::GridOptions o;
  o.nx = o.ny = 5;
  o.hole = c.hole;
  o.feature_column = c.features ? 2 : -1;
  o.feature_kink = c.features;
  return test::random_spline(c.degree, o, seed);
}

Bary barycentric(const Point2& a, const Point2& b, const Point2& c, const Point2& u) {
  const double area = det3(a, b, c);
  return {det3(u, b, c) / area, det3(a, u, c) / area, det3(a, b, u) / area};
}

class Extract : public ::testing::TestWithParam<Case> {};

TEST_P(Extract, PiecesAgreeWithDirectEvaluationAndTileEachTriangle) {
  const Spline s = make_spline(GetParam(), 21);
  const Extraction x = extract_bezier(s);
  const Evaluator ev(s);
  const Domain& d = s.domain();
  ASSERT_EQ(x.degree, s.degree());
  ASSERT_EQ(static_cast<int>(x.piece_start.size()), d.triangle_count() + 1);
  ASSERT_EQ(x.control_points.size(), x.pieces.size() * beta_count(s.degree()));

  // Tiling: positive pieces whose areas sum to the triangle's area.
  for (int t = 0; t < d.triangle_count(); ++t) {
    const auto& tri = d.triangle(t);
    const double area = det3(d.vertex(tri[0]), d.vertex(tri[1]), d.vertex(tri[2]));
    double sum = 0;
    ASSERT_GT(x.piece_start[t + 1], x.piece_start[t]);
    ASSERT_GE(x.cells[t], 1);
    for (int p = x.piece_start[t]; p < x.piece_start[t + 1]; ++p) {
      const auto& c = x.pieces[p].corners;
      const double a = det3(x.vertices[c[0]], x.vertices[c[1]], x.vertices[c[2]]);
      ASSERT_GT(a, 0) << "piece " << p << " of triangle " << t << " is not counter-clockwise";
      ASSERT_EQ(x.pieces[p].triangle, t);
      ASSERT_LT(x.pieces[p].cell, x.cells[t]);
      sum += a;
    }
    EXPECT_NEAR(sum, area, 1e-12 * area) << "triangle " << t;
  }

  // Every random point lies in exactly one piece, and the piece's net gives F there.
  const auto pts = test::random_domain_points(d, 30000, 5);
  double worst = 0, scale = 0;
  for (const auto& c : s.control_points()) scale = std::max(scale, c.cwiseAbs().maxCoeff());
  for (const auto& u : pts) {
    const int t = ev.locate(u);
    ASSERT_GE(t, 0);
    int inside = 0, best = -1;
    double best_min = -1e300;
    Bary best_b;
    for (int p = x.piece_start[t]; p < x.piece_start[t + 1]; ++p) {
      const auto& c = x.pieces[p].corners;
      const Bary b = barycentric(x.vertices[c[0]], x.vertices[c[1]], x.vertices[c[2]], u);
      if (b.minCoeff() > 1e-12) ++inside;
      if (b.minCoeff() > best_min) best_min = b.minCoeff(), best = p, best_b = b;
    }
    ASSERT_LE(inside, 1) << "pieces overlap at " << u.transpose();
    ASSERT_GT(best_min, -1e-12) << "no piece covers " << u.transpose();
    const Point3 f = ev.value(u);
    const Point3 b = bezier_value(x.net(best), x.degree, best_b);
    worst = std::max(worst, (f - b).norm());
  }
  EXPECT_LT(worst, 1e-10 * scale) << "largest difference " << worst;
  RecordProperty("pieces", static_cast<int>(x.pieces.size()));
  RecordProperty("largest_difference", std::to_string(worst / scale * 1e15) + "e-15");
}

TEST_P(Extract, SharedEdgesHaveBitIdenticalControlPoints) {
  const Spline s = make_spline(GetParam(), 22);
  const Extraction x = extract_bezier(s);
  const int n = x.degree;
  std::map<std::pair<int, int>, std::vector<Point3>> seen;  // (from, to) -> side points
  int shared = 0, across_triangles = 0;
  std::map<std::pair<int, int>, int> owner;
  for (int p = 0; p < static_cast<int>(x.pieces.size()); ++p) {
    const auto& c = x.pieces[p].corners;
    for (int k = 0; k < 3; ++k) {
      const int a = c[(k + 1) % 3], b = c[(k + 2) % 3];
      const auto side = bezier_side(x.net(p), n, k);
      const auto other = seen.find({b, a});
      if (other != seen.end()) {
        ++shared;
        if (x.pieces[owner[{b, a}]].triangle != x.pieces[p].triangle) ++across_triangles;
        for (int i = 0; i <= n; ++i)
          ASSERT_TRUE(side[i] == other->second[n - i]) << "piece " << p << " side " << k;
      }
      seen[{a, b}] = side;
      owner[{a, b}] = p;
    }
  }
  EXPECT_GT(shared, static_cast<int>(x.pieces.size()));
  EXPECT_GT(across_triangles, s.domain().triangle_count());
  // Watertight: every piece edge is shared unless it lies on the domain boundary.
  const Evaluator ev(s);
  for (const auto& [key, side] : seen) {
    if (seen.count({key.second, key.first})) continue;
    const Point2 mid = (x.vertices[key.first] + x.vertices[key.second]) / 2;
    const Point2 normal(x.vertices[key.second].y() - x.vertices[key.first].y(),
                        x.vertices[key.first].x() - x.vertices[key.second].x());
    // Just across an unshared edge (to its right) there is no domain.
    EXPECT_LT(ev.locate(mid + 1e-7 * normal), 0) << "open piece edge inside the domain";
  }
}

TEST_P(Extract, SameResultForOneAndTwoThreads) {
  const Spline s = make_spline(GetParam(), 23);
  const Extraction a = extract_bezier(s, {.threads = 1});
  const Extraction b = extract_bezier(s, {.threads = 2});
  ASSERT_EQ(a.vertices, b.vertices);
  ASSERT_EQ(a.control_points, b.control_points);
  ASSERT_EQ(a.cells, b.cells);
}

INSTANTIATE_TEST_SUITE_P(Splines, Extract,
                         ::testing::Values(Case{2, false, false}, Case{3, true, false},
                                           Case{4, false, true}, Case{3, false, true},
                                           Case{4, true, false}, Case{1, false, false}),
                         name);

TEST(Extract, CellsOfADegreeOneSplineAreItsTriangles) {
  const Spline s = make_spline({1, false, false}, 3);
  const Extraction x = extract_bezier(s);
  for (int c : x.cells) EXPECT_EQ(c, 1);
  EXPECT_EQ(x.pieces.size(), static_cast<size_t>(s.domain().triangle_count()));
}

TEST(Bezier, CurveRestrictionIsTheSameCurve) {
  const std::vector<Point3> cps = {{0, 0, 0}, {1, 2, 0}, {3, -1, 1}, {4, 0, 2}};
  const auto r = bezier_curve_restrict(cps, 0.25, 0.75);
  for (double t : {0.0, 0.3, 0.5, 1.0})
    EXPECT_LT((bezier_curve_value(r, t) - bezier_curve_value(cps, 0.25 + 0.5 * t)).norm(), 1e-14);
  const auto rev = bezier_curve_restrict(cps, 1, 0);
  EXPECT_LT((bezier_curve_value(rev, 0.2) - bezier_curve_value(cps, 0.8)).norm(), 1e-14);
}

TEST(Bezier, DerivativesMatchDifferences) {
  std::vector<Point3> net(beta_count(3));
  for (size_t i = 0; i < net.size(); ++i) net[i] = Point3(std::sin(i), std::cos(3 * i), i * 0.1);
  const Bary b(0.2, 0.3, 0.5);
  Point3 v;
  Vector3 d1, d2;
  bezier_derivatives(net, 3, b, v, d1, d2);
  const double h = 1e-6;
  const Vector3 f1 = (bezier_value(net, 3, b + h * Bary(-1, 1, 0)) - bezier_value(net, 3, b - h * Bary(-1, 1, 0))) / (2 * h);
  const Vector3 f2 = (bezier_value(net, 3, b + h * Bary(-1, 0, 1)) - bezier_value(net, 3, b - h * Bary(-1, 0, 1))) / (2 * h);
  EXPECT_LT((d1 - f1).norm(), 1e-8);
  EXPECT_LT((d2 - f2).norm(), 1e-8);
  EXPECT_LT((v - bezier_value(net, 3, b)).norm(), 1e-15);
  std::vector<double> bern(beta_count(3));
  bernstein_triangle(3, b, bern);
  Point3 sum = Point3::Zero();
  for (size_t i = 0; i < net.size(); ++i) sum += bern[i] * net[i];
  EXPECT_LT((sum - v).norm(), 1e-14);
}

}  // namespace
}  // namespace tbs

namespace tbs {
namespace {

TEST(Bezier, QuadsAndCollapsedQuadEqualTheTriangle) {
  for (int m : {1, 2, 3, 4, 5, 7}) {
    std::vector<Point3> net(beta_count(m));
    for (size_t i = 0; i < net.size(); ++i) net[i] = Point3(std::sin(1.3 * i), std::cos(0.7 * i), 0.1 * i * i);
    const auto quads = bezier_triangle_to_quads(net, m);
    const Bary e[3] = {Bary(1, 0, 0), Bary(0, 1, 0), Bary(0, 0, 1)};
    for (int k = 0; k < 3; ++k)
      for (double s : {0.0, 0.3, 1.0})
        for (double t : {0.0, 0.55, 1.0}) {
          const Bary b00 = e[k], b10 = (e[k] + e[(k + 1) % 3]) / 2, b01 = (e[k] + e[(k + 2) % 3]) / 2,
                     b11 = Bary(1, 1, 1) / 3;
          const Bary b = (1 - s) * (1 - t) * b00 + s * (1 - t) * b10 + (1 - s) * t * b01 + s * t * b11;
          EXPECT_LT((bezier_tensor_value(quads[k], m, s, t) - bezier_value(net, m, b)).norm(), 1e-12)
              << "m " << m << " quad " << k;
        }
    const auto collapsed = bezier_triangle_to_collapsed_quad(net, m);
    for (double s : {0.0, 0.4, 1.0})
      for (double t : {0.0, 0.8, 1.0}) {
        const Bary b(1 - s, s * (1 - t), s * t);
        EXPECT_LT((bezier_tensor_value(collapsed, m, s, t) - bezier_value(net, m, b)).norm(), 1e-12);
      }
  }
}

}  // namespace
}  // namespace tbs
