#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/knots.h>
#include <tbs/predicates.h>
#include <tbs/tessellate.h>

#include "random_spline.h"

#include <gtest/gtest.h>

#include <map>

namespace tbs {
namespace {

Spline make_spline(int degree, uint64_t seed) {
  test::GridOptions o;
  o.nx = o.ny = 5;
  o.hole = false;
  o.feature_column = 2;
  return test::random_spline(degree, o, seed);
}

Spline make_holed(int degree, uint64_t seed) {
  test::GridOptions o;
  o.nx = o.ny = 6;
  o.hole = true;
  return test::random_spline(degree, o, seed);
}

// Faces per undirected edge.
std::map<std::pair<int, int>, int> edge_faces(const Mesh& m) {
  std::map<std::pair<int, int>, int> count;
  for (const auto& f : m.faces)
    for (int k = 0; k < 3; ++k) ++count[{std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])}];
  return count;
}

// True if the parameter segment a-b lies on the domain boundary: just beside its midpoint,
// on one side, there is no domain.
bool on_boundary(const Evaluator& ev, const Point2& a, const Point2& b) {
  const Point2 mid = (a + b) / 2, n(b.y() - a.y(), a.x() - b.x());
  return ev.locate(mid + 1e-7 * n.normalized()) < 0 || ev.locate(mid - 1e-7 * n.normalized()) < 0;
}

void check_mesh(const Spline& s, const Mesh& m, bool split) {
  const Evaluator ev(s);
  ASSERT_EQ(m.positions.size(), m.parameters.size());
  ASSERT_EQ(m.normals.size(), m.parameters.size());
  ASSERT_EQ(m.face_triangle.size(), m.faces.size());
  // Watertight: interior edges have two faces, boundary edges (one face) lie on the domain
  // boundary, or on a feature edge when the mesh is split there.
  for (const auto& [e, n] : edge_faces(m)) {
    ASSERT_LE(n, 2);
    if (n == 2) continue;
    const Point2 &a = m.parameters[e.first], &b = m.parameters[e.second];
    if (on_boundary(ev, a, b)) continue;
    ASSERT_TRUE(split) << "open edge inside the domain at " << a.transpose() << " - " << b.transpose();
  }
  // Vertices on the surface, normals of the spline.
  for (size_t v = 0; v < m.positions.size(); ++v) {
    const Point2& u = m.parameters[v];
    ASSERT_LT((ev.value(u) - m.positions[v]).norm(), 1e-12) << v;
  }
  // Faces: counter-clockwise, in their domain triangle. Normals: the spline's, on the side of
  // each face that uses the vertex.
  std::vector<std::vector<Vector3>> sides(m.positions.size());
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const auto& fc = m.faces[f];
    const Point2 &a = m.parameters[fc[0]], &b = m.parameters[fc[1]], &c = m.parameters[fc[2]];
    ASSERT_GT(det3(a, b, c), 0) << "face " << f;
    const Point2 centre = (a + b + c) / 3;
    ASSERT_EQ(ev.locate(centre), m.face_triangle[f]);
    for (int k = 0; k < 3; ++k) {
      const Point2& u = m.parameters[fc[k]];
      const auto side = ev.evaluate(u, Perturbation::toward(u, centre, m.parameters[fc[(k + 1) % 3]]));
      ASSERT_TRUE(side);
      sides[fc[k]].push_back(side->du.cross(side->dv).normalized());
    }
  }
  int creased = 0;
  for (size_t v = 0; v < sides.size(); ++v) {
    bool all_same = true, one_of = false;
    for (const Vector3& n : sides[v]) {
      all_same = all_same && (n - sides[v][0]).norm() < 1e-9;
      one_of = one_of || (m.normals[v] - n).norm() < 1e-9;
    }
    if (split || all_same) {
      // Smooth here, or split: every face around the vertex has the vertex's normal.
      for (const Vector3& n : sides[v]) ASSERT_LT((m.normals[v] - n).norm(), 1e-9) << "vertex " << v;
    } else {
      // A crease vertex shared by both sides carries the normal of one of them.
      ASSERT_TRUE(one_of) << "vertex " << v;
      ++creased;
    }
  }
  if (!split) ::testing::Test::RecordProperty("crease_vertices", creased);
}

TEST(Tessellate, UniformMeshIsWatertightOnTheSurfaceWithSplineNormals) {
  for (int degree : {2, 3, 4}) {
    const Spline s = make_spline(degree, 40 + degree);
    const Mesh m = tessellate(s, {.resolution = 5});
    ASSERT_EQ(m.faces.size(), static_cast<size_t>(25 * s.domain().triangle_count()));
    check_mesh(s, m, false);
  }
}

TEST(Tessellate, DomainWithAHole) {
  const Spline s = make_holed(3, 44);
  const Mesh m = tessellate(s, {.resolution = 4});
  check_mesh(s, m, false);
  // Two boundary loops' worth of open edges: the outer square and the hole.
  int open = 0;
  for (const auto& [e, n] : edge_faces(m)) open += n == 1;
  int boundary_edges = 0;
  for (int e = 0; e < s.domain().edge_count(); ++e) boundary_edges += s.domain().is_boundary_edge(e);
  EXPECT_EQ(open, 4 * boundary_edges);
}

TEST(Tessellate, SplitFeaturesGivesEachSideItsNormal) {
  const Spline s = make_spline(3, 45);
  const Mesh joined = tessellate(s, {.resolution = 4});
  const Mesh split = tessellate(s, {.resolution = 4, .split_features = true});
  check_mesh(s, split, true);
  EXPECT_GT(split.positions.size(), joined.positions.size());
  // Copies: same parameter and position, different normals.
  std::map<std::pair<double, double>, std::vector<int>> at;
  for (size_t v = 0; v < split.parameters.size(); ++v) at[{split.parameters[v].x(), split.parameters[v].y()}].push_back(v);
  int creased = 0;
  for (const auto& [u, vs] : at) {
    if (vs.size() < 2) continue;
    EXPECT_TRUE(split.positions[vs[0]] == split.positions[vs[1]]);
    if ((split.normals[vs[0]] - split.normals[vs[1]]).norm() > 1e-3) ++creased;
  }
  EXPECT_GT(creased, 10);
}

// A smooth height field with the default knots: random knots and control points make
// surfaces with spikes no resolution below 64 follows to 1e-3.
Spline smooth_spline(uint64_t seed) {
  const Spline r = make_spline(3, seed);
  Spline s(3, r.domain(), default_knots(r.domain(), 3), r.control_points(), r.control_point_map());
  for (int t = 0; t < s.domain().triangle_count(); ++t)
    for (int i = 0; i < beta_count(3); ++i) {
      const Point2 b = s.blossom_point(t, beta_at(3, i));
      Point3& c = s.control_points()[s.control_point_index(t, i)];
      c = Point3(b.x(), b.y(), 0.1 * c.z());
    }
  return s;
}

TEST(Tessellate, AdaptiveMeetsTheChordalTolerance) {
  const Spline s = smooth_spline(46);
  const Mesh coarse = tessellate(s, {.chordal_tolerance = 1e-2});
  const Mesh fine = tessellate(s, {.chordal_tolerance = 1e-3});
  check_mesh(s, fine, false);
  Box3 box;
  for (const auto& c : s.control_points()) box.extend(c);
  const double size = (box.max - box.min).norm();
  EXPECT_LE(coarse.max_chordal_deviation, 1e-2 * size);
  EXPECT_LE(fine.max_chordal_deviation, 1e-3 * size);
  EXPECT_LT(coarse.faces.size(), fine.faces.size());
  // Adaptive: not every triangle needs the same resolution.
  EXPECT_NE(*std::min_element(fine.resolution.begin(), fine.resolution.end()),
            *std::max_element(fine.resolution.begin(), fine.resolution.end()));
}

TEST(Tessellate, SameMeshForOneAndTwoThreads) {
  const Spline s = smooth_spline(47);
  const Mesh a = tessellate(s, {.chordal_tolerance = 3e-3, .threads = 1});
  const Mesh b = tessellate(s, {.chordal_tolerance = 3e-3, .threads = 2});
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.positions, b.positions);
}

TEST(Tessellate, RejectsBadOptions) {
  const Spline s = make_spline(2, 48);
  EXPECT_THROW(tessellate(s, {.resolution = 0}), InvalidInput);
  EXPECT_THROW(tessellate(s, {.chordal_tolerance = -1}), InvalidInput);
  EXPECT_THROW(tessellate(s, {.chordal_tolerance = 1e-3, .max_resolution = 0}), InvalidInput);
}

}  // namespace
}  // namespace tbs
