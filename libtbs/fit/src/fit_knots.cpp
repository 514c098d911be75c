// OptimizeKnot (paper section 4.3, fit_knots.h): each vertex's knots moved by a pattern search,
// with the control points of its star solved again on the local points; colour classes of
// vertices far enough apart run in parallel, with the same result for any thread count.

#include "fit_knots.h"

#include "thread_arena.h"

#include <tbs/knots.h>
#include <tbs/predicates.h>
#include <tbs/tolerances.h>

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

namespace tbs::detail {
namespace {


double tri_area(const Domain& d, int t) {
  const auto& tri = d.triangle(t);
  return 0.5 * det3(d.vertex(tri[0]), d.vertex(tri[1]), d.vertex(tri[2]));
}

}  // namespace

namespace {

// Points per task when a local energy computes its basis rows in parallel.
constexpr Eigen::Index kRowsPerTask = 32;

// The energy a choice of knots for s allows (variable projection, restricted to the star): the
// knots of s enter only the basis functions of the triangles around s, so their control points
// are solved again by least squares on the local points, the others held as they are, and the
// energy is judged with that solution. Without it a knot move is judged with control points
// fitted to the old knots, and nearly every move looks worse than it is.
//
// The basis rows of the local points are most of the cost. A point's row changes with the knots
// of s only through the star's basis functions, and those are zero outside their supports (the
// boxes of their knots, as the evaluator bounds them): the rows of points outside the star's
// supports, before and after a move, are kept from the accepted knots, the same numbers the
// evaluator would give again.
class LocalResolve {
 public:
  LocalResolve(const Spline& spline, std::span<const int> star, const FitPoints& pts, std::span<const int> local,
               double lambda, bool keep_rows)
      : spline_(spline), star_(star), pts_(pts), local_(local), lambda_(lambda), keep_rows_(keep_rows) {
    const int bc = beta_count(spline.degree());
    for (int t : star)
      for (int j = 0; j < bc; ++j) free_.push_back(spline.control_point_index(t, j));
    std::sort(free_.begin(), free_.end());
    free_.erase(std::unique(free_.begin(), free_.end()), free_.end());
    const auto m = static_cast<Eigen::Index>(free_.size());
    c_.resize(m, 3);
    for (Eigen::Index f = 0; f < m; ++f)
      for (int k = 0; k < 3; ++k) c_(f, k) = spline.control_points()[free_[f]][k];
  }

  /// Whether the points decide the star's control points: twice as many points in the star
  /// as control points (three coordinates each against three unknowns each), and in each of
  /// its triangles at least as many as the triangle's own control points (`fewest`; fewer,
  /// and the smoothness terms of the global solve shape the triangle, which the local energy
  /// does not see).
  bool determined(size_t star_points, size_t fewest) const {
    return star_points >= 2 * free_.size() && fewest >= static_cast<size_t>(beta_count(spline_.degree()));
  }

  /// min over the star's control points of the data and fairness energy of the local points,
  /// plus a small pull to the current control points (it keeps the solve definite), for the
  /// spline's current knots. The first call sets the accepted state; later calls start from
  /// it (see accept()).
  double energy(const Evaluator& eval) {
    const auto q = static_cast<Eigen::Index>(local_.size()), m = static_cast<Eigen::Index>(free_.size());
    if (accepted_.boxes.empty()) {
      now_.a.setZero(q, m);
      now_.du.setZero(q, m);
      now_.dv.setZero(q, m);
      now_.r.resize(q, 3);
      now_.fu.resize(q, 3);
      now_.fv.resize(q, 3);
    } else {
      now_ = accepted_;
    }
    supports(now_.boxes);
    const auto& cp = spline_.control_points();
    // In parallel: each point fills its own rows of the matrices, so the result does not
    // depend on the thread count. Isolated: a worker waiting here must not pick up another
    // vertex's search, which would change this worker's copy of the spline under it
    // (optimize_knots runs one search per worker copy).
    auto fill = [&](const tbb::blocked_range<Eigen::Index>& range) {
      thread_local BasisRow row;
      for (Eigen::Index i = range.begin(); i != range.end(); ++i) {
        const int p = local_[i];
        if (keep_rows_ && !accepted_.boxes.empty() && !touched(pts_.uv[p])) continue;
        now_.a.row(i).setZero();
        now_.du.row(i).setZero();
        now_.dv.row(i).setZero();
        Eigen::Vector3d f = Eigen::Vector3d::Zero(), fu = f, fv = f;
        if (eval.basis_row(pts_.uv[p], row)) {
          for (size_t k = 0; k < row.index.size(); ++k) {
            const auto it = std::lower_bound(free_.begin(), free_.end(), row.index[k]);
            if (it != free_.end() && *it == row.index[k]) {
              const auto j = it - free_.begin();
              now_.a(i, j) = row.value[k];
              now_.du(i, j) = row.du[k];
              now_.dv(i, j) = row.dv[k];
            } else {
              const Point3& c = cp[row.index[k]];
              f += row.value[k] * c;
              fu += row.du[k] * c;
              fv += row.dv[k] * c;
            }
          }
        }
        now_.r.row(i) = (pts_.p[p] - f).transpose();
        if (!pts_.weight.empty()) {  // guides: rows scaled by the square root of their weight
          const double s = std::sqrt(pts_.weight[p]);
          now_.a.row(i) *= s;
          now_.r.row(i) *= s;
        }
        now_.fu.row(i) = fu.transpose();
        now_.fv.row(i) = fv.transpose();
      }
    };
    tbb::this_task_arena::isolate(
        [&] { tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, q, kRowsPerTask), fill); });
    const Rows& w = now_;
    g_.noalias() = w.a.transpose() * w.a;
    const double mu = 1e-6 * std::max(g_.trace() / static_cast<double>(m), 1e-300);
    g_.diagonal().array() += mu;
    x_ = g_.llt().solve(w.a.transpose() * w.r + mu * c_);
    const Eigen::MatrixXd& x = x_;
    double e = ((w.r - w.a * x).rowwise().squaredNorm()).sum() + mu * (x - c_).squaredNorm();
    if (lambda_ > 0) {
      fu_ = w.fu;
      fv_ = w.fv;
      fu_.noalias() += w.du * x;
      fv_.noalias() += w.dv * x;
      for (Eigen::Index i = 0; i < q; ++i) {
        const int p = local_[i];
        const Eigen::Vector3d n(pts_.n[p].x(), pts_.n[p].y(), pts_.n[p].z());
        const double a = fu_.row(i).dot(n), b = fv_.row(i).dot(n);
        e += lambda_ * pts_.fair_weight(p) * (a * a + b * b);
      }
    }
    if (accepted_.boxes.empty()) accept();
    return e;
  }

  /// The knots of the last energy() call are kept: later calls start from its rows.
  void accept() { std::swap(accepted_, now_); }

  /// The control points of the last energy() call's solution.
  std::vector<std::pair<int, Point3>> solution() const {
    std::vector<std::pair<int, Point3>> out(free_.size());
    for (size_t f = 0; f < free_.size(); ++f)
      out[f] = {free_[f], x_.row(static_cast<Eigen::Index>(f)).transpose()};
    return out;
  }

 private:
  // The local points' rows over the free control points (a, du, dv), and the rest of each
  // point's row applied to the held control points (r = p - F of the rest, fu, fv), for one
  // choice of knots, with the supports of the star's basis functions for those knots.
  struct Rows {
    Eigen::MatrixXd a, du, dv, r, fu, fv;
    std::vector<Box2> boxes;
  };

  // The box the evaluator bounds each star triangle's basis functions by (its support-grid
  // box): the knots of levels 0 .. n-1 of the triangle's vertices.
  void supports(std::vector<Box2>& boxes) const {
    const int n = spline_.degree();
    boxes.assign(star_.size(), Box2{});
    for (size_t k = 0; k < star_.size(); ++k)
      for (int v : spline_.domain().triangle(star_[k]))
        for (int l = 0; l < n; ++l) boxes[k].extend(spline_.knot(v, l));
  }

  // Whether the star's basis functions may be non-zero at u for the accepted or the current knots.
  bool touched(const Point2& u) const {
    for (const auto* b : {&accepted_.boxes, &now_.boxes})
      for (const Box2& box : *b)
        if (box.contains(u)) return true;
    return false;
  }

  const Spline& spline_;
  std::span<const int> star_;
  const FitPoints& pts_;
  std::span<const int> local_;
  double lambda_;
  bool keep_rows_;
  std::vector<int> free_;
  Rows accepted_, now_;
  Eigen::MatrixXd c_, fu_, fv_, g_, x_;
};

struct VertexResult {
  bool tried = false, moved = false, primary_moved = false;
  double before = 0, after = 0;
  std::vector<Point2> knots;
  std::vector<std::pair<int, Point3>> control_points;  // the star's, re-solved for the knots
};

// OptimizeKnot(t_s) on one spline copy: pattern search, accepting only improvements.
VertexResult optimize_vertex(Spline& spline, Evaluator& eval, int s, std::vector<int>& located,
                             std::vector<std::vector<int>>& tri_points, const FitPoints& pts,
                             double lambda, bool keep_rows) {
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
  // Knots are moved only where the points decide the star's control points.
  LocalResolve resolve(spline, star, pts, local, lambda, keep_rows);
  size_t star_points = 0, fewest = std::numeric_limits<size_t>::max();
  for (int t : star) star_points += tri_points[t].size(), fewest = std::min(fewest, tri_points[t].size());
  if (!resolve.determined(star_points, fewest)) return res;
  res.tried = true;
  double energy = resolve.energy(eval);
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
      e = resolve.energy(eval);
    }
    if (ok && e < energy * (1 - 1e-9)) {
      energy = e;
      resolve.accept();
      res.control_points = resolve.solution();
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
                              int threads, bool keep_rows) {
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
    std::vector<std::pair<int, Point3>> control_points;
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
      for (const auto& [index, p] : ch.control_points) s.control_points()[index] = p;
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
        w.eval = std::make_unique<Evaluator>(eval, *w.spline);
        w.synced = 0;  // a copy of the pass-start state: replay every earlier class's changes
      }
      sync(*w.spline, w.eval.get(), w.synced, log_size);
      w.synced = log_size;
      results[q] = optimize_vertex(*w.spline, *w.eval, cls[q], located, tri_points, pts, lambda, keep_rows);
      // Keep the copy equal to the class-start state for the other vertices of the class it
      // may still run: the vertex's own change is replayed from the log later (idempotent).
    };
    // In the arena even for one vertex: its local energies run their rows in parallel.
    auto loop = [&] {
      if (cls.size() == 1)
        body(0);
      else
        tbb::parallel_for(size_t{0}, cls.size(), body);
    };
    with_threads(threads, loop);
    for (size_t q = 0; q < cls.size(); ++q) {
      const VertexResult& r = results[q];
      if (!r.tried) continue;
      ++stats.vertices;
      stats.energy_before += r.before;
      stats.energy_after += r.after;
      if (!r.moved) continue;
      ++stats.moved;
      log.push_back({cls[q], r.knots, r.control_points});
      if (r.primary_moved) on_primary_move(cls[q], r.knots[0]);
    }
  }
  sync(spline, &eval, 0, log.size());
  return stats;
}

}  // namespace tbs::detail
