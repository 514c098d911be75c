// Region faces (cad_regions.h): smooth regions of the domain, one trimmed B-spline surface each.

#include <tbs/atlas.h>
#include <tbs/cad_regions.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/predicates.h>

#include "bspline_basis.h"
#include "atlas_trims.h"
#include "side_eval.h"
#include "trim_curve.h"

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <tbb/parallel_for.h>
#include <tbb/parallel_for_each.h>
#include <tbb/task_arena.h>

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <optional>
#include <queue>

namespace tbs {

const char* to_string(RegionEdgeKind kind) {
  switch (kind) {
    case RegionEdgeKind::Boundary: return "boundary";
    case RegionEdgeKind::Crease: return "crease";
    case RegionEdgeKind::CreaseExtension: return "crease extension";
    case RegionEdgeKind::Split: return "split";
    case RegionEdgeKind::Seam: return "seam";
  }
  return "?";
}

namespace {

using detail::Basis;
using detail::breaks_and_midpoints;
using detail::inner_points;
using detail::span_of;
using detail::uniform_breaks;
using detail::basis_functions;
using detail::find_span;

constexpr double kPi = 3.14159265358979323846;
// The fit aims below the tolerances, so that the surface between the check samples stays
// within them.
constexpr double kPositionMargin = 0.7;
constexpr double kNormalMargin = 0.8;
// Trim curves aim at a quarter of the tolerance: the edge gap adds the face's deviation.
constexpr double kCurveMargin = 0.25;
// Normals are compared where sin(angle between the tangents) is at least this.
constexpr double kRegular = 1e-2;
// Thin-plate weights, relative to the data of a cell: tiny inside the region (it only keeps
// the least-squares system regular where a cell has few samples), stronger outside it, where
// it alone shapes the surface.
constexpr double kSmoothInside = 1e-5;
constexpr double kSmoothOutside = 1e-2;
// Two segments of a trim chain are one straight edge when the sine of their angle is below
// this: the straight line then misses the middle vertex by at most 1e-9 of its length.
constexpr double kCollinear = 1e-9;
constexpr int kMaxRounds = 14;
constexpr double kNormalStall = 0.75;
// The rectangle of a face reaches this fraction of its size past the region, so that no trim
// lies on the surface's own boundary.
constexpr double kMargin = 2e-3;
// Resolution of the check lattice in every domain triangle.
constexpr int kLattice = 8;
// Regions of at most this many triangles that no chain across splits are cut along a single
// edge (Regions::cut_small).
constexpr size_t kSmallRegion = 64;

struct Sample {
  Point2 uv;
  Point3 f;
  Vector3 fu = Vector3::Zero(), fv = Vector3::Zero();
  Vector3 n;        // unit normal of the spline, on the region's side
  bool regular = false;
};

double angle_deg(const Vector3& a, const Vector3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / kPi;
}

bool regular(const SurfacePoint& p) {
  return p.du.cross(p.dv).norm() >= kRegular * p.du.norm() * p.dv.norm() && p.du.norm() > 0;
}

// The domain with the borders of the regions and the region label of every triangle.
class Regions {
 public:
  // With `creases` false, feature edges do not bound regions (an atlas: one region per chart).
  explicit Regions(const Domain& d, bool creases = true) : d_(d), kind_(static_cast<size_t>(d.edge_count())),
                                      border_(static_cast<size_t>(d.edge_count()), 0),
                                      vertex_edges_(static_cast<size_t>(d.vertex_count())) {
    for (int e = 0; e < d.edge_count(); ++e) {
      for (int v : d.edges()[static_cast<size_t>(e)]) vertex_edges_[static_cast<size_t>(v)].push_back(e);
      if (d.is_boundary_edge(e)) {
        border_[static_cast<size_t>(e)] = 1;
        kind_[static_cast<size_t>(e)] = RegionEdgeKind::Boundary;
      } else if (creases && d.is_feature_edge(e)) {
        border_[static_cast<size_t>(e)] = 1;
        kind_[static_cast<size_t>(e)] = RegionEdgeKind::Crease;
      }
    }
  }

  const Domain& domain() const { return d_; }
  // Interior vertices where a crease ended (before extend_creases() extended it).
  const std::vector<int>& crease_tips() const { return tips_; }
  RegionEdgeKind kind(int e) const { return kind_[static_cast<size_t>(e)]; }
  int label(int t) const { return label_[static_cast<size_t>(t)]; }
  int region_count() const { return static_cast<int>(members_.size()); }
  const std::vector<int>& triangles(int r) const { return members_[static_cast<size_t>(r)]; }
  const std::vector<int>& vertex_edges(int v) const { return vertex_edges_[static_cast<size_t>(v)]; }
  int other(int e, int v) const {
    const auto& ed = d_.edges()[static_cast<size_t>(e)];
    return ed[0] == v ? ed[1] : ed[0];
  }

  // Extends every crease that ends at an interior vertex along domain edges to the nearest
  // border vertex, preferring to go straight on. Returns (extended, left inside).
  std::pair<int, int> extend_creases() {
    int extended = 0, left = 0;
    tips_.clear();
    std::vector<int> degree(static_cast<size_t>(d_.vertex_count()), 0);
    for (int e = 0; e < d_.edge_count(); ++e)
      if (border_[static_cast<size_t>(e)])
        for (int v : d_.edges()[static_cast<size_t>(e)]) ++degree[static_cast<size_t>(v)];
    auto on_border = [&](int v) { return d_.is_boundary_vertex(v) || degree[static_cast<size_t>(v)] > 0; };
    for (int v = 0; v < d_.vertex_count(); ++v) {
      if (d_.is_boundary_vertex(v) || degree[static_cast<size_t>(v)] != 1) continue;
      tips_.push_back(v);
      // The crease's own chain back to its first junction: not a target.
      std::vector<char> excluded(static_cast<size_t>(d_.vertex_count()), 0);
      excluded[static_cast<size_t>(v)] = 1;
      int prev = v, cur = -1;
      for (int e : vertex_edges(v))
        if (border_[static_cast<size_t>(e)]) cur = other(e, v);
      const Vector2 dir = (d_.vertex(v) - d_.vertex(cur)).normalized();
      while (!d_.is_boundary_vertex(cur) && degree[static_cast<size_t>(cur)] <= 2 && !excluded[static_cast<size_t>(cur)]) {
        excluded[static_cast<size_t>(cur)] = 1;
        int next = -1;
        for (int e : vertex_edges(cur))
          if (border_[static_cast<size_t>(e)] && other(e, cur) != prev) next = other(e, cur);
        if (next < 0) break;
        prev = cur;
        cur = next;
      }
      // Dijkstra over non-border edges; a turn away from the crease's direction costs extra.
      std::vector<double> dist(static_cast<size_t>(d_.vertex_count()), std::numeric_limits<double>::infinity());
      std::vector<int> from(static_cast<size_t>(d_.vertex_count()), -1);
      using Item = std::pair<double, int>;
      std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
      dist[static_cast<size_t>(v)] = 0;
      queue.push({0.0, v});
      int target = -1;
      while (!queue.empty()) {
        const auto [dv, a] = queue.top();
        queue.pop();
        if (dv > dist[static_cast<size_t>(a)]) continue;
        if (a != v && on_border(a)) {
          if (!excluded[static_cast<size_t>(a)]) {
            target = a;
            break;
          }
          continue;  // through no border vertex
        }
        for (int e : vertex_edges(a)) {
          if (border_[static_cast<size_t>(e)]) continue;
          const int b = other(e, a);
          const Vector2 step = d_.vertex(b) - d_.vertex(a);
          const double len = step.norm();
          const double turn = 1 - std::clamp(step.dot(dir) / std::max(len, 1e-300), -1.0, 1.0);
          const double nd = dv + len * (1 + 2 * turn);
          if (nd < dist[static_cast<size_t>(b)]) {
            dist[static_cast<size_t>(b)] = nd;
            from[static_cast<size_t>(b)] = e;
            queue.push({nd, b});
          }
        }
      }
      if (target < 0) {
        ++left;
        continue;
      }
      for (int b = target; b != v;) {
        const int e = from[static_cast<size_t>(b)];
        border_[static_cast<size_t>(e)] = 1;
        kind_[static_cast<size_t>(e)] = RegionEdgeKind::CreaseExtension;
        for (int w : d_.edges()[static_cast<size_t>(e)]) ++degree[static_cast<size_t>(w)];
        b = other(e, b);
      }
      ++extended;
    }
    return {extended, left};
  }

  // Numbers the regions by their smallest triangle, as label_all() does: the numbering that
  // splits made depends on the order in which they happened. Returns the old number of each
  // new one.
  std::vector<int> renumber() {
    std::vector<std::pair<int, int>> first;  // (smallest triangle, region)
    for (int r = 0; r < region_count(); ++r) {
      const auto& m = members_[static_cast<size_t>(r)];
      first.emplace_back(m.empty() ? std::numeric_limits<int>::max() : *std::min_element(m.begin(), m.end()), r);
    }
    std::sort(first.begin(), first.end());
    std::vector<std::vector<int>> members(members_.size());
    for (size_t k = 0; k < first.size(); ++k) {
      members[k] = std::move(members_[static_cast<size_t>(first[k].second)]);
      for (int t : members[k]) label_[static_cast<size_t>(t)] = static_cast<int>(k);
    }
    members_ = std::move(members);
    std::vector<int> old(first.size());
    for (size_t k = 0; k < first.size(); ++k) old[k] = first[k].second;
    return old;
  }

  // Labels the triangles: connected across edges that are not borders, numbered by their
  // smallest triangle.
  void label_all() {
    label_.assign(static_cast<size_t>(d_.triangle_count()), -1);
    members_.clear();
    for (int t = 0; t < d_.triangle_count(); ++t)
      if (label_[static_cast<size_t>(t)] < 0) flood(t, static_cast<int>(members_.size()), -1);
  }

  // Cuts region r along a chain of domain edges across its longer side, through vertices
  // that are on no border, from its outer loop to its outer loop. The parts get new labels
  // (the part with the smallest triangle keeps r). Returns false if there is no such chain.
  // The cut runs near the worst point of the last fit (`worst`, if inside the region's box),
  // a little past it toward the middle, so that repeated splits close in on a spot that
  // needs many knots instead of halving the whole region each time.
  bool split(int r, const Point2& worst) {
    const std::vector<int> tris = members_[static_cast<size_t>(r)];
    if (tris.size() < 2) return false;
    Box2 box;
    for (int t : tris)
      for (int v : d_.triangle(t)) box.extend(d_.vertex(v));
    const Vector2 ext = box.max - box.min;
    for (int attempt = 0; attempt < 2; ++attempt) {
      const int axis = (ext.x() >= ext.y()) == (attempt == 0) ? 0 : 1;
      const double a = box.min[axis], b = box.max[axis], length = b - a, centre = 0.5 * (a + b);
      double at = centre;
      if (worst.allFinite() && worst[axis] >= a && worst[axis] <= b) {
        const double toward = worst[axis] < centre ? 1.0 : -1.0;
        at = std::clamp(worst[axis] + toward * 0.15 * length, a + 0.1 * length, b - 0.1 * length);
        if (std::fabs(worst[axis] - centre) < 0.15 * length) at = centre;
      }
      if (cut_across(r, tris, box, axis, at)) return true;
    }
    // No chain there (the ends found on the outer loop can lie on the same side of a region
    // that is not convex): other places across either side.
    for (double f : {0.5, 0.3, 0.7, 0.15, 0.85})
      for (int axis : {0, 1})
        if (cut_across(r, tris, box, axis, box.min[axis] + f * (box.max[axis] - box.min[axis]))) return true;
    // A ring around a hole (an island carved out before, or a hole of the domain) that is too
    // thin for a chain between two points of its outer loop: cut it in two by chains from
    // either side of the hole to the outer loop.
    if (cut_ring(r, tris, ext.x() >= ext.y() ? 0 : 1)) return true;
    return cut_small(r, tris);
  }

  // Whether domain edge e lies inside region r: between two of its triangles, not on a border.
  bool inner_edge(int e, int r) const {
    const auto tr = d_.edge_triangles(e);
    return tr[1] >= 0 && label_[static_cast<size_t>(tr[0])] == r && label_[static_cast<size_t>(tr[1])] == r &&
           !border_[static_cast<size_t>(e)];
  }

  // Takes back a cut of region r (its triangles `tris`): the edges `cut` marked as border and
  // r relabelled, when members_ had `old_count` regions. relabel() touches r's triangles only.
  void undo_cut(int r, const std::vector<int>& tris, const std::vector<int>& cut, size_t old_count) {
    for (int e : cut) border_[static_cast<size_t>(e)] = 0;
    for (int t : tris) label_[static_cast<size_t>(t)] = r;
    members_.resize(old_count);
    members_[static_cast<size_t>(r)] = tris;
  }

  // Cuts region r, which has holes, in two along two chains of domain edges, each from a vertex
  // of a hole's loop to one of the outer loop, through vertices on no border: the shortest
  // from the hole's low side (along `axis`) and the shortest from its high side that shares no
  // vertex with the first. False (and r as it was) if there are no such chains or they do not
  // cut r apart.
  bool cut_ring(int r, const std::vector<int>& tris, int axis) {
    const std::vector<std::vector<HalfEdge>> lp = loops(r);
    if (lp.size() < 2) return false;
    std::vector<char> on_border(static_cast<size_t>(d_.vertex_count()), 0), outer(on_border.size(), 0);
    for (const auto& l : lp)
      for (const HalfEdge& h : l) on_border[static_cast<size_t>(h.from)] = 1;
    for (const HalfEdge& h : lp[0]) outer[static_cast<size_t>(h.from)] = 1;
    // The shortest chain from `starts` to the outer loop avoiding `blocked` vertices; its edges.
    auto chain = [&](const std::vector<int>& starts, const std::vector<char>& blocked) {
      std::vector<double> dist(on_border.size(), std::numeric_limits<double>::infinity());
      std::vector<int> from(on_border.size(), -1);
      using Item = std::pair<double, int>;
      std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
      for (int v : starts) {
        dist[static_cast<size_t>(v)] = 0;
        queue.push({0.0, v});
      }
      int goal = -1;
      while (!queue.empty()) {
        const auto [dv, a] = queue.top();
        queue.pop();
        if (dv > dist[static_cast<size_t>(a)]) continue;
        if (outer[static_cast<size_t>(a)]) {
          goal = a;
          break;
        }
        if (from[static_cast<size_t>(a)] >= 0 && on_border[static_cast<size_t>(a)]) continue;
        for (int e : vertex_edges(a)) {
          if (!inner_edge(e, r)) continue;
          const int b = other(e, a);
          if (blocked[static_cast<size_t>(b)] || (on_border[static_cast<size_t>(b)] && !outer[static_cast<size_t>(b)])) continue;
          const double nd = dv + (d_.vertex(b) - d_.vertex(a)).norm();
          if (nd < dist[static_cast<size_t>(b)]) {
            dist[static_cast<size_t>(b)] = nd;
            from[static_cast<size_t>(b)] = e;
            queue.push({nd, b});
          }
        }
      }
      std::vector<int> edges;
      for (int b = goal; b >= 0 && from[static_cast<size_t>(b)] >= 0;) {
        const int e = from[static_cast<size_t>(b)];
        edges.push_back(e);
        b = other(e, b);
      }
      return edges;
    };
    for (size_t h = 1; h < lp.size(); ++h) {
      double centre = 0;
      for (const HalfEdge& e : lp[h]) centre += d_.vertex(e.from)[axis];
      centre /= static_cast<double>(lp[h].size());
      std::vector<int> low, high;
      for (const HalfEdge& e : lp[h]) (d_.vertex(e.from)[axis] < centre ? low : high).push_back(e.from);
      if (low.empty() || high.empty()) continue;
      std::vector<char> blocked(on_border.size(), 0);
      const std::vector<int> first = chain(low, blocked);
      if (first.empty()) continue;
      for (int e : first)
        for (int v : d_.edges()[static_cast<size_t>(e)]) blocked[static_cast<size_t>(v)] = 1;
      const std::vector<int> second = chain(high, blocked);
      if (second.empty()) continue;
      const size_t old_count = members_.size();
      std::vector<int> cut = first;
      cut.insert(cut.end(), second.begin(), second.end());
      for (int e : cut) border_[static_cast<size_t>(e)] = 1;
      relabel(r, tris);
      if (members_.size() > old_count) {
        for (int e : cut) kind_[static_cast<size_t>(e)] = RegionEdgeKind::Split;
        return true;
      }
      undo_cut(r, tris, cut, old_count);
    }
    return false;
  }

  // Cuts a small region (kSmallRegion triangles at most) in two along one inner domain edge
  // between two of its border vertices, the one that leaves the two parts closest in size:
  // for the regions whose border vertices sit where cut_across() finds no sides to join (an
  // L of four triangles whose inner corner is the centre of its box). False if no edge cuts.
  bool cut_small(int r, const std::vector<int>& tris) {
    if (tris.size() < 2 || tris.size() > kSmallRegion) return false;
    std::vector<char> on_border(static_cast<size_t>(d_.vertex_count()), 0);
    for (const HalfEdge& h : border_half_edges(r)) on_border[static_cast<size_t>(h.from)] = 1;
    std::vector<int> candidates;
    for (int t : tris)
      for (int k = 0; k < 3; ++k) {
        const int e = d_.triangle_edge(t, k);
        const auto& ends = d_.edges()[static_cast<size_t>(e)];
        if (inner_edge(e, r) && on_border[static_cast<size_t>(ends[0])] && on_border[static_cast<size_t>(ends[1])])
          candidates.push_back(e);
      }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    const size_t old_count = members_.size();
    int best = -1;
    size_t best_smaller = 0;
    for (int e : candidates) {
      border_[static_cast<size_t>(e)] = 1;
      relabel(r, tris);
      if (members_.size() == old_count + 1) {
        const size_t smaller = std::min(members_[static_cast<size_t>(r)].size(), members_.back().size());
        if (smaller > best_smaller) best_smaller = smaller, best = e;
      }
      undo_cut(r, tris, {e}, old_count);
    }
    if (best < 0) return false;
    border_[static_cast<size_t>(best)] = 1;
    kind_[static_cast<size_t>(best)] = RegionEdgeKind::Split;
    relabel(r, tris);
    return true;
  }

  // Cuts the triangles of region r that share a vertex with triangle t out of r, as a region
  // of their own (an island; the rest may fall apart into several regions). Refused (false)
  // when they are not much smaller than r, or when a new border would pinch a region at a
  // vertex (a loop through the same vertex twice).
  bool carve(int r, int t) {
    const std::vector<int> tris = members_[static_cast<size_t>(r)];
    if (label_[static_cast<size_t>(t)] != r || tris.size() < 8) return false;
    std::vector<int> island;
    for (int v : d_.triangle(t))
      for (int u : d_.vertex_triangles(v))
        if (label_[static_cast<size_t>(u)] == r) island.push_back(u);
    std::sort(island.begin(), island.end());
    island.erase(std::unique(island.begin(), island.end()), island.end());
    if (4 * island.size() > tris.size()) return false;
    std::vector<char> in(static_cast<size_t>(d_.triangle_count()), 0);
    for (int u : island) in[static_cast<size_t>(u)] = 1;
    std::vector<int> cut;
    for (int u : island)
      for (int k = 0; k < 3; ++k) {
        const int e = d_.triangle_edge(u, k);
        const auto tr = d_.edge_triangles(e);
        const int across = tr[0] == u ? tr[1] : tr[0];
        if (across < 0 || border_[static_cast<size_t>(e)] || in[static_cast<size_t>(across)] ||
            label_[static_cast<size_t>(across)] != r)
          continue;
        border_[static_cast<size_t>(e)] = 1;
        cut.push_back(e);
      }
    const size_t old_count = members_.size();
    relabel(r, tris);
    // No pinch: every vertex of the cut is passed once by each region's border.
    bool simple = true;
    for (int q = r; simple && q < region_count(); q = q == r ? static_cast<int>(old_count) : q + 1) {
      std::map<int, int> passes;
      for (const HalfEdge& h : border_half_edges(q)) ++passes[h.from];
      for (int e : cut)
        for (int v : d_.edges()[static_cast<size_t>(e)]) {
          const auto it = passes.find(v);
          if (it != passes.end() && it->second > 1) simple = false;
        }
    }
    if (!simple) {
      undo_cut(r, tris, cut, old_count);
      return false;
    }
    for (int e : cut) kind_[static_cast<size_t>(e)] = RegionEdgeKind::Split;
    return true;
  }

  // Domain edges on the border of region r (one per half-edge: the region is on its left):
  // (from, to, triangle of r on the left).
  struct HalfEdge {
    int from, to, triangle;
  };
  std::vector<HalfEdge> border_half_edges(int r) const {
    std::vector<HalfEdge> out;
    for (int t : members_[static_cast<size_t>(r)]) {
      const auto& c = d_.triangle(t);
      for (int k = 0; k < 3; ++k) {
        const int e = d_.triangle_edge(t, k);
        if (is_region_border(e)) out.push_back({c[static_cast<size_t>((k + 1) % 3)], c[static_cast<size_t>((k + 2) % 3)], t});
      }
    }
    return out;
  }

  // An edge between two regions, or on the boundary.
  bool is_region_border(int e) const {
    const auto tr = d_.edge_triangles(e);
    return tr[1] < 0 || label_[static_cast<size_t>(tr[0])] != label_[static_cast<size_t>(tr[1])];
  }

  // The next border half-edge of the region after (a -> b) with left triangle t: turn around
  // b through the region's triangles.
  HalfEdge next_border(const HalfEdge& h) const {
    int cur = h.triangle;
    const int r = label_[static_cast<size_t>(cur)];
    for (int guard = 0; guard < 100000; ++guard) {
      const auto& c = d_.triangle(cur);
      const int j = c[0] == h.to ? 0 : c[1] == h.to ? 1 : 2;
      const int x = c[static_cast<size_t>((j + 1) % 3)];
      const int e = d_.triangle_edge(cur, (j + 2) % 3);
      const auto tr = d_.edge_triangles(e);
      const int across = tr[0] == cur ? tr[1] : tr[0];
      if (across < 0 || label_[static_cast<size_t>(across)] != r) return {h.to, x, cur};
      cur = across;
    }
    throw Error("region faces: a region's border does not close around vertex " + std::to_string(h.to));
  }

  // The border loops of region r as half-edge sequences; the outer one (largest positive
  // area) first.
  std::vector<std::vector<HalfEdge>> loops(int r) const {
    const std::vector<HalfEdge> all = border_half_edges(r);
    std::map<std::pair<int, int>, size_t> index;
    for (size_t i = 0; i < all.size(); ++i) index[{all[i].from, all[i].to}] = i;
    std::vector<char> used(all.size(), 0);
    std::vector<std::vector<HalfEdge>> out;
    std::vector<double> area;
    for (size_t i = 0; i < all.size(); ++i) {
      if (used[i]) continue;
      std::vector<HalfEdge> loop;
      HalfEdge h = all[i];
      double a = 0;
      while (true) {
        const size_t k = index.at({h.from, h.to});
        if (used[k]) break;
        used[k] = 1;
        loop.push_back(h);
        const Point2 &p = d_.vertex(h.from), &q = d_.vertex(h.to);
        a += p.x() * q.y() - p.y() * q.x();
        h = next_border(h);
      }
      out.push_back(std::move(loop));
      area.push_back(a / 2);
    }
    std::vector<size_t> order(out.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) { return area[x] > area[y]; });
    std::vector<std::vector<HalfEdge>> sorted;
    for (size_t k : order) sorted.push_back(std::move(out[k]));
    return sorted;
  }

 private:
  void flood(int seed, int id, int only) {
    if (static_cast<int>(members_.size()) <= id) members_.resize(static_cast<size_t>(id) + 1);
    std::vector<int>& m = members_[static_cast<size_t>(id)];
    m.clear();
    std::vector<int> stack{seed};
    label_[static_cast<size_t>(seed)] = id;
    while (!stack.empty()) {
      const int t = stack.back();
      stack.pop_back();
      m.push_back(t);
      for (int k = 0; k < 3; ++k) {
        const int e = d_.triangle_edge(t, k);
        if (border_[static_cast<size_t>(e)]) continue;
        const auto tr = d_.edge_triangles(e);
        const int n = tr[0] == t ? tr[1] : tr[0];
        if (n < 0 || label_[static_cast<size_t>(n)] != only) continue;
        label_[static_cast<size_t>(n)] = id;
        stack.push_back(n);
      }
    }
    std::sort(m.begin(), m.end());
  }

  // Cuts region r along a chain of domain edges from a vertex of its outer loop on the low
  // side (across the axis) to one on the high side, through vertices on no border, close to
  // the line axis = mid: the cheapest such chain, where an edge costs its length times
  // (1 + 20 x its distance from the line / the region's extent) and each end its distance
  // from the line times 20.
  bool cut_across(int r, const std::vector<int>& tris, const Box2& box, int axis, double mid) {
    const int across = 1 - axis;
    const double extent = std::max(box.max[axis] - box.min[axis], 1e-300);
    const double centre = 0.5 * (box.min[across] + box.max[across]);
    const std::vector<std::vector<HalfEdge>> lp = loops(r);
    if (lp.empty()) return false;
    std::vector<char> outer(static_cast<size_t>(d_.vertex_count()), 0), on_border(outer.size(), 0);
    for (const auto& l : lp)
      for (const HalfEdge& h : l) on_border[static_cast<size_t>(h.from)] = 1;
    for (const HalfEdge& h : lp[0]) outer[static_cast<size_t>(h.from)] = 1;
    auto side = [&](int v) { return d_.vertex(v)[across] < centre ? 0 : 1; };
    auto end_cost = [&](int v) { return 20 * std::fabs(d_.vertex(v)[axis] - mid); };
    std::vector<double> dist(outer.size(), std::numeric_limits<double>::infinity());
    std::vector<int> from(outer.size(), -1), source(outer.size(), -1);
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    for (const HalfEdge& h : lp[0])
      if (side(h.from) == 0 && end_cost(h.from) < dist[static_cast<size_t>(h.from)]) {
        dist[static_cast<size_t>(h.from)] = end_cost(h.from);
        source[static_cast<size_t>(h.from)] = h.from;
        queue.push({dist[static_cast<size_t>(h.from)], h.from});
      }
    int goal = -1;
    double best = std::numeric_limits<double>::infinity();
    while (!queue.empty()) {
      const auto [dv, a] = queue.top();
      queue.pop();
      if (dv >= best) break;
      if (dv > dist[static_cast<size_t>(a)]) continue;
      if (source[static_cast<size_t>(a)] != a && on_border[static_cast<size_t>(a)]) continue;
      for (int e : vertex_edges(a)) {
        if (!inner_edge(e, r)) continue;
        const int b = other(e, a);
        const Point2 &pa = d_.vertex(a), &pb = d_.vertex(b);
        const double off = 0.5 * (std::fabs(pa[axis] - mid) + std::fabs(pb[axis] - mid)) / extent;
        const double nd = dv + (pb - pa).norm() * (1 + 20 * off);
        if (on_border[static_cast<size_t>(b)]) {
          // An end on the high side of the outer loop (not back where the chain began).
          if (outer[static_cast<size_t>(b)] && side(b) == 1 && nd + end_cost(b) < best) {
            best = nd + end_cost(b);
            goal = b;
            from[static_cast<size_t>(b)] = e;
            source[static_cast<size_t>(b)] = source[static_cast<size_t>(a)];
          }
          continue;
        }
        if (nd < dist[static_cast<size_t>(b)]) {
          dist[static_cast<size_t>(b)] = nd;
          from[static_cast<size_t>(b)] = e;
          source[static_cast<size_t>(b)] = source[static_cast<size_t>(a)];
          queue.push({nd, b});
        }
      }
    }
    if (goal < 0) return false;
    const int s = source[static_cast<size_t>(goal)];
    for (int b = goal; b != s;) {
      const int e = from[static_cast<size_t>(b)];
      border_[static_cast<size_t>(e)] = 1;
      kind_[static_cast<size_t>(e)] = RegionEdgeKind::Split;
      b = other(e, b);
    }
    relabel(r, tris);
    return true;
  }

  // Labels the triangles `tris` of region r after new borders were drawn: the part with the
  // smallest triangle keeps r, the other parts get new labels.
  void relabel(int r, const std::vector<int>& tris) {
    for (int t : tris) label_[static_cast<size_t>(t)] = -2;
    bool first = true;
    for (int t : tris) {
      if (label_[static_cast<size_t>(t)] != -2) continue;
      flood(t, first ? r : static_cast<int>(members_.size()), -2);
      first = false;
    }
  }

  const Domain& d_;
  std::vector<RegionEdgeKind> kind_;
  std::vector<char> border_;
  std::vector<std::vector<int>> vertex_edges_;
  std::vector<int> label_;
  std::vector<std::vector<int>> members_;
  std::vector<int> tips_;
};

// Runs the OpenMP parallel regions started on this thread on this thread alone, while it
// lives. Debian's CHOLMOD runs loops of its supernodal factorization as OpenMP regions of
// CHOLMOD_OMP_NUM_THREADS (4) threads; region fits already run on every core through TBB, and
// the OpenMP threads on top only wait for each other (head.off's region faces: 44.5 -> 36.1 s,
// the same bytes). tbs reaches OpenMP through CHOLMOD alone, so its runtime is looked up, not
// linked: without it (a CHOLMOD built without OpenMP) there is nothing to do.
class SerialOpenMp {
 public:
  SerialOpenMp() {
    if (!api().set) return;
    old_ = api().get();
    api().set(0);
  }
  ~SerialOpenMp() {
    if (api().set) api().set(old_);
  }
  SerialOpenMp(const SerialOpenMp&) = delete;
  SerialOpenMp& operator=(const SerialOpenMp&) = delete;

 private:
  struct Api {
    int (*get)() = nullptr;
    void (*set)(int) = nullptr;
  };
  static const Api& api() {
    static const Api found = [] {
      Api a;
      a.get = reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, "omp_get_max_active_levels"));
      a.set = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "omp_set_max_active_levels"));
      if (!a.get || !a.set) a = Api{};
      return a;
    }();
    return found;
  }
  int old_ = 0;
};

// Least squares on a tensor-product B-spline space: the normal equations in a band over the
// pole grid (pole (i, j) couples with poles within degree steps in each direction).
class TensorSystem {
 public:
  TensorSystem(int p, const std::vector<double>& ku, const std::vector<double>& kv)
      : p_(p), ku_(ku), kv_(kv), nu_(static_cast<int>(ku.size()) - p - 1), nv_(static_cast<int>(kv.size()) - p - 1),
        w_(2 * p + 1), band_(static_cast<size_t>(nu_) * static_cast<size_t>(nv_) * static_cast<size_t>(w_ * w_), 0.0),
        rhs_(Eigen::MatrixX3d::Zero(static_cast<Eigen::Index>(nu_) * nv_, 3)) {}

  int pole_count() const { return nu_ * nv_; }

  // A sample of the value f and, with weight wd > 0, of the partial derivatives fu, fv.
  void add_sample(const Point2& uv, const Point3& f, const Vector3& fu, const Vector3& fv, double wd) {
    const int order = wd > 0 ? 1 : 0;
    const int su = find_span(ku_, p_, uv.x());
    Basis bu;
    basis_functions(ku_, p_, su, uv.x(), order, bu);
    // Grid samples come row by row: the v basis of the last sample is often this one's.
    if (!(uv.y() == last_v_ && order == last_order_)) {
      last_sv_ = find_span(kv_, p_, uv.y());
      basis_functions(kv_, p_, last_sv_, uv.y(), order, last_bv_);
      last_v_ = uv.y();
      last_order_ = order;
    }
    const int sv = last_sv_;
    const Basis& bv = last_bv_;
    constexpr int kN = (detail::kMaxBasisDegree + 1) * (detail::kMaxBasisDegree + 1);
    double w[kN], wu[kN], wv[kN];
    const int n = p_ + 1;
    for (int b = 0; b < n; ++b)
      for (int a = 0; a < n; ++a) {
        w[a + n * b] = bu.value[a] * bv.value[b];
        if (order) {
          wu[a + n * b] = bu.d1[a] * bv.value[b];
          wv[a + n * b] = bu.value[a] * bv.d1[b];
        }
      }
    const int i0 = su - p_, j0 = sv - p_;
    for (int b = 0; b < n; ++b)
      for (int a = 0; a < n; ++a) {
        const int ab = a + n * b;
        const int k = i0 + a + nu_ * (j0 + b);
        Eigen::RowVector3d r = w[ab] * f.transpose();
        if (order) r += wd * (wu[ab] * fu.transpose() + wv[ab] * fv.transpose());
        rhs_.row(k) += r;
        double* row = &band_[static_cast<size_t>(k) * static_cast<size_t>(w_ * w_)];
        // The lower triangle only (pole cd at or before pole ab): solve() reads no other. One
        // row of poles at a time, a contiguous run in both the weights and the band.
        const double x = w[ab], xu = order ? wu[ab] : 0.0, xv = order ? wv[ab] : 0.0;
        for (int d = 0; d <= b; ++d) {
          const int cn = d < b ? n : a + 1;
          double* __restrict out = row + (p_ - a) + w_ * (d - b + p_);
          const double* __restrict w0 = w + n * d;
          if (order) {
            const double* __restrict u0 = wu + n * d;
            const double* __restrict v0 = wv + n * d;
            for (int c = 0; c < cn; ++c) out[c] += x * w0[c] + wd * (xu * u0[c] + xv * v0[c]);
          } else {
            for (int c = 0; c < cn; ++c) out[c] += x * w0[c];
          }
        }
      }
  }

  // lambda times the thin-plate energy of cell (iu, jv) (span indices from 0).
  void add_thin_plate(int iu, int jv, double lambda) {
    const int su = iu + p_, sv = jv + p_;
    double mu[3][10][10], mv[3][10][10];
    span_gram(ku_, su, mu);
    span_gram(kv_, sv, mv);
    const int n = p_ + 1, i0 = su - p_, j0 = sv - p_;
    for (int b = 0; b < n; ++b)
      for (int a = 0; a < n; ++a) {
        const int k = i0 + a + nu_ * (j0 + b);
        double* row = &band_[static_cast<size_t>(k) * static_cast<size_t>(w_ * w_)];
        for (int d = 0; d <= b; ++d)  // the lower triangle, as in add_sample()
          for (int c = 0; c < (d < b ? n : a + 1); ++c)
            row[(c - a + p_) + w_ * (d - b + p_)] +=
                lambda * (mu[2][a][c] * mv[0][b][d] + 2 * mu[1][a][c] * mv[1][b][d] + mu[0][a][c] * mv[2][b][d]);
      }
  }

  // The poles, or empty if the system could not be factored.
  std::vector<Point3> solve() const {
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(static_cast<size_t>(pole_count()) * static_cast<size_t>(w_ * w_ / 2 + 1));
    for (int j = 0; j < nv_; ++j)
      for (int i = 0; i < nu_; ++i) {
        const int k = i + nu_ * j;
        const double* row = &band_[static_cast<size_t>(k) * static_cast<size_t>(w_ * w_)];
        for (int dj = -p_; dj <= p_; ++dj)
          for (int di = -p_; di <= p_; ++di) {
            const int i2 = i + di, j2 = j + dj;
            if (i2 < 0 || i2 >= nu_ || j2 < 0 || j2 >= nv_) continue;
            const int l = i2 + nu_ * j2;
            if (l > k) continue;  // lower triangle
            const double v = row[(di + p_) + w_ * (dj + p_)];
            if (v != 0) entries.emplace_back(k, l, v);
          }
      }
    Eigen::SparseMatrix<double> a(pole_count(), pole_count());
    a.setFromTriplets(entries.begin(), entries.end());
    // CHOLMOD's supernodal factorization: the pole grid is a 2D stencil of (2p+1)^2 entries per
    // row, where Eigen's simplicial LDLT spent 70 % of a region fit.
    Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> chol;
    chol.setMode(Eigen::CholmodSupernodalLLt);
    chol.cholmod().print = 0;  // a failed factorization is handled by the caller, not printed
    // AMD only: METIS orderings differ from run to run, and so would the rounding of the
    // solution, and with it which knots get inserted.
    chol.cholmod().nmethods = 1;
    chol.cholmod().method[0].ordering = CHOLMOD_AMD;
    // The ordering and the symbolic analysis call no BLAS and run in parallel.
    chol.analyzePattern(a);
    if (chol.info() != Eigen::Success) return {};
    // One numeric factorization at a time: CHOLMOD's supernodal kernels call BLAS, and a
    // single-threaded BLAS (Debian's libopenblas0-serial, say) is not safe to call from two
    // threads at once; concurrent calls gave different results from run to run.
    static std::mutex blas;
    std::lock_guard lock(blas);
    {
      const SerialOpenMp serial;
      chol.factorize(a);
    }
    if (chol.info() != Eigen::Success) return {};
    const Eigen::MatrixX3d x = chol.solve(rhs_);
    if (chol.info() != Eigen::Success || !x.allFinite()) return {};
    std::vector<Point3> poles(static_cast<size_t>(pole_count()));
    for (int k = 0; k < pole_count(); ++k) poles[static_cast<size_t>(k)] = x.row(k).transpose();
    return poles;
  }

 private:
  // Gram matrices of the basis functions of span s and of their first and second
  // derivatives, integrated over the span (Gauss-Legendre, exact for these degrees).
  void span_gram(const std::vector<double>& k, int s, double g[3][10][10]) const {
    static const double x5[] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
    static const double w5[] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                                0.2369268850561891};
    static const double x10[] = {-0.9739065285171717, -0.8650633666889845, -0.6794095682990244, -0.4333953941292472,
                                 -0.1488743389816312, 0.1488743389816312,  0.4333953941292472,  0.6794095682990244,
                                 0.8650633666889845,  0.9739065285171717};
    static const double w10[] = {0.0666713443086881, 0.1494513491505806, 0.2190863625159820, 0.2692667193099963,
                                 0.2955242247147529, 0.2955242247147529, 0.2692667193099963, 0.2190863625159820,
                                 0.1494513491505806, 0.0666713443086881};
    const bool small = p_ <= 4;
    const int m = small ? 5 : 10;
    const double* x = small ? x5 : x10;
    const double* w = small ? w5 : w10;
    const double a = k[static_cast<size_t>(s)], b = k[static_cast<size_t>(s + 1)];
    for (int o = 0; o < 3; ++o)
      for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j) g[o][i][j] = 0;
    for (int q = 0; q < m; ++q) {
      const double t = 0.5 * (a + b) + 0.5 * (b - a) * x[q], wt = 0.5 * (b - a) * w[q];
      Basis bs;
      basis_functions(k, p_, s, t, 2, bs);
      const double* f[3] = {bs.value, bs.d1, bs.d2};
      for (int o = 0; o < 3; ++o)
        for (int i = 0; i <= p_; ++i)
          for (int j = 0; j <= p_; ++j) g[o][i][j] += wt * f[o][i] * f[o][j];
    }
  }

  int p_;
  const std::vector<double>& ku_;
  const std::vector<double>& kv_;
  int nu_, nv_, w_;
  std::vector<double> band_;
  Eigen::MatrixX3d rhs_;
  double last_v_ = std::numeric_limits<double>::quiet_NaN();  // NaN: no sample yet
  int last_order_ = -1, last_sv_ = 0;
  Basis last_bv_{};
};

// What a fit needs of its region, copied while no other fit changes the regions: its
// triangles, its border half-edges and which triangles of the domain it holds.
struct RegionView {
  int region;
  std::vector<int> triangles;
  std::vector<Regions::HalfEdge> border;
  std::vector<char> inside;
  // Over an atlas the border of a region is the domain's boundary, beyond the chart's
  // outline: not sampled (the outline is).
  RegionView(const Regions& regions, int r, bool atlas)
      : region(r), triangles(regions.triangles(r)),
        border(atlas ? std::vector<Regions::HalfEdge>{} : regions.border_half_edges(r)),
        inside(static_cast<size_t>(regions.domain().triangle_count()), 0) {
    for (int t : triangles) inside[static_cast<size_t>(t)] = 1;
  }
  bool holds(int t) const { return t >= 0 && inside[static_cast<size_t>(t)]; }
};

struct Context {
  const Spline& spline;
  const Evaluator& ev;
  const CadRegionOptions& o;
  double tol = 0;
  double angle = 0;  // the normal limit: half the angle tolerance
  // The check lattice of every domain triangle.
  std::vector<Sample> lattice;
  std::vector<size_t> lattice_start;
  // Triangles around the end of a crease: the spline's normal is not continuous at that
  // vertex (the crease's angle on one side, none on the other), so no smooth face can follow
  // it there; normals are not compared in them. (Normals are compared only along the borders
  // where two faces meet: that is where the angle tolerance keeps them together.)
  std::vector<char> near_tip;
  // Over an atlas: the charts' outlines. Only the part of a chart's domain inside them is
  // the surface: the faces are fitted and checked there, and along the outlines (the trims).
  const OutlineIndex* outline = nullptr;
  std::vector<std::vector<std::array<Point2, 2>>> outline_segments;  // per region
  bool keeps(const Point2& u) const { return !outline || outline->inside(u); }
};

std::array<Point2, 3> corners(const Domain& d, int t) {
  const auto& c = d.triangle(t);
  return {d.vertex(c[0]), d.vertex(c[1]), d.vertex(c[2])};
}

Sample make_sample(const Point2& uv, const SurfacePoint& sp, bool compare_normal = true) {
  Sample s;
  s.uv = uv;
  s.f = sp.position;
  s.fu = sp.du;
  s.fv = sp.dv;
  s.regular = compare_normal && regular(sp);
  s.n = detail::unit_normal(sp);
  return s;
}

struct FitResult {
  BSplineSurface3 surface;
  double position_dev = std::numeric_limits<double>::infinity();
  double normal_dev = 0;
  bool within = false;
  bool over_budget = false;
  bool normals_stalled = false;
  // Where the last fit missed the position tolerance by the most (NaN if nowhere).
  Point2 worst = Point2::Constant(std::numeric_limits<double>::quiet_NaN());
  // Over the budget by projection: the last rounds' convergence says that the tolerances need
  // more than the budget (fit_region(), `early`).
  bool projected = false;
  // The worst spot stayed put while the error fell more slowly than the pole count grew: the
  // spline turns there faster than elsewhere in the region (a fold, a cone's tip).
  bool slow_spot = false;
};

// Samples along the border of a region, evaluated on the region's side, about `spacing`
// apart (in (u, v)); `offset` 0.5 gives the points halfway between those of offset 0.
void border_samples(const Context& c, const std::vector<Regions::HalfEdge>& border, double spacing,
                    double offset, std::vector<Sample>& out) {
  const Domain& d = c.spline.domain();
  for (const auto& h : border) {
    const Point2 &a = d.vertex(h.from), &b = d.vertex(h.to);
    const int count = static_cast<int>(std::clamp(std::ceil((b - a).norm() / spacing), 1.0, 4096.0));
    const auto tri = corners(d, h.triangle);
    for (int k = 0; k < count; ++k) {
      const double t = (k + offset) / count;
      const Point2 u = a + t * (b - a);
      // Normals matter where this face meets another one: not on the domain's boundary.
      const bool shared = !d.is_boundary_edge(d.find_edge(h.from, h.to));
      out.push_back(make_sample(u, detail::evaluate_in_triangle(c.ev, tri, u),
                                shared && !c.near_tip[static_cast<size_t>(h.triangle)]));
    }
  }
}

// Over an atlas: samples along the outline of region r's chart, about `spacing` apart (in
// (u, v)); `offset` 0.5 gives the points halfway between those of offset 0.
void outline_samples(const Context& c, int r, double spacing, double offset, std::vector<Sample>& out) {
  if (!c.outline) return;
  for (const auto& [a, b] : c.outline_segments[static_cast<size_t>(r)]) {
    const int count = static_cast<int>(std::clamp(std::ceil((b - a).norm() / spacing), 1.0, 4096.0));
    for (int k = 0; k < count; ++k) {
      const Point2 u = a + (k + offset) / count * (b - a);
      out.push_back(make_sample(u, c.ev.evaluate(u), false));
    }
  }
}

// The samples of a rectangle grid (us x vs) at its points in the region, kept from one round
// of a fit to the next: refinement bisects some spans and keeps the others, and a kept span's
// grid points come back bit for bit (the same breaks give the same inner points and
// midpoints), so only the new points are located and evaluated. On lion.off's region faces
// about half of the grid points of a round were evaluated in an earlier round.
class GridSamples {
 public:
  // Appends the samples of the grid (us x vs, both increasing) in the region to `out`, v
  // outer, u inner.
  void update(const Context& c, const RegionView& rv, const std::vector<double>& us, const std::vector<double>& vs,
              std::vector<Sample>& out) {
    const std::vector<int> ou = match(us_, us), ov = match(vs_, vs);
    // Per new grid point: an old sample (>= 0), outside the region (-1) or to evaluate (-2).
    std::vector<int> at(us.size() * vs.size());
    std::vector<Point2> pts;
    for (size_t j = 0; j < vs.size(); ++j)
      for (size_t i = 0; i < us.size(); ++i) {
        int& a = at[i + us.size() * j];
        if (ou[i] >= 0 && ov[j] >= 0) {
          a = at_[static_cast<size_t>(ou[i]) + us_.size() * static_cast<size_t>(ov[j])];
          continue;
        }
        const Point2 q(us[i], vs[j]);
        a = rv.holds(c.ev.locate(q)) && c.keeps(q) ? -2 : -1;
        if (a == -2) pts.push_back(q);
      }
    std::vector<Point3> pos(pts.size());
    std::vector<Vector3> du(pts.size()), dv(pts.size());
    std::vector<uint8_t> inside(pts.size());
    c.ev.evaluate_batch(pts, pos, du, dv, inside, c.o.threads);
    std::vector<Sample> samples;
    size_t next = 0;
    for (int& a : at) {
      if (a >= 0) {
        samples.push_back(samples_[static_cast<size_t>(a)]);
      } else if (a == -2) {
        const size_t k = next++;
        if (!inside[k]) {
          a = -1;
          continue;
        }
        samples.push_back(make_sample(pts[k], SurfacePoint{pos[k], du[k], dv[k]}, false));
      } else {
        continue;
      }
      a = static_cast<int>(samples.size()) - 1;
    }
    out.insert(out.end(), samples.begin(), samples.end());
    us_ = us;
    vs_ = vs;
    at_ = std::move(at);
    samples_ = std::move(samples);
  }

 private:
  // For every value of `now`, its index in `before` (equal bits), or -1.
  static std::vector<int> match(const std::vector<double>& before, const std::vector<double>& now) {
    std::vector<int> out(now.size(), -1);
    size_t k = 0;
    for (size_t i = 0; i < now.size(); ++i) {
      while (k < before.size() && before[k] < now[i]) ++k;
      if (k < before.size() && before[k] == now[i]) out[i] = static_cast<int>(k);
    }
    return out;
  }

  std::vector<double> us_, vs_;
  std::vector<int> at_;  // per grid point (u inner): index into samples_, or -1 outside the region
  std::vector<Sample> samples_;
};

// Stops refining a region whose last two rounds project a need of more than this many times
// the pole budget (the error falling as a power of the pole count).
constexpr double kProjectedOver = 4.0;
// Below this rate (error ~ poles^-rate) at a spot that stays put, the spot is carved out of its
// region: smooth parts converge at about poles^-(p+1)/2, a kink at poles^-1/2.
constexpr double kSlowRate = 1.0;

// Fits region r. With `early`, stops as soon as the last rounds project a pole count over
// kProjectedOver times the budget (the caller then splits the region).
FitResult fit_region(const Context& c, const RegionView& rv, bool early) {
  const Domain& d = c.spline.domain();
  const std::vector<int>& tris = rv.triangles;
  const int p = c.o.degree;
  Box2 box;
  double area = 0;
  for (int t : tris) {
    const auto tri = corners(d, t);
    for (const Point2& q : tri) box.extend(q);
    area += 0.5 * std::fabs(det3(tri[0], tri[1], tri[2]));
  }
  const Vector2 size = box.max - box.min;
  const double margin = kMargin * std::max(size.x(), size.y());
  const Point2 lo = box.min - Vector2::Constant(margin), hi = box.max + Vector2::Constant(margin);
  const double h = std::sqrt(2 * area / static_cast<double>(tris.size()));
  const auto& border = rv.border;

  // The fixed part of the check: the lattice of every triangle of the region.
  std::vector<Sample> lattice;
  for (int t : tris)
    for (size_t k = c.lattice_start[static_cast<size_t>(t)]; k < c.lattice_start[static_cast<size_t>(t) + 1]; ++k)
      if (c.keeps(c.lattice[k].uv)) lattice.push_back(c.lattice[k]);

  auto spans_for = [&](double extent) { return std::max(1, static_cast<int>(std::ceil(extent / h))); };
  std::vector<double> bu = uniform_breaks(lo.x(), hi.x(), spans_for(hi.x() - lo.x()));
  std::vector<double> bv = uniform_breaks(lo.y(), hi.y(), spans_for(hi.y() - lo.y()));
  // Start below a quarter of the budget.
  while (static_cast<long>(bu.size() - 1 + static_cast<size_t>(p)) * static_cast<long>(bv.size() - 1 + static_cast<size_t>(p)) >
             c.o.max_poles / 4 &&
         (bu.size() > 2 || bv.size() > 2)) {
    if (bu.size() >= bv.size())
      bu = uniform_breaks(lo.x(), hi.x(), static_cast<int>(bu.size() - 1) / 2);
    else
      bv = uniform_breaks(lo.y(), hi.y(), static_cast<int>(bv.size() - 1) / 2);
  }

  // Derivatives are fitted too, weighted so that an error of the normal limit in them weighs
  // as much as one of the tolerance in position: |F_u| * angle ~ tol.
  std::vector<double> speeds;
  for (const Sample& q : lattice) speeds.push_back(std::max(q.fu.norm(), q.fv.norm()));
  std::nth_element(speeds.begin(), speeds.begin() + static_cast<long>(speeds.size() / 2), speeds.end());
  const double speed = speeds.empty() ? 0.0 : speeds[speeds.size() / 2];
  const double slope = speed * c.angle * kPi / 180;
  const double derivative_weight = slope > 0 ? (c.tol / slope) * (c.tol / slope) : 0.0;

  FitResult best;
  std::vector<double> normal_history;
  struct Round {
    long poles;
    double badness;  // the largest deviation over its limit (with the margins)
    Point2 worst;
  };
  std::vector<Round> rounds;
  GridSamples fit_grid, check_grid;
  for (int round = 0; round < kMaxRounds; ++round) {
    const long poles = static_cast<long>(bu.size() - 1 + static_cast<size_t>(p)) *
                       static_cast<long>(bv.size() - 1 + static_cast<size_t>(p));
    if (poles > c.o.max_poles) {
      best.over_budget = true;
      return best;
    }
    BSplineSurface3 s;
    s.degree_u = s.degree_v = p;
    s.knots_u = detail::clamped_knots(p, bu);
    s.knots_v = detail::clamped_knots(p, bv);
    double min_span = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i + 1 < bu.size(); ++i) min_span = std::min(min_span, bu[i + 1] - bu[i]);
    for (size_t i = 0; i + 1 < bv.size(); ++i) min_span = std::min(min_span, bv[i + 1] - bv[i]);

    // Fit samples: 3 x 3 per cell (with derivatives), and the border. 4 x 4 took more poles
    // and faces for the same tolerance (head.off 122 region faces, 99 with 3 x 3).
    std::vector<Sample> fit;
    fit_grid.update(c, rv, inner_points(bu, std::min(p, 2)), inner_points(bv, std::min(p, 2)), fit);
    border_samples(c, border, min_span / (p + 1), 0.0, fit);
    outline_samples(c, rv.region, min_span / (p + 1), 0.0, fit);
    // Thin plate per cell: relative to the data a cell holds, 3 x 3 samples.
    const double per_cell = 9;
    std::vector<double> lambda;
    for (size_t j = 0; j + 1 < bv.size(); ++j)
      for (size_t i = 0; i + 1 < bu.size(); ++i) {
        const double hu = bu[i + 1] - bu[i], hv = bv[j + 1] - bv[j], hm = std::max(hu, hv);
        const Point2 centre(0.5 * (bu[i] + bu[i + 1]), 0.5 * (bv[j] + bv[j + 1]));
        const int t = c.ev.locate(centre);
        const bool inside = rv.holds(t);
        lambda.push_back((inside ? kSmoothInside : kSmoothOutside) * per_cell * hm * hm * hm * hm / (hu * hv));
      }
    // A system that cannot be factored, or whose solution misses its own samples by far more
    // than the last round's surface did (rounding on a nearly singular system), is solved again
    // with a stronger thin plate. Far: 100 times. A round's new samples can be harder than the
    // last round's (on sphere966.off a one-triangle island missed 0.0016 with 42 poles, then
    // 0.032 with 63 poles and 0.25 with the strongest plate); 10 times threw such rounds away.
    const double bound = 100 * std::max(best.position_dev, c.tol);
    for (double scale : {1.0, 1e2, 1e4}) {
      TensorSystem sys(p, s.knots_u, s.knots_v);
      for (const Sample& q : fit) sys.add_sample(q.uv, q.f, q.fu, q.fv, derivative_weight);
      size_t k = 0;
      for (size_t j = 0; j + 1 < bv.size(); ++j)
        for (size_t i = 0; i + 1 < bu.size(); ++i)
          sys.add_thin_plate(static_cast<int>(i), static_cast<int>(j), scale * lambda[k++]);
      s.poles = sys.solve();
      if (s.poles.empty()) continue;
      double miss = 0;
      for (const Sample& q : fit) miss = std::max(miss, (s.value(q.uv) - q.f).norm());
      if (miss <= bound) break;
      s.poles.clear();
    }
    if (s.poles.empty()) {
      // Keep the last round's surface: it is what the result says it is.
      if (best.surface.poles.empty())
        throw SolverError("region faces: the least-squares system of a region could not be solved");
      best.over_budget = false;
      return best;
    }

    // Check samples: breaks and midpoints of the grid, the border between the fit samples,
    // and the triangle lattices.
    std::vector<Sample> check;
    check_grid.update(c, rv, breaks_and_midpoints(bu), breaks_and_midpoints(bv), check);
    border_samples(c, border, min_span / (p + 1), 0.5, check);
    outline_samples(c, rv.region, min_span / (p + 1), 0.5, check);
    check.insert(check.end(), lattice.begin(), lattice.end());
    double pos_dev = 0, normal_dev = 0;
    std::vector<char> mark_u(bu.size() - 1, 0), mark_v(bv.size() - 1, 0);
    bool failed = false;
    // Normals that two rounds of refinement did not bring below kNormalStall of what they were
    // turn faster than a face can follow (near a cone's tip, a fold, the end of a crease): they
    // no longer drive refinement, and the result says by how much they miss.
    double worst_dev = 0;
    Point2 worst_uv = Point2::Constant(std::numeric_limits<double>::quiet_NaN());
    const size_t nh = normal_history.size();
    const bool normals_stalled = nh >= 3 && normal_history[nh - 1] > kNormalStall * normal_history[nh - 3];
    for (const Sample& q : check) {
      Point3 sp;
      Vector3 su, sv;
      s.evaluate(q.uv, sp, su, sv);
      const double dev = (sp - q.f).norm();
      double ang = 0;
      const Vector3 n = su.cross(sv);
      if (q.regular && n.norm() > 0) ang = angle_deg(n, q.n);
      pos_dev = std::max(pos_dev, dev);
      normal_dev = std::max(normal_dev, ang);
      if (dev > kPositionMargin * c.tol && dev > worst_dev) {
        worst_dev = dev;
        worst_uv = q.uv;
      }
      if (dev > kPositionMargin * c.tol || (!normals_stalled && ang > kNormalMargin * c.angle)) {
        failed = true;
        const int iu = span_of(bu, q.uv.x()), jv = span_of(bv, q.uv.y());
        // Refine the direction in which the cell is long on the surface.
        const double lu = su.norm() * (bu[static_cast<size_t>(iu) + 1] - bu[static_cast<size_t>(iu)]);
        const double lv = sv.norm() * (bv[static_cast<size_t>(jv) + 1] - bv[static_cast<size_t>(jv)]);
        if (lu >= 0.5 * lv) mark_u[static_cast<size_t>(iu)] = 1;
        if (lv >= 0.5 * lu) mark_v[static_cast<size_t>(jv)] = 1;
      }
    }
    best.surface = std::move(s);
    best.position_dev = pos_dev;
    best.normal_dev = normal_dev;
    best.within = !failed && normal_dev <= c.angle && pos_dev <= c.tol;
    best.normals_stalled = normals_stalled;
    best.worst = worst_uv;
    if (!failed) return best;
    normal_history.push_back(normal_dev);
    const double badness = std::max(pos_dev / (kPositionMargin * c.tol),
                                    normals_stalled ? 0.0 : normal_dev / (kNormalMargin * c.angle));
    rounds.push_back({poles, badness, worst_uv});
    if (early && rounds.size() >= 3) {
      // error ~ poles^-rate between rounds; the poles that the tolerances need at the better
      // of the last two rates.
      auto rate = [](const Round& a, const Round& b) {
        return b.poles > a.poles && a.badness > b.badness
                   ? std::log(a.badness / b.badness) / std::log(static_cast<double>(b.poles) / a.poles)
                   : 0.0;
      };
      const size_t n = rounds.size();
      const double best_rate = std::max(rate(rounds[n - 3], rounds[n - 2]), rate(rounds[n - 2], rounds[n - 1]));
      const double need = best_rate > 0 ? static_cast<double>(poles) * std::pow(badness, 1 / best_rate)
                                        : std::numeric_limits<double>::infinity();
      if (need > kProjectedOver * static_cast<double>(c.o.max_poles)) {
        best.over_budget = best.projected = true;
        bool still = true;
        for (size_t k = n - 3; k + 1 < n; ++k)
          still = still && rounds[k].worst.allFinite() && rounds[n - 1].worst.allFinite() &&
                  (rounds[k].worst - rounds[n - 1].worst).norm() <= 2 * h;
        best.slow_spot = still && best_rate < kSlowRate;
        return best;
      }
    }
    auto refine = [](const std::vector<double>& br, const std::vector<char>& mark) {
      std::vector<double> out;
      for (size_t i = 0; i + 1 < br.size(); ++i) {
        out.push_back(br[i]);
        if (mark[i]) out.push_back(0.5 * (br[i] + br[i + 1]));
      }
      out.push_back(br.back());
      return out;
    };
    bu = refine(bu, mark_u);
    bv = refine(bv, mark_v);
  }
  // Not within the tolerance after every round: as over the budget.
  best.over_budget = true;
  return best;
}

// The triangle of `tris` whose centroid is nearest to u.
int nearest_triangle(const Domain& d, const std::vector<int>& tris, const Point2& u) {
  int best = tris.front();
  double bd = std::numeric_limits<double>::infinity();
  for (int t : tris) {
    const auto c = corners(d, t);
    const double dd = ((c[0] + c[1] + c[2]) / 3.0 - u).squaredNorm();
    if (dd < bd) bd = dd, best = t;
  }
  return best;
}

// The 3D curve of a straight trim edge: fitted to F along the (u, v) segment of its chain,
// within a quarter of the tolerance.
struct TrimCurve {
  BSplineCurve3 curve;
  double length = 0;
};

TrimCurve fit_trim_curve(const Context& c, const std::vector<int>& chain, int degree) {
  const Domain& d = c.spline.domain();
  const Point2 a = d.vertex(chain.front()), b = d.vertex(chain.back());
  TrimCurve out;
  out.length = (b - a).norm();
  const Vector2 dir = (b - a) / out.length;
  // Position of each chain vertex along the segment, for choosing the triangle to evaluate in.
  std::vector<double> at(chain.size());
  for (size_t i = 0; i < chain.size(); ++i) at[i] = (d.vertex(chain[i]) - a).dot(dir);
  auto spline_at = [&](double t) {
    const size_t i = std::min<size_t>(
        static_cast<size_t>(std::max<long>(std::upper_bound(at.begin(), at.end(), t) - at.begin() - 1, 0)),
        chain.size() - 2);
    const int e = d.find_edge(chain[i], chain[i + 1]);
    const int tri = d.edge_triangles(e)[0];
    const Point2 u = a + t * dir;
    return detail::evaluate_in_triangle(c.ev, corners(d, tri), u).position;
  };
  out.curve = detail::fit_trim_curve(spline_at, out.length, static_cast<int>(chain.size()) - 1, at, degree,
                                     kCurveMargin * c.tol, kMaxRounds);
  return out;
}

// Largest distance between the curve and the surface of a face along the segment.
double trim_gap(const TrimCurve& tc, const BSplineSurface3& s, const Point2& a, const Point2& b) {
  const int spans = static_cast<int>(tc.curve.knots.size()) - 2 * tc.curve.degree - 1;
  const int n = std::max(16, 8 * spans);
  double gap = 0;
  for (int i = 0; i <= n; ++i) {
    const double f = static_cast<double>(i) / n;
    gap = std::max(gap, (tc.curve.value(f * tc.length) - s.value(a + f * (b - a))).norm());
  }
  return gap;
}

}  // namespace

CadRegions make_cad_regions(const Spline& spline, const CadRegionOptions& o) {
  return make_cad_regions(spline, Atlas{}, o);
}

CadRegions make_cad_regions(const Spline& spline, const Atlas& atlas_in, const CadRegionOptions& o) {
  const Domain& d = spline.domain();
  if (d.triangle_count() == 0) throw InvalidInput("region faces: the spline has no triangles");
  if (!(o.tolerance > 0) && !(o.tolerance_abs > 0))
    throw InvalidInput("region faces: the CAD tolerance must be positive");
  if (!(o.angle_tolerance > 0 && o.angle_tolerance < 90))
    throw InvalidInput("region faces: the angle tolerance must be between 0 and 90 degrees");
  if (o.degree < 2 || o.degree > detail::kMaxBasisDegree)
    throw InvalidInput("region faces: the face degree must be 2 to 9, not " + std::to_string(o.degree));
  if (o.max_poles < static_cast<long>(o.degree + 1) * (o.degree + 1))
    throw InvalidInput("region faces: the pole budget must be at least (degree + 1)^2 = " +
                       std::to_string((o.degree + 1) * (o.degree + 1)));
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  return arena.execute([&] {
    const Evaluator ev(spline);
    const bool atlas = !atlas_in.empty();
    if (atlas) check_atlas_structure(atlas_in, "region faces");
    Regions regions(d, !atlas);
    CadRegions out;
    out.atlas = atlas;
    out.closed = atlas && atlas_in.closed;
    out.tolerance = o.tolerance_abs > 0 ? o.tolerance_abs : o.tolerance * detail::model_size(spline);
    out.angle_tolerance = o.angle_tolerance;
    const auto [extended, left] = regions.extend_creases();
    out.crease_extensions = extended;
    out.creases_left_inside = left;
    regions.label_all();
    out.smooth_regions = regions.region_count();

    Context c{spline, ev, o, out.tolerance, o.angle_tolerance / 2, {}, {}, {}};
    c.near_tip.assign(static_cast<size_t>(d.triangle_count()), 0);
    std::optional<OutlineIndex> outline;
    if (atlas) {
      const std::vector<std::vector<Point2>> loops = chart_outlines(atlas_in);
      outline.emplace(loops);
      c.outline = &*outline;
      c.outline_segments.resize(static_cast<size_t>(regions.region_count()));
      for (const auto& loop : loops) {
        const int t = ev.locate(0.5 * (loop[0] + loop[1]));
        if (t < 0) throw Error("region faces: a chart's outline passes outside the domain");
        auto& segs = c.outline_segments[static_cast<size_t>(regions.label(t))];
        for (size_t i = 0; i < loop.size(); ++i) segs.push_back({loop[i], loop[(i + 1) % loop.size()]});
      }
    }
    for (int v : regions.crease_tips())
      for (int t : d.vertex_triangles(v)) c.near_tip[static_cast<size_t>(t)] = 1;
    // The check lattice of every triangle, evaluated inside that triangle.
    const int per = (kLattice + 1) * (kLattice + 2) / 2;
    c.lattice.resize(static_cast<size_t>(d.triangle_count()) * static_cast<size_t>(per));
    c.lattice_start.resize(static_cast<size_t>(d.triangle_count()) + 1);
    for (int t = 0; t <= d.triangle_count(); ++t) c.lattice_start[static_cast<size_t>(t)] = static_cast<size_t>(t) * per;
    tbb::parallel_for(0, d.triangle_count(), [&](int t) {
      const auto tri = corners(d, t);
      size_t k = c.lattice_start[static_cast<size_t>(t)];
      for (int i = 0; i <= kLattice; ++i)
        for (int j = 0; j <= kLattice - i; ++j) {
          const double b1 = static_cast<double>(i) / kLattice, b2 = static_cast<double>(j) / kLattice;
          const Point2 u = (1 - b1 - b2) * tri[0] + b1 * tri[1] + b2 * tri[2];
          c.lattice[k++] = make_sample(u, detail::evaluate_in_triangle(ev, tri, u), false);
        }
    });

    // Fit every region, in parallel; split one over the budget and fit its parts as soon as its
    // fit is done (no round waits for its slowest region). Each fit sees a copy of its region
    // taken under the lock, and a split changes only the region it splits, so the regions that
    // come out do not depend on the order in which fits finish; their numbers do, and are made
    // canonical afterwards.
    std::vector<FitResult> fits(static_cast<size_t>(regions.region_count()));
    // Regions that can be split no further: fitted to the whole budget, without projection.
    std::vector<char> to_budget(fits.size(), 0);
    std::vector<int> first(fits.size());
    std::iota(first.begin(), first.end(), 0);
    std::mutex lock;
    // Progress: regions fitted and regions still to fit (splits add to them).
    size_t done = 0, to_fit = first.size();
    auto last_said = std::chrono::steady_clock::now();
    auto cuts = [&] {
      return std::to_string(out.budget_splits) + " splits and " + std::to_string(out.islands) +
             " islands for the pole budget";
    };
    tbb::parallel_for_each(first.begin(), first.end(), [&](int r, tbb::feeder<int>& feeder) {
      const auto rr = static_cast<size_t>(r);
      bool early = true;
      const RegionView view = [&] {
        std::lock_guard guard(lock);
        early = !to_budget[rr];
        return RegionView(regions, r, atlas);
      }();
      FitResult f = fit_region(c, view, early);
      std::lock_guard guard(lock);
      if (f.over_budget && atlas) {
        // A chart's face is trimmed by its outline, which no split or island follows: it
        // takes the whole budget.
        const bool again = !to_budget[rr];
        if (again) {
          to_budget[rr] = 1;
          feeder.add(r);
          ++to_fit;
        } else {
          ++out.unsplittable;
          ++done;
        }
      } else if (f.over_budget) {
        const int before = regions.region_count();
        bool again = true;
        if (f.slow_spot && regions.carve(r, nearest_triangle(d, regions.triangles(r), f.worst)))
          ++out.islands;
        else if (regions.split(r, f.worst))
          ++out.budget_splits;
        else if (f.projected)
          to_budget[rr] = 1;
        else
          again = false, ++out.unsplittable;
        fits.resize(static_cast<size_t>(regions.region_count()));
        to_budget.resize(fits.size(), 0);
        if (again) {
          feeder.add(r);
          for (int k = before; k < regions.region_count(); ++k) feeder.add(k);
          to_fit += 1 + static_cast<size_t>(regions.region_count() - before);
        }
        done += !again;
      } else {
        ++done;
      }
      --to_fit;
      fits[rr] = std::move(f);
      const auto now = std::chrono::steady_clock::now();
      if (o.progress && now - last_said >= std::chrono::seconds(2)) {
        last_said = now;
        o.progress("fitting region faces: " + std::to_string(done) + " fitted, " + std::to_string(to_fit) +
                   " to fit (" + cuts() + " so far)");
      }
    });
    if (o.progress) o.progress("fitted " + std::to_string(done) + " region faces (" + cuts() + ")");
    {
      const std::vector<int> order = regions.renumber();
      std::vector<FitResult> sorted(fits.size());
      for (size_t k = 0; k < order.size(); ++k) sorted[k] = std::move(fits[static_cast<size_t>(order[k])]);
      fits = std::move(sorted);
    }

    // Faces.
    out.faces.resize(static_cast<size_t>(regions.region_count()));
    bool within = true;
    for (int r = 0; r < regions.region_count(); ++r) {
      RegionFace& f = out.faces[static_cast<size_t>(r)];
      FitResult& fr = fits[static_cast<size_t>(r)];
      f.surface = std::move(fr.surface);
      f.triangles = regions.triangles(r);
      f.max_position_deviation = fr.position_dev;
      f.max_normal_deviation = fr.normal_dev;
      f.within_tolerance = fr.within;
      out.normal_stalls += fr.normals_stalled ? 1 : 0;
      within = within && fr.within;
      out.poles += f.surface.poles.size();
      out.max_position_deviation = std::max(out.max_position_deviation, fr.position_dev);
      out.max_normal_deviation = std::max(out.max_normal_deviation, fr.normal_dev);
    }

    if (atlas) {
      const Charts charts = domain_charts(d);
      std::vector<int> face_of_chart(static_cast<size_t>(charts.count), -1);
      for (int r = 0; r < regions.region_count(); ++r)
        face_of_chart[static_cast<size_t>(charts.of_triangle[static_cast<size_t>(regions.triangles(r).front())])] = r;
      detail::atlas_trims(atlas_in, ev, charts, face_of_chart, kCurveMargin * c.tol, o.degree, kMaxRounds, out);
      out.within_tolerance = within && out.unsplittable == 0;
      return out;
    }

    // Topological vertices: where the region borders meet, turn, or change their kind or
    // their pair of faces.
    std::vector<std::vector<int>> border_at(static_cast<size_t>(d.vertex_count()));
    for (int e = 0; e < d.edge_count(); ++e)
      if (regions.is_region_border(e))
        for (int v : d.edges()[static_cast<size_t>(e)]) border_at[static_cast<size_t>(v)].push_back(e);
    auto face_pair = [&](int e) {
      const auto tr = d.edge_triangles(e);
      const int a = regions.label(tr[0]), b = tr[1] < 0 ? -1 : regions.label(tr[1]);
      return std::make_pair(std::min(a, b), std::max(a, b));
    };
    auto edge_kind = [&](int e) {
      // Borders made by relabelling only (a split) keep the kind recorded for the edge.
      return regions.kind(e);
    };
    std::vector<int> topo(static_cast<size_t>(d.vertex_count()), -1);
    auto make_vertex = [&](int v) {
      if (topo[static_cast<size_t>(v)] >= 0) return;
      topo[static_cast<size_t>(v)] = static_cast<int>(out.vertex_ids.size());
      out.vertex_ids.push_back(v);
    };
    for (int v = 0; v < d.vertex_count(); ++v) {
      const auto& be = border_at[static_cast<size_t>(v)];
      if (be.empty()) continue;
      if (be.size() != 2) {
        make_vertex(v);
        continue;
      }
      const int a = regions.other(be[0], v), b = regions.other(be[1], v);
      const Vector2 x = d.vertex(a) - d.vertex(v), y = d.vertex(b) - d.vertex(v);
      const bool straight = std::fabs(det3(d.vertex(a), d.vertex(v), d.vertex(b))) <= kCollinear * x.norm() * y.norm() &&
                            x.dot(y) < 0;
      if (!straight || face_pair(be[0]) != face_pair(be[1]) || edge_kind(be[0]) != edge_kind(be[1])) make_vertex(v);
    }

    // Edges: runs of border domain edges between topological vertices, oriented with the
    // lower-numbered face on the left (boundary runs: the domain on the left).
    std::map<std::pair<int, int>, std::pair<int, bool>> run_of;  // directed domain edge -> (run, forward)
    for (int r = 0; r < regions.region_count(); ++r) {
      for (auto& loop : regions.loops(r)) {
        // Start at a topological vertex.
        size_t start = loop.size();
        for (size_t i = 0; i < loop.size(); ++i)
          if (topo[static_cast<size_t>(loop[i].from)] >= 0) {
            start = i;
            break;
          }
        if (start == loop.size()) {
          make_vertex(loop[0].from);
          make_vertex(loop[loop.size() / 2].from);
          start = 0;
        }
        std::rotate(loop.begin(), loop.begin() + static_cast<long>(start), loop.end());
        std::vector<RegionEdgeUse> uses;
        for (size_t i = 0; i < loop.size();) {
          const auto key = std::make_pair(loop[i].from, loop[i].to);
          auto found = run_of.find(key);
          if (found == run_of.end()) {
            // A new run, from here to the next topological vertex, with face r on its left.
            RegionEdge edge;
            edge.faces[0] = r;
            const int e = d.find_edge(loop[i].from, loop[i].to);
            const auto tr = d.edge_triangles(e);
            if (tr[1] >= 0) edge.faces[1] = regions.label(tr[0]) == r ? regions.label(tr[1]) : regions.label(tr[0]);
            edge.kind = edge_kind(e);
            edge.chain.push_back(loop[i].from);
            const int id = static_cast<int>(out.edges.size());
            size_t j = i;
            do {
              edge.chain.push_back(loop[j].to);
              run_of[{loop[j].from, loop[j].to}] = {id, true};
              run_of[{loop[j].to, loop[j].from}] = {id, false};
              ++j;
            } while (j < loop.size() && topo[static_cast<size_t>(loop[j].from)] < 0);
            edge.vertices = {topo[static_cast<size_t>(edge.chain.front())], topo[static_cast<size_t>(edge.chain.back())]};
            out.edges.push_back(std::move(edge));
            uses.push_back({id, false});
            i = j;
          } else {
            const auto [id, forward] = found->second;
            uses.push_back({id, !forward});
            i += out.edges[static_cast<size_t>(id)].chain.size() - 1;
          }
        }
        out.faces[static_cast<size_t>(r)].loops.push_back(std::move(uses));
      }
    }

    // Vertex positions, trim curves and gaps.
    out.vertices.resize(out.vertex_ids.size());
    for (int v : out.vertex_ids) out.vertex_parameters.push_back(d.vertex(v));
    tbb::parallel_for(size_t(0), out.vertex_ids.size(), [&](size_t i) {
      const int v = out.vertex_ids[i];
      const int t = d.vertex_triangles(v)[0];
      out.vertices[i] = detail::evaluate_in_triangle(ev, corners(d, t), d.vertex(v)).position;
    });
    tbb::parallel_for(size_t(0), out.edges.size(), [&](size_t i) {
      RegionEdge& e = out.edges[i];
      TrimCurve tc = fit_trim_curve(c, e.chain, o.degree);
      const Point2 a = d.vertex(e.chain.front()), b = d.vertex(e.chain.back());
      e.gap = 0;
      for (int f : e.faces)
        if (f >= 0) e.gap = std::max(e.gap, trim_gap(tc, out.faces[static_cast<size_t>(f)].surface, a, b));
      e.curve = std::move(tc.curve);
      e.length = tc.length;
    });
    for (const RegionEdge& e : out.edges) out.max_gap = std::max(out.max_gap, e.gap);
    out.within_tolerance = within && out.unsplittable == 0;
    return out;
  });
}

}  // namespace tbs
