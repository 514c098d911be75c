// Folds and stretch of a spline, from normals sampled in every domain triangle (shape_check.h).

#include <tbs/atlas.h>
#include <tbs/errors.h>
#include <tbs/shape_check.h>
#include <tbs/tolerances.h>

#include "thread_arena.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>
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

Sample sample(const Evaluator& eval, const Point2& u, const OutlineIndex* trim = nullptr) {
  Sample s;
  if (eval.locate(u) < 0 || (trim && !trim->inside(u))) return s;
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

// A pair of neighbouring samples whose normals turn by more than 90 degrees: a fold if the
// turn, looked at closely enough, is a reversal between points within the tolerance.
struct Candidate {
  Point2 a, b;
  int triangles[2] = {-1, -1};
};

struct TriangleResult {
  double max_turn = 0;
  double max_speed = 0;
  size_t singular = 0;
  Box3 box;   // of the surface samples
  Box2 ubox;  // of their parameters
  std::vector<Candidate> candidates;
};

// Whether the normal reverses (turns by more than kFoldTurn) between a and b, or between two
// points of the segment ab that lie within `tolerance` of each other in space: the segment is
// halved until its ends are that close, at most kMaxHalvings times, following the halves that
// still turn by more than 90 degrees.
constexpr double kFoldTurn = 150;
constexpr int kMaxHalvings = 20;
bool reverses(const Evaluator& eval, const Point2& ua, const Sample& a, const Point2& ub, const Sample& b,
              double tolerance, int depth) {
  const double angle = turn(a, b);
  if (angle <= 90) return false;
  if ((a.position - b.position).norm() <= tolerance || depth >= kMaxHalvings) return angle > kFoldTurn;
  const Point2 um = 0.5 * (ua + ub);
  const Sample m = sample(eval, um);
  if (!m.inside || m.normal.isZero()) return angle > kFoldTurn;
  return reverses(eval, ua, a, um, m, tolerance, depth + 1) || reverses(eval, um, m, ub, b, tolerance, depth + 1);
}

}  // namespace

ShapeCheck check_shape(const Spline& spline, const Evaluator& eval, int resolution, int threads, double tolerance,
                       const Atlas& atlas) {
  if (resolution < 1 || resolution > 256)
    throw InvalidInput("check_shape: the resolution must be 1 to 256, not " + std::to_string(resolution));
  if (!(tolerance >= 0) || !std::isfinite(tolerance))
    throw InvalidInput("check_shape: the tolerance must be a finite number >= 0");
  const Domain& d = spline.domain();
  const int T = d.triangle_count();
  const int R = resolution;
  // With an atlas, the surface is the charts inside their outlines: the margins beyond are not
  // looked at.
  std::unique_ptr<OutlineIndex> trim;
  if (!atlas.empty()) trim = std::make_unique<OutlineIndex>(chart_outlines(atlas));
  std::vector<TriangleResult> tri(static_cast<size_t>(T));
  // The two sides of every smooth interior edge: the largest turn, per edge.
  std::vector<double> edge_turn(static_cast<size_t>(d.edge_count()), 0.0);
  std::vector<double> edge_speed(edge_turn.size(), 0.0);
  std::vector<size_t> edge_singular(edge_turn.size(), 0);
  std::vector<std::vector<Candidate>> edge_candidates(edge_turn.size());
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
      std::vector<Point2> at(s.size());
      auto index = [&](int i, int j) { return static_cast<size_t>(i * (R + 1) - i * (i - 1) / 2 + j); };
      for (int i = 0; i <= R; ++i)
        for (int j = 0; i + j <= R; ++j) {
          Sample& q = s[index(i, j)];
          at[index(i, j)] = point_in(t, static_cast<double>(i) / R, static_cast<double>(j) / R);
          q = sample(eval, at[index(i, j)], trim.get());
          r.max_speed = std::max(r.max_speed, q.speed);
          if (q.inside) r.box.extend(q.position), r.ubox.extend(at[index(i, j)]);
          if (q.inside && q.normal.isZero()) ++r.singular;
        }
      auto compare = [&](size_t a, size_t b) {
        const double angle = turn(s[a], s[b]);
        r.max_turn = std::max(r.max_turn, angle);
        if (angle > 90) r.candidates.push_back({at[a], at[b], {t, -1}});
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
        Point2 where[2];
        for (int m = 0; m < 2; ++m) {
          const auto& c = d.triangle(tr[static_cast<size_t>(m)]);
          const Point2 centroid = (d.vertex(c[0]) + d.vertex(c[1]) + d.vertex(c[2])) / 3.0;
          where[m] = p + kInside * (centroid - p);
          side[m] = sample(eval, where[m], trim.get());
          edge_speed[static_cast<size_t>(e)] = std::max(edge_speed[static_cast<size_t>(e)], side[m].speed);
          if (side[m].inside && side[m].normal.isZero()) ++edge_singular[static_cast<size_t>(e)];
        }
        const double angle = turn(side[0], side[1]);
        edge_turn[static_cast<size_t>(e)] = std::max(edge_turn[static_cast<size_t>(e)], angle);
        if (angle > 90) edge_candidates[static_cast<size_t>(e)].push_back({where[0], where[1], {tr[0], tr[1]}});
      }
    });
  });

  ShapeCheck out;
  // Per chart (domain component): the largest speed, the box of the surface samples and the
  // box of the domain.
  const Charts charts = domain_charts(d);
  std::vector<double> speed(static_cast<size_t>(charts.count), 0.0);
  std::vector<Box3> surface(static_cast<size_t>(charts.count));
  std::vector<Box2> dom(static_cast<size_t>(charts.count));
  Box3 whole;
  for (int t = 0; t < T; ++t) {
    const TriangleResult& r = tri[static_cast<size_t>(t)];
    const size_t c = static_cast<size_t>(charts.of_triangle[static_cast<size_t>(t)]);
    out.max_normal_turn = std::max(out.max_normal_turn, r.max_turn);
    speed[c] = std::max(speed[c], r.max_speed);
    out.singular_samples += r.singular;
    if (!r.box.empty()) {
      surface[c].extend(r.box.min);
      surface[c].extend(r.box.max);
      whole.extend(r.box.min);
      whole.extend(r.box.max);
    }
    if (trim) {
      if (!r.ubox.empty()) dom[c].extend(r.ubox.min), dom[c].extend(r.ubox.max);
    } else {
      for (int v : d.triangle(t)) dom[c].extend(d.vertex(v));
    }
  }
  for (int e = 0; e < d.edge_count(); ++e) {
    const size_t c = static_cast<size_t>(charts.of_triangle[static_cast<size_t>(d.edge_triangles(e)[0])]);
    out.max_normal_turn = std::max(out.max_normal_turn, edge_turn[static_cast<size_t>(e)]);
    speed[c] = std::max(speed[c], edge_speed[static_cast<size_t>(e)]);
    out.singular_samples += edge_singular[static_cast<size_t>(e)];
  }
  // The folds: candidates looked at closely, in parallel, each triangle's and edge's own.
  const double size = whole.empty() ? 0.0 : (whole.max - whole.min).norm();
  const double tol = tolerance > 0 ? tolerance : tol::kDefaultFoldTolerance * size;
  std::vector<char> folded(static_cast<size_t>(T), 0);
  std::vector<char> tri_folds(static_cast<size_t>(T), 0), edge_folds(static_cast<size_t>(d.edge_count()), 0);
  auto any_reverses = [&](const std::vector<Candidate>& list) {
    for (const Candidate& c : list)
      if (reverses(eval, c.a, sample(eval, c.a), c.b, sample(eval, c.b), tol, 0)) return true;
    return false;
  };
  detail::with_threads(threads, [&] {
    tbb::parallel_for(0, T, [&](int t) { tri_folds[static_cast<size_t>(t)] = any_reverses(tri[static_cast<size_t>(t)].candidates); });
    tbb::parallel_for(0, d.edge_count(), [&](int e) {
      edge_folds[static_cast<size_t>(e)] = any_reverses(edge_candidates[static_cast<size_t>(e)]);
    });
  });
  for (int t = 0; t < T; ++t)
    if (tri_folds[static_cast<size_t>(t)]) folded[static_cast<size_t>(t)] = 1;
  for (int e = 0; e < d.edge_count(); ++e)
    if (edge_folds[static_cast<size_t>(e)])
      for (int t : d.edge_triangles(e))
        if (t >= 0) folded[static_cast<size_t>(t)] = 1;
  for (int t = 0; t < T; ++t)
    if (folded[static_cast<size_t>(t)]) out.folded_triangles.push_back(t);
  for (int c = 0; c < charts.count; ++c) {
    const Box3& b = surface[static_cast<size_t>(c)];
    const double chart_size = b.empty() ? 0.0 : (b.max - b.min).norm();
    const Box2& db = dom[static_cast<size_t>(c)];
    const double diameter = db.empty() ? 0.0 : (db.max - db.min).norm();
    if (chart_size > 0) out.max_stretch = std::max(out.max_stretch, speed[static_cast<size_t>(c)] * diameter / chart_size);
  }
  return out;
}

}  // namespace tbs
