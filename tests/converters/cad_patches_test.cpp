#include <tbs/bezier.h>
#include <tbs/cad_patches.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/knots.h>
#include <tbs/predicates.h>

#include "random_spline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

namespace tbs {
namespace {

// A height field over the unit square, like a scan: control points at the blossom points
// (u, v, g(u, v)) with a smooth g, plus a crease of about 53 degrees along the feature line
// x = 0.5 when there is one. The knots are Traas's default ones, as a fit starts from.
Spline make_spline(int degree, bool features, uint64_t seed, int cells = 4) {
  test::GridOptions o;
  o.nx = o.ny = cells;
  o.feature_column = features ? cells / 2 : -1;
  const Spline r = test::random_spline(degree, o, seed);
  Spline s(degree, r.domain(), default_knots(r.domain(), degree), r.control_points(), r.control_point_map());
  for (int t = 0; t < s.domain().triangle_count(); ++t)
    for (int i = 0; i < beta_count(degree); ++i) {
      const Point2 b = s.blossom_point(t, beta_at(degree, i));
      const double z = 0.2 * std::sin(3 * b.x() + seed) * std::cos(2 * b.y()) +
                       (features ? 0.5 * std::fabs(b.x() - 0.5) : 0.0);
      s.control_points()[s.control_point_index(t, i)] = Point3(b.x(), b.y(), z);
    }
  return s;
}

Bary barycentric(const Point2& a, const Point2& b, const Point2& c, const Point2& u) {
  const double area = det3(a, b, c);
  return {det3(u, b, c) / area, det3(a, u, c) / area, det3(a, b, u) / area};
}

// The patch of triangle t that contains u, and u's barycentric coordinates in it.
std::pair<int, Bary> find_patch(const CadPatches& c, int t, const Point2& u) {
  int best = -1;
  Bary bb;
  double best_min = -1e300;
  for (int p = c.patch_start[t]; p < c.patch_start[t + 1]; ++p) {
    const auto& k = c.patches[p].corners;
    const Bary b = barycentric(c.vertex_parameters[k[0]], c.vertex_parameters[k[1]],
                               c.vertex_parameters[k[2]], u);
    if (b.minCoeff() > best_min) best_min = b.minCoeff(), best = p, bb = b;
  }
  return {best, bb};
}

double angle_deg(const Vector3& a, const Vector3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / M_PI;
}

Vector3 patch_normal(const CadPatches& c, int p, const Bary& b) {
  Point3 v;
  Vector3 d1, d2;
  bezier_derivatives(c.net(p), c.degree, b, v, d1, d2);
  return d1.cross(d2).normalized();
}

class CadPatchesTest : public ::testing::TestWithParam<int> {};

TEST_P(CadPatchesTest, WithinToleranceOfTheSplineAtRandomPoints) {
  const int n = GetParam();
  const Spline s = make_spline(n, false, 31);
  const CadPatches c = make_cad_patches(s);
  const Evaluator ev(s);
  ASSERT_TRUE(c.within_tolerance) << c.max_position_deviation << " " << c.max_normal_deviation;
  ASSERT_EQ(c.degree, n + 2);
  double worst = 0, worst_angle = 0;
  for (const Point2& u : test::random_domain_points(s.domain(), 20000, 7)) {
    const int t = ev.locate(u);
    const auto [p, b] = find_patch(c, t, u);
    ASSERT_GT(b.minCoeff(), -1e-12);
    const SurfacePoint f = ev.evaluate(u);
    worst = std::max(worst, (bezier_value(c.net(p), c.degree, b) - f.position).norm());
    worst_angle = std::max(worst_angle, angle_deg(patch_normal(c, p, b), f.du.cross(f.dv)));
  }
  EXPECT_LE(worst, c.tolerance);
  EXPECT_LE(worst_angle, c.angle_tolerance / 2);
  RecordProperty("patches", static_cast<int>(c.patches.size()));
  RecordProperty("worst_over_tolerance", std::to_string(worst / c.tolerance));
}

TEST_P(CadPatchesTest, BoundariesComeFromSharedEdgesBitForBit) {
  const Spline s = make_spline(GetParam(), true, 32);
  const CadPatches c = make_cad_patches(s);
  const int m = c.degree;
  std::vector<int> uses(c.edges.size(), 0);
  int t_junctions = 0;
  for (int p = 0; p < static_cast<int>(c.patches.size()); ++p) {
    const auto net = c.net(p);
    const auto& k = c.patches[p].corners;
    for (int j = 0; j < 3; ++j) {
      Beta g{0, 0, 0};
      g[j] = m;
      ASSERT_TRUE(net[beta_index(g)] == c.vertices[k[j]]);
    }
    // Walk the boundary: side k0 runs from corner 1 to corner 2, and so on.
    const auto& b = c.boundaries[p];
    ASSERT_GE(b.size(), 3u);
    size_t at = 0;
    for (int side = 0; side < 3; ++side) {
      const int from = k[(side + 1) % 3], to = k[(side + 2) % 3];
      const auto curve = bezier_side(net, m, side);
      std::vector<CadEdgeUse> chain;
      int v = from;
      while (v != to) {
        ASSERT_LT(at, b.size());
        const CadEdgeUse& u = b[at++];
        const CadEdge& e = c.edges[u.edge];
        ASSERT_EQ(e.vertices[u.reversed ? 1 : 0], v);
        v = e.vertices[u.reversed ? 0 : 1];
        chain.push_back(u);
        ++uses[u.edge];
      }
      if (chain.size() == 1) {
        auto cps = c.edges[chain[0].edge].control_points;
        if (chain[0].reversed) std::reverse(cps.begin(), cps.end());
        for (int i = 0; i <= m; ++i) ASSERT_TRUE(cps[i] == curve[i]) << "patch " << p << " side " << side;
      } else {
        // A long side next to smaller patches: each edge is a piece of the side's curve.
        ++t_junctions;
        const Point2 a = c.vertex_parameters[from], z = c.vertex_parameters[to];
        for (const CadEdgeUse& u : chain) {
          const CadEdge& e = c.edges[u.edge];
          for (double t : {0.25, 0.5, 0.75}) {
            const Point2 q = c.vertex_parameters[e.vertices[0]] +
                             t * (c.vertex_parameters[e.vertices[1]] - c.vertex_parameters[e.vertices[0]]);
            const double w = (q - a).norm() / (z - a).norm();
            EXPECT_LT((bezier_curve_value(e.control_points, t) - bezier_curve_value(curve, w)).norm(), 1e-12);
          }
        }
      }
    }
    ASSERT_EQ(at, b.size());
  }
  // Watertight: an edge has two patches unless it is on the domain boundary.
  for (size_t e = 0; e < c.edges.size(); ++e) {
    const int de = c.edges[e].domain_edge;
    const int expected = de >= 0 && s.domain().is_boundary_edge(de) ? 1 : 2;
    ASSERT_EQ(uses[e], expected) << "edge " << e;
  }
  RecordProperty("t_junctions", t_junctions);
}

TEST_P(CadPatchesTest, NormalsAgreeAcrossSmoothEdgesAndKeepTheJumpAtFeatures) {
  const Spline s = make_spline(GetParam(), true, 33);
  const CadPatches c = make_cad_patches(s);
  const Evaluator ev(s);
  ASSERT_TRUE(c.within_tolerance);
  // The two patches of each edge, with the edge's position in each.
  std::map<int, std::vector<std::pair<int, bool>>> users;
  for (int p = 0; p < static_cast<int>(c.patches.size()); ++p)
    for (const auto& u : c.boundaries[p]) users[u.edge].emplace_back(p, u.reversed);
  double smooth = 0, feature_error = 0, feature_jump = 1e300;
  int feature_edges = 0;
  for (const auto& [e, ps] : users) {
    if (ps.size() != 2) continue;
    const CadEdge& edge = c.edges[e];
    const Point2 a = c.vertex_parameters[edge.vertices[0]], b = c.vertex_parameters[edge.vertices[1]];
    for (double t : {0.2, 0.5, 0.8}) {
      const Point2 u = a + t * (b - a);
      Vector3 nrm[2], spline_nrm[2];
      for (int i = 0; i < 2; ++i) {
        const int p = ps[i].first;
        const auto& k = c.patches[p].corners;
        Bary bb = barycentric(c.vertex_parameters[k[0]], c.vertex_parameters[k[1]],
                              c.vertex_parameters[k[2]], u);
        bb = bb.cwiseMax(0.0) / bb.cwiseMax(0.0).sum();
        nrm[i] = patch_normal(c, p, bb);
        const Point2 centre = (c.vertex_parameters[k[0]] + c.vertex_parameters[k[1]] + c.vertex_parameters[k[2]]) / 3;
        const auto f = ev.evaluate(u, Perturbation::toward(u, centre, c.vertex_parameters[k[0]] == u ? c.vertex_parameters[k[1]] : c.vertex_parameters[k[0]]));
        ASSERT_TRUE(f);
        spline_nrm[i] = f->du.cross(f->dv).normalized();
      }
      if (edge.feature) {
        feature_error = std::max({feature_error, angle_deg(nrm[0], spline_nrm[0]), angle_deg(nrm[1], spline_nrm[1])});
        feature_jump = std::min(feature_jump, angle_deg(spline_nrm[0], spline_nrm[1]));
      } else {
        smooth = std::max(smooth, angle_deg(nrm[0], nrm[1]));
      }
    }
    if (edge.feature) ++feature_edges;
  }
  EXPECT_LE(smooth, c.angle_tolerance);
  ASSERT_GT(feature_edges, 3);
  EXPECT_GT(feature_jump, 1.0);  // the spline's crease is real ...
  EXPECT_LE(feature_error, c.angle_tolerance / 2 + 1e-9);  // ... and each side keeps its normal
}

INSTANTIATE_TEST_SUITE_P(Degrees, CadPatchesTest, ::testing::Values(2, 3, 4));

TEST(CadPatches, AnAffineSplineNeedsOnePatchPerTriangle) {
  Spline s = make_spline(3, true, 34);
  for (int t = 0; t < s.domain().triangle_count(); ++t)
    for (int i = 0; i < beta_count(3); ++i) {
      const Point2 b = s.blossom_point(t, beta_at(3, i));
      s.control_points()[s.control_point_index(t, i)] = Point3(2 * b.x() + 1, b.y() - b.x(), 0.5 * b.y());
    }
  const CadPatches c = make_cad_patches(s, {.degree = 3});
  EXPECT_EQ(c.patches.size(), static_cast<size_t>(s.domain().triangle_count()));
  EXPECT_LT(c.max_position_deviation, 1e-12);
  EXPECT_TRUE(c.within_tolerance);
}

TEST(CadPatches, LooserToleranceGivesFewerPatches) {
  const Spline s = make_spline(3, false, 35);
  const CadPatches tight = make_cad_patches(s, {.tolerance = 1e-6});
  const CadPatches loose = make_cad_patches(s, {.tolerance = 1e-3});
  EXPECT_LT(loose.patches.size(), tight.patches.size());
  EXPECT_LE(loose.max_position_deviation, loose.tolerance);
  EXPECT_GT(loose.max_position_deviation, tight.max_position_deviation);
}

TEST(CadPatches, SameResultForOneAndTwoThreads) {
  const Spline s = make_spline(3, true, 36);
  const CadPatches a = make_cad_patches(s, {.threads = 1});
  const CadPatches b = make_cad_patches(s, {.threads = 2});
  EXPECT_EQ(a.control_points, b.control_points);
  EXPECT_EQ(a.vertices, b.vertices);
}

TEST(CadPatches, RejectsBadOptions) {
  const Spline s = make_spline(3, false, 37, 2);
  EXPECT_THROW(make_cad_patches(s, {.degree = 2}), InvalidInput);
  EXPECT_THROW(make_cad_patches(s, {.degree = 16}), InvalidInput);
  EXPECT_THROW(make_cad_patches(s, {.tolerance = 0}), InvalidInput);
  EXPECT_THROW(make_cad_patches(s, {.angle_tolerance = -1}), InvalidInput);
  EXPECT_THROW(make_cad_patches(s, {.max_level = 40}), InvalidInput);
  EXPECT_THROW(make_cad_patches(s, {.max_patches = s.domain().triangle_count() - 1}), InvalidInput);
}

TEST(CadPatches, StopsAtThePatchBudgetAndSaysSo) {
  const Spline s = make_spline(3, false, 39);
  const long budget = 3L * s.domain().triangle_count();
  const CadPatches c = make_cad_patches(s, {.tolerance = 1e-12, .max_patches = budget});
  EXPECT_TRUE(c.budget_reached);
  EXPECT_FALSE(c.within_tolerance);
  EXPECT_LE(static_cast<long>(c.patches.size()), budget);
  // The budget is used: the worst patches split until no further split fits.
  EXPECT_GT(static_cast<long>(c.patches.size()), budget - 3);
  EXPECT_GT(c.max_position_deviation, c.tolerance);
  // Without the budget the same tolerance takes more patches.
  const CadPatches d = make_cad_patches(s, {.tolerance = 1e-12, .max_level = 3});
  EXPECT_FALSE(d.budget_reached);
  EXPECT_GT(d.patches.size(), c.patches.size());
}

// A crease that ends inside the surface: at its last vertex the spline's normal has no limit
// (the crease's angle on one side, none beyond), and no patch can follow it there. Splitting
// for the normals stops where two splits did not help, instead of going to the deepest level
// around that vertex, and the result says that the angle tolerance is missed.
TEST(CadPatches, ANormalThatJumpsAtAVertexDoesNotSplitForever) {
  const Spline full = make_spline(3, true, 40, 8);
  const Domain& fd = full.domain();
  std::vector<std::array<int, 2>> lower;
  for (const auto& e : fd.feature_edges())
    if (std::max(fd.vertex(e[0]).y(), fd.vertex(e[1]).y()) <= 0.5) lower.push_back(e);
  ASSERT_GE(lower.size(), 2u);
  const Domain d(fd.vertices(), fd.triangles(), lower);
  Spline s(3, d, default_knots(d, 3), full.control_points(), full.control_point_map());
  const int T = d.triangle_count();
  const CadPatches c = make_cad_patches(s, {.tolerance = 1e-3, .angle_tolerance = 1});
  EXPECT_FALSE(c.budget_reached);
  EXPECT_LT(c.patches.size(), 400u * T) << c.patches.size() << " patches for " << T << " triangles";
  EXPECT_GT(c.max_normal_deviation, 0.5);
  EXPECT_FALSE(c.within_tolerance);
  EXPECT_LE(c.max_position_deviation, c.tolerance);
}

// A degree-1 spline is linear in each domain triangle, and its normal jumps across every
// domain edge. Each patch follows its own triangle's normal up to its edges: one patch per
// triangle. (Points computed on an edge lie off it by rounding, on either side; evaluated
// there, the other triangle's normal made every patch split to the deepest level.)
TEST(CadPatches, NormalsThatJumpAcrossEdgesNeedNoSplits) {
  const Spline s = make_spline(1, false, 40, 2);
  const int T = s.domain().triangle_count();
  const CadPatches c = make_cad_patches(s, {.degree = 3, .tolerance = 1e-3, .angle_tolerance = 1});
  EXPECT_EQ(static_cast<int>(c.patches.size()), T);
  EXPECT_TRUE(c.within_tolerance) << c.max_normal_deviation << " degrees";
}

TEST(CadPatches, ReportsWhenTheDepthLimitStopsIt) {
  const Spline s = make_spline(4, false, 38);
  const CadPatches c = make_cad_patches(s, {.degree = 4, .tolerance = 1e-13, .max_level = 1});
  EXPECT_FALSE(c.within_tolerance);
  EXPECT_GT(c.max_position_deviation, c.tolerance);
  for (const auto& p : c.patches) EXPECT_LE(p.level, 1);
}

}  // namespace
}  // namespace tbs
