#include <tbs/domain.h>
#include <tbs/errors.h>

#include "random_spline.h"

#include <gtest/gtest.h>

namespace tbs {
namespace {

using Tris = std::vector<std::array<int, 3>>;

std::vector<Point2> square() { return {{0, 0}, {1, 0}, {1, 1}, {0, 1}}; }

std::string error_of(const std::vector<Point2>& v, const Tris& t,
                     std::vector<std::array<int, 2>> f = {}) {
  try {
    Domain d(v, t, f);
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "";
}

TEST(Domain, GridTopology) {
  test::GridOptions o;
  o.nx = 4;
  o.ny = 3;
  const Domain d = test::grid_domain(o, 1);
  EXPECT_EQ(d.vertex_count(), 20);
  EXPECT_EQ(d.triangle_count(), 24);
  EXPECT_EQ(d.edge_count(), 20 + 24 - 1);  // Euler: V - E + F = 1
  ASSERT_EQ(d.boundary_loops().size(), 1u);
  EXPECT_EQ(d.boundary_loops()[0].size(), 14u);
  for (int e = 0; e < d.edge_count(); ++e) {
    const auto et = d.edge_triangles(e);
    EXPECT_GE(et[0], 0);
  }
}

TEST(Domain, HoleIsAClockwiseLoop) {
  test::GridOptions o;
  o.nx = o.ny = 6;
  o.hole = true;
  const Domain d = test::grid_domain(o, 2);
  ASSERT_EQ(d.boundary_loops().size(), 2u);
  int cw = 0;
  for (const auto& loop : d.boundary_loops()) {
    double a = 0;
    for (size_t i = 0; i < loop.size(); ++i) {
      const Point2& p = d.vertex(loop[i]);
      const Point2& q = d.vertex(loop[(i + 1) % loop.size()]);
      a += p.x() * q.y() - p.y() * q.x();
    }
    cw += a < 0;
  }
  EXPECT_EQ(cw, 1);
}

TEST(Domain, RejectsClockwiseTriangle) {
  EXPECT_NE(error_of(square(), {{0, 2, 1}}).find("clockwise"), std::string::npos);
}

TEST(Domain, RejectsDegenerateTriangle) {
  EXPECT_NE(error_of({{0, 0}, {1, 0}, {2, 0}}, {{0, 1, 2}}).find("degenerate"), std::string::npos);
}

TEST(Domain, RejectsIndexOutOfRange) {
  EXPECT_NE(error_of(square(), {{0, 1, 7}}).find("out of range"), std::string::npos);
}

TEST(Domain, RejectsRepeatedVertex) {
  EXPECT_NE(error_of(square(), {{0, 1, 1}}).find("repeats"), std::string::npos);
}

TEST(Domain, RejectsUnusedVertex) {
  EXPECT_NE(error_of(square(), {{0, 1, 2}}).find("vertex 3"), std::string::npos);
}

TEST(Domain, RejectsNonManifoldEdge) {
  // Three triangles on edge (0, 1).
  const std::vector<Point2> v{{0, 0}, {1, 0}, {0.5, 1}, {0.5, -1}, {0.5, 2}};
  const auto msg = error_of(v, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  EXPECT_NE(msg.find("edge (0, 1)"), std::string::npos) << msg;
}

TEST(Domain, RejectsPinchVertex) {
  // Two triangles touching at vertex 0 only.
  const std::vector<Point2> v{{0, 0}, {1, 0}, {1, 1}, {-1, 0}, {-1, -1}};
  const auto msg = error_of(v, {{0, 1, 2}, {0, 3, 4}});
  EXPECT_NE(msg.find("pinch"), std::string::npos) << msg;
}

TEST(Domain, RejectsOverlap) {
  // Two separate triangles that overlap in the plane.
  const std::vector<Point2> v{{0, 0}, {2, 0}, {0, 2}, {0.5, 0.5}, {3, 0.5}, {0.5, 3}};
  const auto msg = error_of(v, {{0, 1, 2}, {3, 4, 5}});
  EXPECT_NE(msg.find("intersects itself"), std::string::npos) << msg;
}

TEST(Domain, RejectsNonFinite) {
  auto v = square();
  v[2].x() = std::nan("");
  EXPECT_NE(error_of(v, {{0, 1, 2}, {0, 2, 3}}).find("non-finite"), std::string::npos);
}

TEST(Domain, FeatureEdgesMustBeInteriorEdges) {
  EXPECT_NE(error_of(square(), {{0, 1, 2}, {0, 2, 3}}, {{0, 1}}).find("boundary"), std::string::npos);
  EXPECT_NE(error_of(square(), {{0, 1, 2}, {0, 2, 3}}, {{1, 3}}).find("not an edge"), std::string::npos);
  const Domain d(square(), {{0, 1, 2}, {0, 2, 3}}, {{2, 0}});
  ASSERT_EQ(d.feature_edges().size(), 1u);
  EXPECT_TRUE(d.is_feature_edge(d.find_edge(0, 2)));
}

TEST(Domain, MoveVertexRefusesFlips) {
  Domain d({{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5, 0.5}},
           {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}});
  d.move_vertex(4, {0.6, 0.4});
  EXPECT_EQ(d.vertex(4), Point2(0.6, 0.4));
  EXPECT_THROW(d.move_vertex(4, {2, 2}), InvalidInput);
  EXPECT_EQ(d.vertex(4), Point2(0.6, 0.4));
}

}  // namespace
}  // namespace tbs
