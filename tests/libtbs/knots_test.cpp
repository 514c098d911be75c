#include <tbs/errors.h>
#include <tbs/knots.h>
#include <tbs/predicates.h>

#include "random_spline.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <gtest/gtest.h>

#include <numbers>
#include <random>

namespace tbs {
namespace {

// A Delaunay triangulation of random points in a disk, plus the disk's rim: general position,
// sharp convex boundary corners.
Domain delaunay_domain(int count, uint64_t seed) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using DT = CGAL::Delaunay_triangulation_2<K>;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0, 1);
  std::vector<K::Point_2> pts;
  for (int i = 0; i < count; ++i) {
    const double r = std::sqrt(uni(rng)), a = 2 * std::numbers::pi * uni(rng);
    pts.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  DT dt(pts.begin(), pts.end());
  std::vector<Point2> verts;
  std::map<DT::Vertex_handle, int> id;
  for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) {
    id[v] = static_cast<int>(verts.size());
    verts.emplace_back(v->point().x(), v->point().y());
  }
  std::vector<std::array<int, 3>> tris;
  for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f)
    tris.push_back({id[f->vertex(0)], id[f->vertex(1)], id[f->vertex(2)]});
  return Domain(verts, tris);
}

// An L-shaped domain: reflex corner at (1, 1).
Domain l_shape() {
  std::vector<Point2> v{{0, 0}, {1, 0}, {2, 0}, {0, 1}, {1, 1}, {2, 1}, {0, 2}, {1, 2}};
  return Domain(v, {{0, 1, 4}, {0, 4, 3}, {1, 2, 5}, {1, 5, 4}, {3, 4, 7}, {3, 7, 6}});
}

class DefaultKnots : public ::testing::TestWithParam<int> {};

TEST_P(DefaultKnots, PassTheCheckOnManyDomains) {
  const int n = GetParam();
  std::vector<Domain> domains;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    test::GridOptions o;
    o.nx = 6;
    o.ny = 5;
    domains.push_back(test::grid_domain(o, seed));
    o.hole = true;
    o.nx = o.ny = 8;
    domains.push_back(test::grid_domain(o, seed));
    o.hole = false;
    o.feature_column = 3;
    domains.push_back(test::grid_domain(o, seed));
    o.feature_kink = true;
    domains.push_back(test::grid_domain(o, seed));
    domains.push_back(delaunay_domain(200, seed));
  }
  domains.push_back(l_shape());
  for (size_t i = 0; i < domains.size(); ++i) {
    const auto knots = default_knots(domains[i], n);
    const KnotCheck check = check_knot_conditions(domains[i], n, knots);
    EXPECT_TRUE(check.ok()) << "domain " << i << ":\n" << check.summary();
    // Deterministic.
    EXPECT_EQ(knots, default_knots(domains[i], n));
  }
}

INSTANTIATE_TEST_SUITE_P(Degrees, DefaultKnots, ::testing::Values(1, 2, 3, 4, 5, 6));

TEST(KnotCheck, NamesTheDegenerateX) {
  test::GridOptions o;
  const Domain d = test::grid_domain(o, 5);
  const int n = 3;
  auto knots = default_knots(d, n);
  // Put t_{a,2} on the line through the other two corners of a triangle: X_{(2,0,0)} degenerates.
  const int t = 7;
  const auto& tri = d.triangle(t);
  knots[tri[0] * (n + 1) + 2] = 0.5 * (d.vertex(tri[1]) + d.vertex(tri[2]));
  const KnotCheck check = check_knot_conditions(d, n, knots);
  ASSERT_FALSE(check.ok());
  bool found = false;
  for (const auto& issue : check.issues)
    if (issue.condition == "orientation" && issue.triangle == t && issue.vertex == tri[0]) {
      found = true;
      EXPECT_EQ(issue.beta[0], 2);
      EXPECT_NE(issue.message.find("t_{" + std::to_string(tri[0]) + ",2}"), std::string::npos)
          << issue.message;
    }
  EXPECT_TRUE(found) << check.summary();
}

TEST(KnotCheck, NamesTheBoundaryVertexWithAKnotInside) {
  test::GridOptions o;
  const Domain d = test::grid_domain(o, 5);
  const int n = 2;
  auto knots = default_knots(d, n);
  const int v = d.boundary_loops()[0][0];
  // Move a sub-knot just inside the domain.
  const Point2 inward = (d.vertex(d.boundary_prev(v)) + d.vertex(d.boundary_next(v))) / 2 - d.vertex(v);
  Point2 c = Point2::Zero();
  for (int t : d.vertex_triangles(v))
    for (int w : d.triangle(t)) c += d.vertex(w);
  c /= 3.0 * d.vertex_triangles(v).size();
  knots[v * (n + 1) + 1] = d.vertex(v) + 0.05 * (c - d.vertex(v));
  (void)inward;
  const KnotCheck check = check_knot_conditions(d, n, knots);
  ASSERT_FALSE(check.ok());
  bool found = false;
  for (const auto& issue : check.issues) found = found || (issue.condition == "boundary" && issue.vertex == v);
  EXPECT_TRUE(found) << check.summary();
}

TEST(KnotCheck, CommonInteriorFailsForFarKnots) {
  test::GridOptions o;
  o.jitter = 0;
  const Domain d = test::grid_domain(o, 4);
  const int n = 3;
  auto knots = default_knots(d, n);
  // An interior vertex whose sub-knot moves most of the way to a neighbour: X triangles stay
  // oriented in some triangles but lose their common interior point.
  int v = -1;
  for (int i = 0; i < d.vertex_count() && v < 0; ++i)
    if (!d.is_boundary_vertex(i)) v = i;
  ASSERT_GE(v, 0);
  const auto& tri = d.triangle(d.vertex_triangles(v)[0]);
  const int w = tri[0] == v ? tri[1] : tri[0];
  knots[v * (n + 1) + 1] = d.vertex(v) + 0.9 * (d.vertex(w) - d.vertex(v));
  const KnotCheck check = check_knot_conditions(d, n, knots);
  EXPECT_FALSE(check.ok());
}

TEST(KnotCheck, NonFinite) {
  test::GridOptions o;
  const Domain d = test::grid_domain(o, 4);
  auto knots = default_knots(d, 2);
  knots[5].y() = std::numeric_limits<double>::infinity();
  const KnotCheck check = check_knot_conditions(d, 2, knots);
  ASSERT_FALSE(check.ok());
  EXPECT_EQ(check.issues[0].condition, "finite");
}

TEST(FeatureServers, EveryFeatureVertexServesALineAndEveryEdgeIsServed) {
  test::GridOptions o;
  o.nx = o.ny = 7;
  o.jitter = 0;
  o.feature_column = 3;
  const Domain d = test::grid_domain(o, 1);
  const auto server = feature_servers(d);
  const auto serves = [&](int p, int q) {
    return server[p] >= 0 && orientation(d.vertex(p), d.vertex(server[p]), d.vertex(q)) == 0;
  };
  for (const auto& e : d.feature_edges()) {
    EXPECT_TRUE(serves(e[0], e[1]) || serves(e[1], e[0])) << e[0] << " " << e[1];
    // Interior feature vertices all put their sub-knots on the line (the paper's constraint);
    // a boundary end only when its ray leaves the domain.
    for (int v : e)
      if (!d.is_boundary_vertex(v)) {
        EXPECT_GE(server[v], 0) << v;
      }
  }
}

class Continuity : public ::testing::TestWithParam<int> {};

TEST_P(Continuity, FeatureEdgesAreC0AndOtherEdgesSmooth) {
  const int n = GetParam();
  for (bool kink : {false, true}) {
    test::GridOptions o;
    o.nx = o.ny = 6;
    o.feature_column = 3;
    o.feature_kink = kink;
    const Domain d = test::grid_domain(o, 3);
    const auto knots = default_knots(d, n);
    const auto cont = edge_continuity(d, n, knots);
    for (int e = 0; e < d.edge_count(); ++e) {
      if (d.is_feature_edge(e))
        EXPECT_EQ(cont[e], 0) << "feature edge " << e << " kink " << kink;
      else
        EXPECT_EQ(cont[e], n - 1) << "edge " << e << " kink " << kink;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Degrees, Continuity, ::testing::Values(2, 3, 4, 5));

}  // namespace
}  // namespace tbs
