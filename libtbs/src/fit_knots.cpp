#include "fit_knots.h"

#include <tbs/knots.h>
#include <tbs/predicates.h>
#include <tbs/tolerances.h>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace tbs::detail {
namespace {


double tri_area(const Domain& d, int t) {
  const auto& tri = d.triangle(t);
  return 0.5 * det3(d.vertex(tri[0]), d.vertex(tri[1]), d.vertex(tri[2]));
}

}  // namespace

namespace {

struct VertexResult {
  bool tried = false, moved = false, primary_moved = false;
  double before = 0, after = 0;
  std::vector<Point2> knots;
};

// OptimizeKnot(t_s) on one spline copy: pattern search, accepting only improvements.
VertexResult optimize_vertex(Spline& spline, Evaluator& eval, int s, std::vector<int>& located,
                             std::vector<std::vector<int>>& tri_points, const FitPoints& pts,
                             double lambda) {
  const Domain& d = spline.domain();
  const int n = spline.degree();
  VertexResult res;
  const bool boundary = d.is_boundary_vertex(s);
  const std::vector<int> star(d.vertex_triangles(s).begin(), d.vertex_triangles(s).end());
  std::vector<int> ring2, local;
  for (int t : star)
    for (int v : d.triangle(t))
      for (int u : d.vertex_triangles(v)) ring2.push_back(u);
  std::sort(ring2.begin(), ring2.end());
  ring2.erase(std::unique(ring2.begin(), ring2.end()), ring2.end());
  for (int t : ring2) local.insert(local.end(), tri_points[t].begin(), tri_points[t].end());
  if (local.empty()) return res;
  std::sort(local.begin(), local.end());
  // The local energy is judged on at most kMaxLocalPoints of them (every k-th, in index order):
  // enough to rank knot moves, and it bounds the cost per vertex for dense scans.
  constexpr size_t kMaxLocalPoints = 512;
  if (local.size() > kMaxLocalPoints) {
    const size_t stride = (local.size() + kMaxLocalPoints - 1) / kMaxLocalPoints;
    size_t w = 0;
    for (size_t q = 0; q < local.size(); q += stride) local[w++] = local[q];
    local.resize(w);
  }
  res.tried = true;
  double energy = local_energy(eval, pts, local, lambda);
  res.before = energy;
  std::vector<double> area0;
  for (int t : star) area0.push_back(tri_area(d, t));
  const Point2 start0 = spline.knot(s, 0);
  std::vector<Point2> saved(n + 1);

  // Tries knots `cand` (levels 0..n) for s; keeps them if valid and better.
  auto attempt = [&](const std::vector<Point2>& cand) {
    for (int k = 0; k <= n; ++k) saved[k] = spline.knot(s, k);
    if (cand[0] != saved[0]) {
      // The primary knot: the star must stay valid and of reasonable shape.
      for (size_t q = 0; q < star.size(); ++q) {
        const auto& tri = d.triangle(star[q]);
        std::array<Point2, 3> p{d.vertex(tri[0]), d.vertex(tri[1]), d.vertex(tri[2])};
        for (int k = 0; k < 3; ++k)
          if (tri[k] == s) p[k] = cand[0];
        if (orientation(p[0], p[1], p[2]) <= 0 || 0.5 * det3(p[0], p[1], p[2]) < 0.3 * area0[q])
          return false;
      }
    }
    for (int k = 0; k <= n; ++k)
      if (cand[k] != saved[k]) spline.set_knot(s, k, cand[k]);
    const double r = traas_radius(d, s);
    bool ok = true;
    for (int k = 1; k <= n && ok; ++k)
      if ((cand[k] - cand[0]).norm() >= tol::kSubKnotMax * r) ok = false;
    if (ok) ok = check_knot_conditions(d, n, spline.knots(), star).ok();
    double e = 0;
    if (ok) {
      eval.update_knots(s);
      e = local_energy(eval, pts, local, lambda);
    }
    if (ok && e < energy * (1 - 1e-9)) {
      energy = e;
      res.moved = true;
      return true;
    }
    for (int k = 0; k <= n; ++k)
      if (spline.knot(s, k) != saved[k]) spline.set_knot(s, k, saved[k]);
    if (ok) eval.update_knots(s);
    return false;
  };

  double delta = 0.25 * traas_radius(d, s);
  const Vector2 dirs[4] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  int evaluations = 0;
  for (int round = 0; round < 3 && evaluations < 24; ++round) {
    bool improved = false;
    if (!boundary) {
      for (const auto& dir : dirs) {
        std::vector<Point2> cand(n + 1);
        for (int k = 0; k <= n; ++k) cand[k] = spline.knot(s, k) + delta * dir;
        ++evaluations;
        improved = attempt(cand) || improved;
      }
    }
    for (int k = 1; k < n; ++k)
      for (const auto& dir : dirs) {
        std::vector<Point2> cand(n + 1);
        for (int q = 0; q <= n; ++q) cand[q] = spline.knot(s, q);
        cand[k] += delta * dir;
        ++evaluations;
        improved = attempt(cand) || improved;
      }
    if (!improved) delta *= 0.5;
  }
  res.after = energy;
  res.knots.resize(n + 1);
  for (int k = 0; k <= n; ++k) res.knots[k] = spline.knot(s, k);
  if (spline.knot(s, 0) != start0) {
    res.primary_moved = true;
    // Points of the star may now lie in another triangle of the star.
    std::vector<int> pts_star;
    for (int t : star) {
      pts_star.insert(pts_star.end(), tri_points[t].begin(), tri_points[t].end());
      tri_points[t].clear();
    }
    std::sort(pts_star.begin(), pts_star.end());
    for (int i : pts_star) {
      const int t = eval.locate(pts.uv[i]);
      located[i] = t;
      if (t >= 0) tri_points[t].push_back(i);
    }
  }
  return res;
}

// Greedy colouring: vertices closer than 4 edges get different colours, so that the vertices
// of one colour can be optimised at the same time (paper section 4.3).
std::vector<std::vector<int>> colour_classes(const Domain& d, std::span<const int> vertices) {
  std::vector<std::vector<int>> adj(d.vertex_count());
  for (const auto& e : d.edges()) adj[e[0]].push_back(e[1]), adj[e[1]].push_back(e[0]);
  std::vector<int> colour(d.vertex_count(), -1), dist(d.vertex_count(), -1);
  std::vector<std::vector<int>> classes;
  std::vector<int> seen, frontier, next;
  for (int v : vertices) {
    // Colours used within distance 3.
    std::vector<char> used(classes.size() + 1, 0);
    seen.assign(1, v);
    frontier.assign(1, v);
    dist[v] = 0;
    for (int level = 1; level <= 3; ++level) {
      next.clear();
      for (int a : frontier)
        for (int b : adj[a])
          if (dist[b] < 0) dist[b] = level, next.push_back(b), seen.push_back(b);
      frontier.swap(next);
    }
    for (int w : seen) {
      if (colour[w] >= 0) used[colour[w]] = 1;
      dist[w] = -1;
    }
    int c = 0;
    while (used[c]) ++c;
    colour[v] = c;
    if (c == static_cast<int>(classes.size())) classes.emplace_back();
    classes[c].push_back(v);
  }
  return classes;
}

}  // namespace

KnotSweepStats optimize_knots(Spline& spline, Evaluator& eval, std::vector<int>& located,
                              const FitPoints& pts, double lambda, std::span<const int> vertices,
                              const std::function<void(int, const Point2&)>& on_primary_move,
                              int threads) {
  const Domain& d = spline.domain();
  const int n = spline.degree();
  KnotSweepStats stats;
  std::vector<char> feature_vertex(d.vertex_count(), 0);
  for (const auto& e : d.feature_edges()) feature_vertex[e[0]] = feature_vertex[e[1]] = 1;
  std::vector<int> todo;
  for (int v : vertices)
    if (!feature_vertex[v]) todo.push_back(v);
  if (todo.empty() || n < 1) return stats;

  std::vector<std::vector<int>> tri_points(d.triangle_count());
  for (size_t i = 0; i < located.size(); ++i)
    if (located[i] >= 0) tri_points[located[i]].push_back(static_cast<int>(i));

  // Each worker optimises on its own copy of the spline; accepted changes are logged and
  // replayed into every copy before the next colour class.
  struct Change {
    int vertex;
    std::vector<Point2> knots;
  };
  std::vector<Change> log;
  struct Worker {
    std::unique_ptr<Spline> spline;
    std::unique_ptr<Evaluator> eval;
    size_t synced = 0;
  };
  tbb::enumerable_thread_specific<Worker> workers;
  auto sync = [&](Spline& s, Evaluator* e, size_t from, size_t to) {
    for (size_t c = from; c < to; ++c) {
      const Change& ch = log[c];
      for (int k = 0; k <= n; ++k)
        if (s.knot(ch.vertex, k) != ch.knots[k]) s.set_knot(ch.vertex, k, ch.knots[k]);
      if (e) e->update_knots(ch.vertex);
    }
  };

  const auto classes = colour_classes(d, todo);
  for (const auto& cls : classes) {
    std::vector<VertexResult> results(cls.size());
    const size_t log_size = log.size();
    auto body = [&](size_t q) {
      Worker& w = workers.local();
      if (!w.spline) {
        w.spline = std::make_unique<Spline>(spline);
        w.eval = std::make_unique<Evaluator>(*w.spline);
        w.synced = log_size;
      }
      sync(*w.spline, w.eval.get(), w.synced, log_size);
      w.synced = log_size;
      results[q] = optimize_vertex(*w.spline, *w.eval, cls[q], located, tri_points, pts, lambda);
      // Keep the copy equal to the class-start state for the other vertices of the class it
      // may still run: the vertex's own change is replayed from the log later (idempotent).
    };
    if (cls.size() == 1) {
      body(0);
    } else {
      auto loop = [&] {
        tbb::parallel_for(size_t{0}, cls.size(), body);
      };
      if (threads > 0) {
        tbb::task_arena arena(threads);
        arena.execute(loop);
      } else {
        loop();
      }
    }
    for (size_t q = 0; q < cls.size(); ++q) {
      const VertexResult& r = results[q];
      if (!r.tried) continue;
      ++stats.vertices;
      stats.energy_before += r.before;
      stats.energy_after += r.after;
      if (!r.moved) continue;
      ++stats.moved;
      log.push_back({cls[q], r.knots});
      if (r.primary_moved) on_primary_move(cls[q], r.knots[0]);
    }
  }
  sync(spline, &eval, 0, log.size());
  return stats;
}

}  // namespace tbs::detail
