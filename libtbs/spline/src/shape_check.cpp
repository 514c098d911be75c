// Folds and stretch of a spline, from normals sampled in every domain triangle (shape_check.h).

#include <tbs/errors.h>
#include <tbs/shape_check.h>

#include "thread_arena.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace tbs {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Samples keep this barycentric distance from the triangle's edges: well past rounding, so
// that each lies on its own triangle's side of a knot line that runs along an edge.
constexpr double kInside = 1e-4;
// F_u x F_v below this fraction of |F_u| |F_v|: no normal to compare.
constexpr double kSingular = 1e-12;

struct Sample {
  Vector3 normal = Vector3::Zero();  // unit, or zero where singular
  double speed = 0;                  // max(|F_u|, |F_v|)
  Point3 position = Point3::Zero();
  bool inside = false;
};

Sample sample(const Evaluator& eval, const Point2& u) {
  Sample s;
  if (eval.locate(u) < 0) return s;
  const SurfacePoint p = eval.evaluate(u);
  s.inside = true;
  s.position = p.position;
  s.speed = std::max(p.du.norm(), p.dv.norm());
  const Vector3 n = p.du.cross(p.dv);
  if (n.norm() > kSingular * p.du.norm() * p.dv.norm()) s.normal = n.normalized();
  return s;
}

// Degrees between two unit normals; -1 when either is missing.
double turn(const Sample& a, const Sample& b) {
  if (a.normal.isZero() || b.normal.isZero()) return -1;
  return std::atan2(a.normal.cross(b.normal).norm(), a.normal.dot(b.normal)) * 180 / kPi;
}

struct TriangleResult {
  bool folded = false;
  double max_turn = 0;
  double max_speed = 0;
  size_t singular = 0;
  Box3 box;  // of the surface samples
};

}  // namespace

ShapeCheck check_shape(const Spline& spline, const Evaluator& eval, int resolution, int threads) {
  if (resolution < 1 || resolution > 256)
    throw InvalidInput("check_shape: the resolution must be 1 to 256, not " + std::to_string(resolution));
  const Domain& d = spline.domain();
  const int T = d.triangle_count();
  const int R = resolution;
  std::vector<TriangleResult> tri(static_cast<size_t>(T));
  // The two sides of every smooth interior edge: the largest turn, per edge.
  std::vector<double> edge_turn(static_cast<size_t>(d.edge_count()), 0.0);
  std::vector<double> edge_speed(edge_turn.size(), 0.0);
  std::vector<size_t> edge_singular(edge_turn.size(), 0);
  auto point_in = [&](int t, double b1, double b2) {
    const auto& c = d.triangle(t);
    const double s1 = kInside / 3 + (1 - kInside) * b1, s2 = kInside / 3 + (1 - kInside) * b2;
    return Point2((1 - s1 - s2) * d.vertex(c[0]) + s1 * d.vertex(c[1]) + s2 * d.vertex(c[2]));
  };
  detail::with_threads(threads, [&] {
    tbb::parallel_for(0, T, [&](int t) {
      TriangleResult& r = tri[static_cast<size_t>(t)];
      // Lattice (i, j), i + j <= R, at barycentric (i / R, j / R) for corners 1 and 2.
      std::vector<Sample> s(static_cast<size_t>((R + 1) * (R + 2) / 2));
      auto index = [&](int i, int j) { return static_cast<size_t>(i * (R + 1) - i * (i - 1) / 2 + j); };
      for (int i = 0; i <= R; ++i)
        for (int j = 0; i + j <= R; ++j) {
          Sample& q = s[index(i, j)];
          q = sample(eval, point_in(t, static_cast<double>(i) / R, static_cast<double>(j) / R));
          r.max_speed = std::max(r.max_speed, q.speed);
          if (q.inside) r.box.extend(q.position);
          if (q.normal.isZero()) ++r.singular;
        }
      auto compare = [&](size_t a, size_t b) {
        const double angle = turn(s[a], s[b]);
        r.max_turn = std::max(r.max_turn, angle);
        if (angle > 90) r.folded = true;
      };
      for (int i = 0; i <= R; ++i)
        for (int j = 0; i + j <= R; ++j) {
          if (i + j < R) {
            compare(index(i, j), index(i + 1, j));
            compare(index(i, j), index(i, j + 1));
            compare(index(i + 1, j), index(i, j + 1));
          }
        }
    });
    tbb::parallel_for(0, d.edge_count(), [&](int e) {
      const auto tr = d.edge_triangles(e);
      if (tr[1] < 0 || d.is_feature_edge(e)) return;
      const Point2 &a = d.vertex(d.edges()[static_cast<size_t>(e)][0]), &b = d.vertex(d.edges()[static_cast<size_t>(e)][1]);
      for (int k = 0; k < R; ++k) {
        const Point2 p = a + (k + 0.5) / R * (b - a);
        Sample side[2];
        for (int m = 0; m < 2; ++m) {
          const auto& c = d.triangle(tr[static_cast<size_t>(m)]);
          const Point2 centroid = (d.vertex(c[0]) + d.vertex(c[1]) + d.vertex(c[2])) / 3.0;
          side[m] = sample(eval, p + kInside * (centroid - p));
          edge_speed[static_cast<size_t>(e)] = std::max(edge_speed[static_cast<size_t>(e)], side[m].speed);
          if (side[m].normal.isZero()) ++edge_singular[static_cast<size_t>(e)];
        }
        edge_turn[static_cast<size_t>(e)] = std::max(edge_turn[static_cast<size_t>(e)], turn(side[0], side[1]));
      }
    });
  });

  ShapeCheck out;
  double speed = 0;
  Box3 surface;
  std::vector<char> folded(static_cast<size_t>(T), 0);
  for (int t = 0; t < T; ++t) {
    const TriangleResult& r = tri[static_cast<size_t>(t)];
    folded[static_cast<size_t>(t)] = r.folded;
    out.max_normal_turn = std::max(out.max_normal_turn, r.max_turn);
    speed = std::max(speed, r.max_speed);
    out.singular_samples += r.singular;
    if (!r.box.empty()) {
      surface.extend(r.box.min);
      surface.extend(r.box.max);
    }
  }
  for (int e = 0; e < d.edge_count(); ++e) {
    out.max_normal_turn = std::max(out.max_normal_turn, edge_turn[static_cast<size_t>(e)]);
    speed = std::max(speed, edge_speed[static_cast<size_t>(e)]);
    out.singular_samples += edge_singular[static_cast<size_t>(e)];
    if (edge_turn[static_cast<size_t>(e)] > 90)
      for (int t : d.edge_triangles(e)) folded[static_cast<size_t>(t)] = 1;
  }
  for (int t = 0; t < T; ++t)
    if (folded[static_cast<size_t>(t)]) out.folded_triangles.push_back(t);
  const double size = surface.empty() ? 0.0 : (surface.max - surface.min).norm();
  const Box2 dom = d.bounding_box();
  const double diameter = d.vertex_count() > 0 ? (dom.max - dom.min).norm() : 0.0;
  out.max_stretch = size > 0 ? speed * diameter / size : 0.0;
  return out;
}

}  // namespace tbs
