#include "fit_knots.h"

#include <tbs/knots.h>
#include <tbs/predicates.h>
#include <tbs/tolerances.h>

#include <algorithm>
#include <cmath>

namespace tbs::detail {
namespace {

double traas_radius(const Domain& d, int v) {
  double r = std::numeric_limits<double>::infinity();
  for (int t : d.vertex_triangles(v)) {
    const auto& tri = d.triangle(t);
    const int k = tri[0] == v ? 0 : (tri[1] == v ? 1 : 2);
    const Point2& a = d.vertex(tri[(k + 1) % 3]);
    const Point2& b = d.vertex(tri[(k + 2) % 3]);
    r = std::min(r, 0.5 * std::fabs(det3(d.vertex(v), a, b)) / (b - a).norm());
  }
  return r;
}

double tri_area(const Domain& d, int t) {
  const auto& tri = d.triangle(t);
  return 0.5 * det3(d.vertex(tri[0]), d.vertex(tri[1]), d.vertex(tri[2]));
}

}  // namespace

KnotSweepStats optimize_knots(Spline& spline, Evaluator& eval, std::vector<int>& located,
                              const FitPoints& pts, double lambda, std::span<const int> vertices,
                              const std::function<void(int, const Point2&)>& on_primary_move) {
  const Domain& d = spline.domain();
  const int n = spline.degree();
  KnotSweepStats stats;
  if (n < 1) return stats;
  std::vector<std::vector<int>> tri_points(d.triangle_count());
  for (size_t i = 0; i < located.size(); ++i)
    if (located[i] >= 0) tri_points[located[i]].push_back(static_cast<int>(i));
  std::vector<char> feature_vertex(d.vertex_count(), 0);
  for (const auto& e : d.feature_edges()) feature_vertex[e[0]] = feature_vertex[e[1]] = 1;

  std::vector<int> ring2, local, star;
  std::vector<Point2> saved(n + 1);
  for (int s : vertices) {
    if (feature_vertex[s]) continue;
    const bool boundary = d.is_boundary_vertex(s);
    star.assign(d.vertex_triangles(s).begin(), d.vertex_triangles(s).end());
    ring2.clear();
    for (int t : star)
      for (int v : d.triangle(t))
        for (int u : d.vertex_triangles(v)) ring2.push_back(u);
    std::sort(ring2.begin(), ring2.end());
    ring2.erase(std::unique(ring2.begin(), ring2.end()), ring2.end());
    local.clear();
    for (int t : ring2) local.insert(local.end(), tri_points[t].begin(), tri_points[t].end());
    if (local.empty()) continue;
    std::sort(local.begin(), local.end());
    ++stats.vertices;
    double energy = local_energy(eval, pts, local, lambda);
    stats.energy_before += energy;
    std::vector<double> area0;
    for (int t : star) area0.push_back(tri_area(d, t));
    const Point2 start0 = spline.knot(s, 0);
    bool moved = false;

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
        moved = true;
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
    stats.energy_after += energy;
    if (moved) ++stats.moved;
    if (spline.knot(s, 0) != start0) {
      on_primary_move(s, spline.knot(s, 0));
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
  }
  return stats;
}

}  // namespace tbs::detail
