// check_shape(): folds where the normal reverses, and the parameterization's stretch, on splines
// built in code whose shape is known.
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/knots.h>
#include <tbs/shape_check.h>

#include "random_spline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

namespace tbs {
namespace {

// A cubic spline on a jittered 8 x 8 grid over [0,1]^2 that is the map
// F(u, v) = (x(u), v, 0) exactly: each control point is F's polar form at the knots of its
// (triangle, beta), t_{i,0..b0-1}, t_{j,0..b1-1}, t_{k,0..b2-1}. `x_polar` is x's polar form
// (symmetric, affine in each of its three arguments, x_polar(u, u, u) = x(u)).
Spline mapped(const std::function<double(double, double, double)>& x_polar) {
  test::GridOptions o;
  o.nx = o.ny = 8;
  const Domain d = test::grid_domain(o, 11);
  Spline s = Spline::with_canonical_map(3, d, default_knots(d, 3));
  for (int t = 0; t < d.triangle_count(); ++t)
    for (int i = 0; i < beta_count(3); ++i) {
      const Beta b = beta_at(3, i);
      std::vector<Point2> args;
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < b[static_cast<size_t>(c)]; ++k) args.push_back(s.knot(d.triangle(t)[static_cast<size_t>(c)], k));
      const double v = (args[0].y() + args[1].y() + args[2].y()) / 3;
      s.control_points()[static_cast<size_t>(s.control_point_index(t, i))] =
          Point3(x_polar(args[0].x(), args[1].x(), args[2].x()), v, 0);
    }
  return s;
}

// x(u) = 8 (u - 1/2)^3 - (u - 1/2) / 2 turns back on itself: x_u = 24 (u - 1/2)^2 - 1/2 changes
// sign at |u - 1/2| = 1/sqrt(48), about 0.144, and with it the normal (0, 0, x_u).
double folding_polar(double a, double b, double c) {
  return 8 * (a - 0.5) * (b - 0.5) * (c - 0.5) - ((a + b + c) / 3 - 0.5) / 2;
}

TEST(ShapeCheck, AFlatSheetHasNoFoldAndTheStretchOfItsMap) {
  // F = (10u, v, 0): |F_u| = 10 everywhere, the domain's diameter sqrt(2), the model size the
  // diagonal of the surface's box, sqrt(101) (less the samples' 1e-4 from the border).
  const Spline s = mapped([](double a, double b, double c) { return 10 * (a + b + c) / 3; });
  const Evaluator ev(s);
  const ShapeCheck c = check_shape(s, ev);
  EXPECT_TRUE(c.folded_triangles.empty());
  EXPECT_LE(c.max_normal_turn, 1e-6);
  EXPECT_NEAR(c.max_stretch, 10 * std::sqrt(2.0) / std::sqrt(101.0), 1e-3);
  EXPECT_EQ(c.singular_samples, 0u);
}

TEST(ShapeCheck, ASurfaceThatFoldsOverItselfIsFoundWhereItFolds) {
  const Spline s = mapped(folding_polar);
  const Evaluator ev(s);
  const ShapeCheck c = check_shape(s, ev);
  ASSERT_FALSE(c.folded_triangles.empty());
  EXPECT_GT(c.max_normal_turn, 90);
  // Every folded triangle reaches a fold line, and every triangle a fold line crosses inside
  // is found.
  const double fold = 1 / std::sqrt(48.0);
  const Domain& d = s.domain();
  std::vector<char> found(static_cast<size_t>(d.triangle_count()), 0);
  for (int t : c.folded_triangles) found[static_cast<size_t>(t)] = 1;
  for (int t = 0; t < d.triangle_count(); ++t) {
    double lo = 1, hi = 0;
    for (int v : d.triangle(t)) {
      lo = std::min(lo, d.vertex(v).x());
      hi = std::max(hi, d.vertex(v).x());
    }
    bool crossed = false, reached = false;
    for (double line : {0.5 - fold, 0.5 + fold}) {
      crossed = crossed || (lo < line - 0.03 && hi > line + 0.03);
      reached = reached || (lo <= line + 1e-3 && hi >= line - 1e-3);
    }
    if (crossed) {
      EXPECT_TRUE(found[static_cast<size_t>(t)]) << "triangle " << t << " crosses a fold line";
    }
    if (found[static_cast<size_t>(t)]) {
      EXPECT_TRUE(reached) << "triangle " << t << " is nowhere near a fold";
    }
  }
}

TEST(ShapeCheck, ACreaseIsNoFold) {
  // A 120 degree crease along the feature column x = 1/2: the normal turns by 60 degrees
  // across it, which is the crease, not a fold.
  test::GridOptions o;
  o.nx = o.ny = 8;
  o.feature_column = 4;
  const Domain d = test::grid_domain(o, 11);
  Spline s = Spline::with_canonical_map(3, d, default_knots(d, 3));
  for (int t = 0; t < d.triangle_count(); ++t)
    for (int i = 0; i < beta_count(3); ++i) {
      const Point2 b = s.blossom_point(t, beta_at(3, i));
      s.control_points()[static_cast<size_t>(s.control_point_index(t, i))] =
          Point3(b.x(), b.y(), 0.57735026918962576 * std::fabs(b.x() - 0.5));
    }
  const Evaluator ev(s);
  const ShapeCheck c = check_shape(s, ev);
  EXPECT_TRUE(c.folded_triangles.empty());
  EXPECT_LT(c.max_normal_turn, 1);
}

TEST(ShapeCheck, SameResultForAnyThreadCountAndResolutionOutOfRangeIsRefused) {
  const Spline s = mapped(folding_polar);
  const Evaluator ev(s);
  const ShapeCheck a = check_shape(s, ev, 8, 1), b = check_shape(s, ev, 8, 2);
  EXPECT_EQ(a.folded_triangles, b.folded_triangles);
  EXPECT_EQ(a.max_normal_turn, b.max_normal_turn);
  EXPECT_EQ(a.max_stretch, b.max_stretch);
  EXPECT_THROW(check_shape(s, ev, 0), InvalidInput);
  EXPECT_THROW(check_shape(s, ev, 257), InvalidInput);
}

}  // namespace
}  // namespace tbs
