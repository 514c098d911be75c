#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/reference.h>

#include "box_grid.h"
#include "random_spline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace tbs {
namespace {

test::GridOptions grid(bool hole = false) {
  test::GridOptions o;
  o.nx = o.ny = 6;
  o.hole = hole;
  return o;
}

class Eval : public ::testing::TestWithParam<int> {};

TEST_P(Eval, GraphMatchesPlainRecursionAndTheReference) {
  const int n = GetParam();
  const Spline s = test::random_spline(n, grid(true), 11);
  const Evaluator graph(s), plain(s, EvalMode::Recursion);
  const auto pts = test::random_domain_points(s.domain(), 2000, 3);
  const Vector2 du(1, 0), dv(0, 1);
  for (size_t i = 0; i < pts.size(); ++i) {
    const SurfacePoint a = graph.evaluate(pts[i]);
    const SurfacePoint b = plain.evaluate(pts[i]);
    ASSERT_LT((a.position - b.position).norm(), 1e-11);
    ASSERT_LT((a.du - b.du).norm(), 1e-9);
    ASSERT_LT((a.dv - b.dv).norm(), 1e-9);
    if (i % 10 == 0) {
      const auto p = *graph.perturbation(pts[i]);
      ASSERT_LT((a.position - reference::derivative(s, {}, p)).norm(), 1e-11);
      ASSERT_LT((a.du - reference::derivative(s, std::span(&du, 1), p)).norm(), 1e-9);
      ASSERT_LT((a.dv - reference::derivative(s, std::span(&dv, 1), p)).norm(), 1e-9);
    }
  }
}

TEST_P(Eval, PartialDerivativesMatchCentralDifferencesWithH2Convergence) {
  const int n = GetParam();
  const Spline s = test::random_spline(n, grid(), 12);
  const Evaluator ev(s);
  const auto pts = test::random_domain_points(s.domain(), 300, 4);
  std::vector<double> ratios;
  for (const auto& u : pts) {
    // Stay away from the boundary so the stencil stays in the domain.
    if ((u.array() < 0.05).any() || (u.array() > 0.95).any()) continue;
    const SurfacePoint f = ev.evaluate(u);
    for (int axis = 0; axis < 2; ++axis) {
      const Vector2 e = axis == 0 ? Vector2(1, 0) : Vector2(0, 1);
      const Vector3 exact = axis == 0 ? f.du : f.dv;
      auto fd = [&](double h) { return Vector3((ev.value(u + h * e) - ev.value(u - h * e)) / (2 * h)); };
      const double small = (fd(1e-6) - exact).norm();
      ASSERT_LT(small, 1e-6 * (1 + exact.norm())) << u.transpose();
      if (n >= 3) {
        const double e1 = (fd(4e-3) - exact).norm(), e2 = (fd(2e-3) - exact).norm();
        if (e1 > 1e-9) ratios.push_back(e1 / e2);
      }
    }
  }
  if (n >= 3) {
    ASSERT_GT(ratios.size(), 100u);
    std::nth_element(ratios.begin(), ratios.begin() + ratios.size() / 2, ratios.end());
    const double median = ratios[ratios.size() / 2];
    EXPECT_GT(median, 3.5);
    EXPECT_LT(median, 4.5);
  }
}

TEST_P(Eval, DirectionalDerivativeAndNormal) {
  const int n = GetParam();
  const Spline s = test::random_spline(n, grid(), 13);
  const Evaluator ev(s);
  for (const auto& u : test::random_domain_points(s.domain(), 200, 5)) {
    const SurfacePoint f = ev.evaluate(u);
    const Vector2 dir(0.3, -1.7);
    EXPECT_LT((ev.derivative(u, dir) - (0.3 * f.du - 1.7 * f.dv)).norm(), 1e-12);
    const Vector3 nrm = ev.normal(u);
    EXPECT_NEAR(nrm.norm(), 1.0, 1e-12);
    EXPECT_NEAR(nrm.dot(f.du), 0.0, 1e-9);
    EXPECT_NEAR(nrm.dot(f.dv), 0.0, 1e-9);
    EXPECT_GT(nrm.dot(f.du.cross(f.dv)), 0);
  }
}

TEST_P(Eval, BatchIsIndependentOfThreadCount) {
  const int n = GetParam();
  const Spline s = test::random_spline(n, grid(true), 14);
  const Evaluator ev(s);
  auto pts = test::random_domain_points(s.domain(), 20000, 6);
  pts.emplace_back(0.5, 0.5);  // in the hole
  pts.emplace_back(2.0, 0.5);  // outside
  std::vector<Point3> p1(pts.size()), p2(pts.size()), p0(pts.size());
  std::vector<Vector3> u1(pts.size()), u2(pts.size()), v1(pts.size()), v2(pts.size());
  std::vector<uint8_t> in1(pts.size()), in2(pts.size());
  EXPECT_EQ(ev.evaluate_batch(pts, p1, u1, v1, in1, 1), 2u);
  EXPECT_EQ(ev.evaluate_batch(pts, p2, u2, v2, in2, 2), 2u);
  EXPECT_EQ(ev.evaluate_batch(pts, p0, {}, {}, {}, 0), 2u);
  for (size_t i = 0; i + 2 < pts.size(); ++i) {
    ASSERT_EQ(in1[i], 1);
    ASSERT_EQ(p1[i], p2[i]);
    ASSERT_EQ(p1[i], p0[i]);
    ASSERT_EQ(u1[i], u2[i]);
    ASSERT_EQ(v1[i], v2[i]);
    // The batch visits points grouped by cell; each must still equal its own evaluation.
    const SurfacePoint f = ev.evaluate(pts[i]);
    ASSERT_EQ(p1[i], f.position);
    ASSERT_EQ(u1[i], f.du);
    ASSERT_EQ(v1[i], f.dv);
  }
  EXPECT_EQ(in1[pts.size() - 1], 0);
  EXPECT_EQ(in1[pts.size() - 2], 0);
  EXPECT_TRUE(std::isnan(p1.back().x()));
  // A batch too small to be reordered gives the same values.
  const std::span<const Point2> head(pts.data(), 500);
  std::vector<Point3> ps(head.size());
  EXPECT_EQ(ev.evaluate_batch(head, ps, {}, {}, {}, 2), 0u);
  for (size_t i = 0; i < head.size(); ++i) ASSERT_EQ(ps[i], p1[i]);
}

TEST(Evaluator, BatchesLargerThanOneSortBlockKeepEveryPointInItsPlace) {
  // evaluate_batch sorts 2^20 points at a time; points after the first block must come back
  // at their own index too.
  const Spline s = test::random_spline(2, grid(true), 16);
  const Evaluator ev(s);
  const auto some = test::random_domain_points(s.domain(), 4096, 9);
  std::vector<Point2> pts((size_t{1} << 20) + 4099);
  for (size_t i = 0; i < pts.size(); ++i) pts[i] = some[(i * 2654435761u) % some.size()];
  pts[pts.size() - 2] = Point2(0.5, 0.5);  // in the hole, in the second block
  std::vector<Point3> pos(pts.size());
  std::vector<Vector3> dv(pts.size());
  EXPECT_EQ(ev.evaluate_batch(pts, pos, {}, dv, {}, 2), 1u);
  std::vector<SurfacePoint> expect(some.size());
  for (size_t j = 0; j < some.size(); ++j) expect[j] = ev.evaluate(some[j]);
  for (size_t i = 0; i < pts.size(); ++i) {
    if (i == pts.size() - 2) {
      ASSERT_TRUE(std::isnan(pos[i].x()));
      continue;
    }
    const SurfacePoint& f = expect[(i * 2654435761u) % some.size()];
    ASSERT_EQ(pos[i], f.position) << "point " << i;
    ASSERT_EQ(dv[i], f.dv) << "point " << i;
  }
}

INSTANTIATE_TEST_SUITE_P(Degrees, Eval, ::testing::Values(1, 2, 3, 4, 5, 6));

TEST(Evaluator, OutsideTheDomainAndInTheHole) {
  const Spline s = test::random_spline(3, grid(true), 15);
  const Evaluator ev(s);
  EXPECT_EQ(ev.locate({0.5, 0.5}), -1);
  EXPECT_EQ(ev.locate({-0.1, 0.5}), -1);
  EXPECT_EQ(ev.locate({1.0 + 1e-15, 0.5}), -1);
  EXPECT_EQ(ev.locate({std::nan(""), 0.5}), -1);
  EXPECT_THROW(ev.value({0.5, 0.5}), OutsideDomain);
  EXPECT_THROW(ev.normal({3, 3}), OutsideDomain);
  BasisRow row;
  EXPECT_FALSE(ev.basis_row({0.5, 0.5}, row));
  EXPECT_TRUE(row.index.empty());
}

// Points on the outer boundary and the hole's boundary evaluate to the limit from inside.
TEST(Evaluator, BoundaryPointsAreLimitsFromInside) {
  const Spline s = test::random_spline(3, grid(true), 16);
  const Evaluator ev(s);
  const Domain& d = s.domain();
  int checked = 0;
  for (const auto& loop : d.boundary_loops())
    for (size_t i = 0; i < loop.size(); ++i) {
      const Point2 a = d.vertex(loop[i]), b = d.vertex(loop[(i + 1) % loop.size()]);
      for (const Point2& u : {a, Point2(0.5 * (a + b))}) {
        ASSERT_GE(ev.locate(u), 0) << u.transpose();
        const Vector2 inward = Vector2(-(b - a).y(), (b - a).x()).normalized();
        const Vector2 along = (b - a).normalized();
        const Point2 q = u + 1e-7 * inward + 1e-8 * along;
        ASSERT_GE(ev.locate(q), 0);
        EXPECT_LT((ev.value(u) - ev.value(q)).norm(), 1e-5) << u.transpose();
        ++checked;
      }
    }
  EXPECT_GT(checked, 40);
}

// On a feature edge the chosen side gives that side's one-sided derivatives: the limits of
// F_u, F_v from that side.
TEST(Evaluator, EvaluateOnAChosenSideGivesOneSidedLimits) {
  test::GridOptions o = grid();
  o.feature_column = 3;
  const Spline s = test::random_spline(3, o, 19);
  const Evaluator ev(s);
  const Domain& d = s.domain();
  int checked = 0;
  for (const auto& fe : d.feature_edges()) {
    const Point2 a = d.vertex(fe[0]), b = d.vertex(fe[1]);
    const Point2 u = 0.5 * (a + b);
    const Vector2 n = Vector2(-(b - a).y(), (b - a).x()).normalized();
    for (double sign : {1.0, -1.0}) {
      const auto side = ev.evaluate(u, Perturbation::toward(u, u + sign * n, b));
      ASSERT_TRUE(side);
      const SurfacePoint near = ev.evaluate(u + sign * 1e-9 * n);
      EXPECT_LT((side->position - near.position).norm(), 1e-7);
      EXPECT_LT((side->du - near.du).norm(), 1e-5 * (1 + near.du.norm()));
      EXPECT_LT((side->dv - near.dv).norm(), 1e-5 * (1 + near.dv.norm()));
    }
    const auto left = ev.evaluate(u, Perturbation::toward(u, u + n, b));
    const auto right = ev.evaluate(u, Perturbation::toward(u, u - n, b));
    EXPECT_LT((left->position - right->position).norm(), 1e-12);  // C^0 ...
    EXPECT_GT((left->du - right->du).norm() + (left->dv - right->dv).norm(), 1e-6);  // ... not C^1
    ++checked;
  }
  EXPECT_GT(checked, 3);
  // Outside the domain there is no side; a perturbation of another point is refused.
  const Point2 corner(0, 0);
  EXPECT_FALSE(ev.evaluate(corner, Perturbation::toward(corner, Point2(-1, -1), Point2(-1, 0))));
  EXPECT_TRUE(ev.evaluate(corner, Perturbation::toward(corner, Point2(1, 1), Point2(1, 0))));
  EXPECT_THROW(ev.evaluate(corner, Perturbation::toward(Point2(0.5, 0.5), Point2(1, 1), Point2(1, 0))),
               InvalidInput);
}

TEST(Evaluator, UpdateKnotsEqualsAFreshEvaluator) {
  Spline s = test::random_spline(3, grid(), 17);
  Evaluator ev(s);
  const auto pts = test::random_domain_points(s.domain(), 500, 7);
  // Move the sub-knots of an interior vertex a little (they stay valid).
  int v = -1;
  for (int i = 0; i < s.domain().vertex_count() && v < 0; ++i)
    if (!s.domain().is_boundary_vertex(i)) v = i;
  for (int l = 0; l <= 3; ++l) {
    const Point2 delta = l == 0 ? Point2(0.004, -0.003) : Point2(0.001 * l, 0.0005);
    s.set_knot(v, l, s.knot(v, l) + delta);
  }
  ev.update_knots(v);
  const Evaluator fresh(s);
  for (const auto& u : pts) {
    if (fresh.locate(u) < 0) continue;
    EXPECT_LT((ev.value(u) - fresh.value(u)).norm(), 1e-14);
  }
}

// update_knots rebuilds its spatial grids only when a moved triangle reaches a cell its grid
// did not list it in. Through a walk of knot moves, small (kept grids) and large (new grids),
// and back, points are located in the same triangles as by a fresh evaluator, and their basis
// rows have the same entries with the same values to rounding (the graph of the updated
// evaluator keeps the split sets it chose for the first knots).
TEST(Evaluator, UpdateKnotsKeepsTheRowsOfAFreshEvaluator) {
  Spline s = test::random_spline(3, grid(), 23);
  Evaluator ev(s);
  const auto pts = test::random_domain_points(s.domain(), 400, 9);
  std::vector<int> inner;
  for (int i = 0; i < s.domain().vertex_count(); ++i)
    if (!s.domain().is_boundary_vertex(i)) inner.push_back(i);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const std::vector<Point2> start = s.knots();
  BasisRow a, b;
  for (int step = 0; step < 40; ++step) {
    SCOPED_TRACE(step);
    const int v = inner[static_cast<size_t>(step) % inner.size()];
    const double reach = step % 5 == 4 ? 0.06 : 0.004;  // every fifth move crosses grid cells
    for (int l = 3; l >= 0; --l) {
      const Point2 p = s.knot(v, l) + reach * Point2(unit(rng), unit(rng));
      try {
        s.set_knot(v, l, p);
      } catch (const InvalidInput&) {  // a primary move that would flip a triangle: skip it
      }
    }
    if (step == 30) {  // back to the start, vertex by vertex
      for (int w = 0; w < s.domain().vertex_count(); ++w)
        for (int l = 3; l >= 0; --l) s.set_knot(w, l, start[static_cast<size_t>(w) * 4 + l]);
      for (int w = 0; w < s.domain().vertex_count(); ++w) ev.update_knots(w);
    } else {
      ev.update_knots(v);
    }
    const Evaluator fresh(s);
    for (const auto& u : pts) {
      ASSERT_EQ(ev.locate(u), fresh.locate(u));
      ASSERT_EQ(ev.basis_row(u, a), fresh.basis_row(u, b));
      ASSERT_EQ(a.index, b.index);
      for (size_t k = 0; k < a.index.size(); ++k) {
        ASSERT_NEAR(a.value[k], b.value[k], 1e-13);
        ASSERT_NEAR(a.du[k], b.du[k], 1e-11);
        ASSERT_NEAR(a.dv[k], b.dv[k], 1e-11);
      }
    }
  }
}

// The exactness behind update_knots' kept grids: while covers() allows a box to change without
// a new build, the grid answers a point with the same boxes, in the same order, as a grid
// built fresh, once both lists are cut to the boxes that contain the point.
TEST(BoxGrid, CoveredChangesAnswerLikeAFreshGrid) {
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto box_at = [](const Point2& c, double rx, double ry) {
    Box2 b;
    b.extend(c - Point2(rx, ry));
    b.extend(c + Point2(rx, ry));
    return b;
  };
  std::vector<Box2> boxes;
  for (int i = 0; i < 300; ++i)
    boxes.push_back(box_at(Point2(unit(rng), unit(rng)), 0.01 + 0.05 * unit(rng), 0.01 + 0.05 * unit(rng)));
  detail::BoxGrid kept, fresh;
  kept.build(boxes, boxes.size());
  int covered = 0, rebuilt = 0;
  auto inside = [](const detail::BoxGrid& g, const std::vector<Box2>& b, const Point2& p) {
    std::vector<int> ids;
    for (int id : g.at(p))
      if (b[id].contains(p)) ids.push_back(id);
    return ids;
  };
  for (int step = 0; step < 600; ++step) {
    const int id = static_cast<int>(rng() % boxes.size());
    const Point2 c = 0.5 * (boxes[id].min + boxes[id].max);
    const double jump = step % 4 == 3 ? 0.1 : 0.005;
    const Box2 b = box_at(c + jump * Point2(unit(rng) - 0.5, unit(rng) - 0.5), 0.01 + 0.05 * unit(rng),
                          0.01 + 0.05 * unit(rng));
    const bool keep = kept.covers(id, b);
    boxes[id] = b;
    if (keep) {
      ++covered;
    } else {
      kept.build(boxes, boxes.size());
      ++rebuilt;
    }
    fresh.build(boxes, boxes.size());
    for (int k = 0; k < 40; ++k) {
      const Point2 p(unit(rng) * 1.1 - 0.05, unit(rng) * 1.1 - 0.05);
      ASSERT_EQ(inside(kept, boxes, p), inside(fresh, boxes, p)) << "step " << step;
    }
    // A point on a box's corner is inside it (closed boxes) and must be found.
    ASSERT_EQ(inside(kept, boxes, b.max), inside(fresh, boxes, b.max)) << "step " << step;
  }
  EXPECT_GT(covered, 100);
  EXPECT_GT(rebuilt, 100);
}

// A copy for a spline copy evaluates that copy: the same basis rows as its source, bit for
// bit, its own control points, and knot updates of its own.
TEST(Evaluator, CopyForASplineCopy) {
  const Spline s = test::random_spline(3, grid(true), 29);
  const Evaluator ev(s);
  Spline t = s;
  for (auto& c : t.control_points()) c += Point3(0.5, -1, 2);
  Evaluator copy(ev, t);
  const auto pts = test::random_domain_points(s.domain(), 300, 4);
  BasisRow a, b;
  for (const auto& u : pts) {
    ASSERT_EQ(ev.basis_row(u, a), copy.basis_row(u, b));
    ASSERT_EQ(a.index, b.index);
    ASSERT_EQ(a.value, b.value);
    ASSERT_EQ(a.du, b.du);
    ASSERT_EQ(a.dv, b.dv);
    ASSERT_LT((copy.value(u) - (ev.value(u) + Point3(0.5, -1, 2))).norm(), 1e-12);
  }
  int v = -1;
  for (int i = 0; i < t.domain().vertex_count() && v < 0; ++i)
    if (!t.domain().is_boundary_vertex(i)) v = i;
  t.set_knot(v, 2, t.knot(v, 2) + Point2(0.003, 0.002));
  copy.update_knots(v);
  const Evaluator fresh(t);
  int differ = 0;
  for (const auto& u : pts) {
    ASSERT_LT((copy.value(u) - fresh.value(u)).norm(), 1e-12);
    differ += (ev.value(u) + Point3(0.5, -1, 2) - copy.value(u)).norm() > 1e-9;
  }
  EXPECT_GT(differ, 0);  // the source still evaluates the old knots
}

TEST(Evaluator, ControlPointsAreReadAtEachCall) {
  Spline s = test::random_spline(2, grid(), 18);
  const Evaluator ev(s);
  const Point2 u(0.31, 0.47);
  const Point3 before = ev.value(u);
  for (auto& c : s.control_points()) c += Point3(1, 2, 3);
  EXPECT_LT((ev.value(u) - (before + Point3(1, 2, 3))).norm(), 1e-12);
}

TEST(Evaluator, GraphSharesNodes) {
  const Spline s = test::random_spline(4, grid(), 19);
  const Evaluator ev(s);
  // Plain recursion visits 1 + 3 + 9 + 27 sets per degree-3 top set; the graph stores each
  // distinct set once.
  const size_t tree = static_cast<size_t>(s.domain().triangle_count()) * beta_count(3) * 40;
  EXPECT_LT(ev.node_count() * 3, tree);
}

}  // namespace
}  // namespace tbs
