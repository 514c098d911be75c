// The region of the parameter plane that the fit domain covers, and its outline: the
// region of a mesh's faces, or of bare points (a Delaunay triangulation cut back to an alpha
// shape of the local spacing), its largest component, its boundary loops, and the polyline
// simplification and resampling the domain's outline is made with.

#include "fit_region.h"

#include <tbs/errors.h>

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace tbs::detail {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using CPoint = K::Point_2;

// Region triangulation of bare parameters.
using DtVb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using DtFb = CGAL::Triangulation_face_base_with_info_2<int, K>;
using Dt = CGAL::Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<DtVb, DtFb>>;

CPoint cp(const Point2& p) { return {p.x(), p.y()}; }

bool has_point(const std::array<int, 3>& t, int v) { return t[0] == v || t[1] == v || t[2] == v; }

// The stars of a region's points.
void add_stars(Adjacency& a, const Region& r, size_t n_points) {
  a.start.assign(n_points + 1, 0);
  for (const auto& t : r.tris)
    for (int v : t) ++a.start[v + 1];
  for (size_t v = 0; v < n_points; ++v) a.start[v + 1] += a.start[v];
  a.star.resize(static_cast<size_t>(a.start[n_points]));
  std::vector<int> fill(a.start.begin(), a.start.end() - 1);
  for (size_t f = 0; f < r.tris.size(); ++f)
    for (int v : r.tris[f]) a.star[fill[v]++] = static_cast<int>(f);
}

}  // namespace

// The adjacency of a region whose neighbours are already known: `across` as Adjacency holds
// it, for a region where every edge has at most two triangles, run in opposite directions (a
// triangulation's triangles; then no edge repeats and each has the one neighbour the search
// below would find).
Adjacency adjacency(const Region& r, size_t n_points, std::vector<std::array<int, 3>> across) {
  Adjacency a;
  add_stars(a, r, n_points);
  a.across = std::move(across);
  return a;
}

Adjacency adjacency(const Region& r, size_t n_points) {
  Adjacency a;
  add_stars(a, r, n_points);
  // The neighbours of each triangle in parallel (each writes its own entries; the caller's
  // arena sets the threads), then the first duplicate edge in triangle order.
  a.across.resize(r.tris.size());
  std::vector<int8_t> duplicate_at(r.tris.size(), -1);  // the first edge k of f that repeats one
  tbb::parallel_for(size_t{0}, r.tris.size(), [&](size_t f) {
    for (int k = 0; k < 3; ++k) {
      const int from = r.tris[f][k], to = r.tris[f][(k + 1) % 3];
      int g = -1;
      for (int q : a.star_of(from)) {
        if (q == static_cast<int>(f)) continue;
        const auto& t = r.tris[q];
        const int at = t[0] == from ? 0 : t[1] == from ? 1 : 2;
        if (t[(at + 1) % 3] == to && q < static_cast<int>(f) && duplicate_at[f] < 0) duplicate_at[f] = static_cast<int8_t>(k);
        if (g < 0 && (t[(at + 1) % 3] == to || t[(at + 2) % 3] == to)) g = q;
      }
      a.across[f][k] = g;
    }
  });
  for (size_t f = 0; f < r.tris.size(); ++f)
    if (duplicate_at[f] >= 0) {
      const int k = duplicate_at[f];
      a.duplicate = {static_cast<int>(f), r.tris[f][k], r.tris[f][(k + 1) % 3]};
      break;
    }
  return a;
}

Region region_from_faces(std::span<const Point2> uv, std::span<const std::array<int, 3>> faces) {
  size_t pos = 0, neg = 0, zero = 0, first_neg = 0, first_pos = 0;
  std::vector<int> sign(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) {
    const auto& t = faces[f];
    const int o = orientation(uv[t[0]], uv[t[1]], uv[t[2]]);
    sign[f] = o;
    if (o > 0) {
      if (pos++ == 0) first_pos = f;
    } else if (o < 0) {
      if (neg++ == 0) first_neg = f;
    } else {
      ++zero;
    }
  }
  if (pos == 0 && neg == 0)
    throw InvalidInput("every face has zero area in the parameter plane (u, v): the parameters are "
                       "degenerate; give each point distinct, non-collinear (u, v)");
  const bool flip = neg > pos;
  const size_t minority = flip ? pos : neg;
  if (minority > 0)
    throw InvalidInput(
        "the parameterization folds over: " + std::to_string(minority) + " of " +
        std::to_string(faces.size()) + " faces are " + (flip ? "counter-clockwise" : "clockwise") +
        " in (u, v) while the others are not (first: face " +
        std::to_string(flip ? first_pos : first_neg) +
        "); the fit needs a bijective parameterization (no flipped triangles)");
  Region r;
  r.tris.reserve(faces.size() - zero);
  for (size_t f = 0; f < faces.size(); ++f) {
    if (sign[f] == 0) continue;
    auto t = faces[f];
    if (flip) std::swap(t[1], t[2]);
    r.tris.push_back(t);
  }
  return r;
}

// The boundary loops of a region (adj: its adjacency), as point indices; throws on
// non-manifold input.
std::vector<std::vector<int>> boundary_loops(const Region& r, const Adjacency& adj, size_t n_points) {
  if (const auto& d = adj.duplicate; d.face >= 0)
    throw InvalidInput("the mesh is not manifold: edge (" + std::to_string(d.a) + ", " + std::to_string(d.b) +
                       ") is used twice in the same direction (face " + std::to_string(d.face) +
                       "); repair the mesh or orient its faces consistently");
  // Every directed edge is used once, so a triangle across an edge runs it the other way.
  std::vector<int> next(n_points, -1);
  std::vector<int> out_count(n_points, 0);
  for (size_t f = 0; f < r.tris.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      if (adj.across[f][k] >= 0) continue;
      const int a = r.tris[f][k], b = r.tris[f][(k + 1) % 3];
      if (++out_count[a] > 1)
        throw InvalidInput("the mesh is not manifold at point " + std::to_string(a) +
                           ": two boundary loops touch there; repair the mesh (split the vertex)");
      next[a] = b;
    }
  std::vector<std::vector<int>> loops;
  std::vector<char> seen(n_points, 0);
  for (size_t s = 0; s < n_points; ++s) {
    if (next[s] < 0 || seen[s]) continue;
    std::vector<int> loop;
    int v = static_cast<int>(s);
    while (!seen[v]) {
      seen[v] = 1;
      loop.push_back(v);
      v = next[v];
      if (v < 0) throw InvalidInput("the mesh boundary is not closed at point " + std::to_string(loop.back()));
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

// Keeps the largest edge-connected component of a region; returns the dropped triangle count.
// `adj` is the region's adjacency, made again for the kept triangles when some are dropped.
size_t keep_largest_component(Region& r, std::span<const Point2> uv, Adjacency& adj, double keep_share) {
  const bool manifold = adj.duplicate.face < 0;
  std::vector<int> comp(r.tris.size(), -1);
  std::vector<double> area;
  for (size_t s = 0; s < r.tris.size(); ++s) {
    if (comp[s] >= 0) continue;
    const int c = static_cast<int>(area.size());
    area.push_back(0);
    std::vector<int> stack{static_cast<int>(s)};
    comp[s] = c;
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      const auto& t = r.tris[f];
      area[c] += signed_area2(uv[t[0]], uv[t[1]], uv[t[2]]);
      // Every triangle sharing an edge, also where more than two do (a face given twice is
      // kept with its copy, and boundary_loops then names it). An edge of three or more
      // triangles runs twice in one direction, so without such a duplicate every edge has at
      // most the one neighbour `across` names: the same triangles in the same order, without
      // a search of the stars.
      for (int k = 0; k < 3; ++k)
        if (manifold) {
          const int g = adj.across[static_cast<size_t>(f)][static_cast<size_t>(k)];
          if (g >= 0 && comp[g] < 0) comp[g] = c, stack.push_back(g);
        } else {
          for (int g : adj.star_of(t[k]))
            if (comp[g] < 0 && has_point(r.tris[g], t[(k + 1) % 3])) comp[g] = c, stack.push_back(g);
        }
    }
  }
  if (area.size() <= 1) return 0;
  const int largest = static_cast<int>(std::max_element(area.begin(), area.end()) - area.begin());
  std::vector<char> keep(area.size(), 0);
  for (size_t c = 0; c < area.size(); ++c) keep[c] = static_cast<int>(c) == largest || area[c] >= keep_share * area[largest];
  if (std::count(keep.begin(), keep.end(), 1) == static_cast<long>(area.size())) return 0;
  // A kept triangle's neighbours are in its component: renumbered, they stay its neighbours
  // (taken over where each edge has at most the one neighbour, searched again otherwise).
  Region kept;
  std::vector<int> renumbered(r.tris.size(), -1);
  for (size_t f = 0; f < r.tris.size(); ++f)
    if (keep[static_cast<size_t>(comp[f])]) renumbered[f] = static_cast<int>(kept.tris.size()), kept.tris.push_back(r.tris[f]);
  std::vector<std::array<int, 3>> across;
  if (manifold)
    for (size_t f = 0; f < r.tris.size(); ++f)
      if (keep[static_cast<size_t>(comp[f])]) {
        std::array<int, 3> g = adj.across[f];
        for (int& q : g)
          if (q >= 0) q = renumbered[static_cast<size_t>(q)];
        across.push_back(g);
      }
  const size_t dropped = r.tris.size() - kept.tris.size();
  r = std::move(kept);
  adj = manifold ? adjacency(r, uv.size(), std::move(across)) : adjacency(r, uv.size());
  return dropped;
}

// Marks as not excluded every point whose (u, v) equals that of a point that is not.
void include_duplicates(std::span<const Point2> uv, std::vector<char>& excluded) {
  // (u, v, index), sorted in parallel: the order within a group of equal (u, v) does not
  // matter, a group is used as a whole.
  struct Entry {
    double u, v;
    int i;
  };
  std::vector<Entry> order(uv.size());
  for (size_t i = 0; i < uv.size(); ++i) order[i] = {uv[i].x(), uv[i].y(), static_cast<int>(i)};
  auto same = [](const Entry& a, const Entry& b) { return a.u == b.u && a.v == b.v; };
  tbb::parallel_sort(order.begin(), order.end(),
                     [](const Entry& a, const Entry& b) { return a.u < b.u || (a.u == b.u && a.v < b.v); });
  for (size_t i = 0; i < order.size();) {
    size_t j = i;
    bool used = false;
    for (; j < order.size() && same(order[j], order[i]); ++j) used |= !excluded[static_cast<size_t>(order[j].i)];
    if (used)
      for (size_t k = i; k < j; ++k) excluded[static_cast<size_t>(order[k].i)] = 0;
    i = j;
  }
}

// Bare parameters: Delaunay triangulation, minus triangles much larger than the local point
// spacing (an alpha shape), so concave outlines and holes of the data are kept (the caller
// then keeps its largest component). `across` receives the kept triangles' neighbours, from the
// triangulation (as Adjacency::across holds them).
Region region_from_points(std::span<const Point2> uv, std::vector<std::array<int, 3>>& across) {
  std::vector<std::pair<CPoint, int>> pts;
  pts.reserve(uv.size());
  for (size_t i = 0; i < uv.size(); ++i) pts.emplace_back(cp(uv[i]), static_cast<int>(i));
  Dt dt;
  dt.insert(pts.begin(), pts.end());
  if (dt.dimension() < 2)
    throw InvalidInput("the parameters (u, v) of all points are collinear or identical; the fit "
                       "needs parameters that span an area");
  // Local spacing: per vertex the shortest incident edge, then the median of that over the
  // vertex and its neighbours (densities vary: parameterizations stretch).
  // Both passes in parallel over the vertices (read-only walks of the triangulation; each
  // vertex writes its own entry).
  std::vector<Dt::Vertex_handle> vertices;
  vertices.reserve(dt.number_of_vertices());
  for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) vertices.push_back(v);
  std::vector<double> nn(uv.size(), 0.0), local(uv.size(), 0.0);
  tbb::parallel_for(size_t{0}, vertices.size(), [&](size_t q) {
    const Dt::Vertex_handle v = vertices[q];
    double best = std::numeric_limits<double>::infinity();
    auto c = dt.incident_vertices(v), done = c;
    do {
      if (!dt.is_infinite(c)) best = std::min(best, std::sqrt(CGAL::squared_distance(v->point(), c->point())));
    } while (++c != done);
    nn[v->info()] = best;
  });
  const double global = [&] {
    std::vector<double> all;
    all.reserve(vertices.size());
    for (const Dt::Vertex_handle& v : vertices) all.push_back(nn[v->info()]);
    std::nth_element(all.begin(), all.begin() + all.size() / 2, all.end());
    return all[all.size() / 2];
  }();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, vertices.size(), 1024), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<double> ring;
    for (size_t q = range.begin(); q != range.end(); ++q) {
      const Dt::Vertex_handle v = vertices[q];
      ring.assign(1, nn[v->info()]);
      auto c = dt.incident_vertices(v), done = c;
      do {
        if (!dt.is_infinite(c)) ring.push_back(nn[c->info()]);
      } while (++c != done);
      std::nth_element(ring.begin(), ring.begin() + ring.size() / 2, ring.end());
      // Never below the global median: a few close pairs must not carve holes.
      local[v->info()] = std::max(global, ring[ring.size() / 2]);
    }
  });
  nn = std::vector<double>();  // what the triangulation holds is the peak: free as we go
  // Random samples leave empty circles a few times the local spacing; only larger gaps are
  // outline or holes: a triangle stays if its circumradius is at most 6 times the largest
  // local spacing at its corners (an alpha shape with a local alpha).
  Region r;
  std::vector<Dt::Face_handle> faces;
  for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f) faces.push_back(f);
  std::vector<char> keep(faces.size());
  tbb::parallel_for(size_t{0}, faces.size(), [&](size_t i) {
    faces[i]->info() = static_cast<int>(i);
    const auto& a = faces[i]->vertex(0)->point();
    const auto& b = faces[i]->vertex(1)->point();
    const auto& c = faces[i]->vertex(2)->point();
    const double la = std::sqrt(CGAL::squared_distance(b, c)), lb = std::sqrt(CGAL::squared_distance(a, c)),
                 lc = std::sqrt(CGAL::squared_distance(a, b));
    const double area2 = std::fabs(CGAL::area(a, b, c)) * 2;
    const double circumradius = area2 > 0 ? la * lb * lc / (2 * area2) : std::numeric_limits<double>::infinity();
    const double alpha = 6.0 * std::max({local[faces[i]->vertex(0)->info()], local[faces[i]->vertex(1)->info()],
                                         local[faces[i]->vertex(2)->info()]});
    // Flat slivers have a large circumradius but short edges: they are not gaps.
    keep[i] = circumradius <= alpha || std::max({la, lb, lc}) <= 0.5 * alpha;
  });
  local = std::vector<double>();
  // Interior gaps smaller than a disc of about 4 spacings are sampling noise, not holes.
  {
    std::vector<int> seen(faces.size(), 0);
    for (size_t i = 0; i < faces.size(); ++i) {
      if (keep[i] || seen[i]) continue;
      std::vector<int> gap{static_cast<int>(i)}, stack{static_cast<int>(i)};
      seen[i] = 1;
      bool outer = false;
      double area = 0;
      while (!stack.empty()) {
        const int f = stack.back();
        stack.pop_back();
        area += std::fabs(CGAL::area(faces[f]->vertex(0)->point(), faces[f]->vertex(1)->point(),
                                     faces[f]->vertex(2)->point()));
        for (int k = 0; k < 3; ++k) {
          auto g = faces[f]->neighbor(k);
          if (dt.is_infinite(g)) {
            outer = true;
            continue;
          }
          const int gi = g->info();
          if (!keep[gi] && !seen[gi]) seen[gi] = 1, gap.push_back(gi), stack.push_back(gi);
        }
      }
      if (!outer && area < 50 * global * global)
        for (int f : gap) keep[f] = 1;
    }
  }
  // Pinch vertices (two kept fans touching at a point) are filled back in until none is left.
  auto pinched = [&](const Dt::Vertex_handle& v) {
    int transitions = 0;
    auto f = dt.incident_faces(v), done = f;
    bool prev = !dt.is_infinite(f) && keep[f->info()];
    do {
      ++f;
      const bool cur = !dt.is_infinite(f) && keep[f->info()];
      if (cur != prev) ++transitions;
      prev = cur;
    } while (f != done);
    return transitions > 2;
  };
  for (int round = 0; round < 20; ++round) {
    // A round changes nothing before its first pinch vertex: that one is found in parallel.
    const size_t first = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, vertices.size(), 4096), vertices.size(),
        [&](const tbb::blocked_range<size_t>& range, size_t best) {
          for (size_t q = range.begin(); q < range.end() && q < best; ++q)
            if (pinched(vertices[q])) return q;
          return best;
        },
        [](size_t a, size_t b) { return std::min(a, b); });
    bool changed = false;
    for (size_t q = first; q < vertices.size(); ++q) {
      if (!pinched(vertices[q])) continue;
      auto g = dt.incident_faces(vertices[q]), gd = g;
      do {
        if (!dt.is_infinite(g) && !keep[g->info()]) keep[g->info()] = 1, changed = true;
      } while (++g != gd);
    }
    if (!changed) break;
  }
  // From here a face's info is its index in the region, -1 if it is not kept.
  for (size_t i = 0; i < faces.size(); ++i) {
    faces[i]->info() = keep[i] ? static_cast<int>(r.tris.size()) : -1;
    if (keep[i])
      r.tris.push_back({faces[i]->vertex(0)->info(), faces[i]->vertex(1)->info(), faces[i]->vertex(2)->info()});
  }
  if (r.tris.empty()) throw InvalidInput("the parameters (u, v) do not span an area");
  // Edge (t[k], t[k + 1]) of a face is the one opposite its vertex k + 2.
  across.assign(r.tris.size(), {-1, -1, -1});
  tbb::parallel_for(size_t{0}, faces.size(), [&](size_t i) {
    const int f = faces[i]->info();
    if (f < 0) return;
    for (int k = 0; k < 3; ++k) {
      const Dt::Face_handle g = faces[i]->neighbor((k + 2) % 3);
      if (!dt.is_infinite(g)) across[static_cast<size_t>(f)][static_cast<size_t>(k)] = g->info();
    }
  });
  return r;
}


// Douglas-Peucker on an open polyline; keeps the ends.
void douglas_peucker(std::span<const Point2> p, size_t i, size_t j, double tol, std::vector<char>& keep) {
  if (j <= i + 1) return;
  double best = -1;
  size_t at = i;
  const Vector2 d = p[j] - p[i];
  const double len = d.norm();
  for (size_t k = i + 1; k < j; ++k) {
    const double dist = len > 0 ? std::fabs(det3(p[i], p[j], p[k])) / len : (p[k] - p[i]).norm();
    if (dist > best) best = dist, at = k;
  }
  if (best > tol) {
    keep[at] = 1;
    douglas_peucker(p, i, at, tol, keep);
    douglas_peucker(p, at, j, tol, keep);
  }
}

// The points of a polyline that Douglas-Peucker keeps at tolerance tol (ends always kept).
std::vector<Point2> simplified(const std::vector<Point2>& line, double tol) {
  std::vector<char> keep(line.size(), 0);
  keep.front() = keep.back() = 1;
  douglas_peucker(line, 0, line.size() - 1, tol, keep);
  std::vector<Point2> out;
  for (size_t q = 0; q < line.size(); ++q)
    if (keep[q]) out.push_back(line[q]);
  return out;
}

// Adds points so that no segment of the polyline is longer than h.
std::vector<Point2> resample(const std::vector<Point2>& poly, double h, bool closed) {
  std::vector<Point2> out;
  const size_t m = poly.size();
  const size_t segs = closed ? m : m - 1;
  for (size_t i = 0; i < segs; ++i) {
    const Point2& a = poly[i];
    const Point2& b = poly[(i + 1) % m];
    out.push_back(a);
    const int pieces = std::max(1, static_cast<int>(std::ceil((b - a).norm() / h - 1e-9)));
    for (int k = 1; k < pieces; ++k) out.push_back(a + (b - a) * (static_cast<double>(k) / pieces));
  }
  if (!closed) out.push_back(poly.back());
  return out;
}

bool segments_cross(const Point2& a, const Point2& b, const Point2& c, const Point2& d) {
  // Proper or touching intersection, excluding shared endpoints.
  if (a == c || a == d || b == c || b == d) {
    // Shared endpoint: overlapping collinear segments still count.
    const Point2& s = (a == c || a == d) ? a : b;
    const Point2& o1 = s == a ? b : a;
    const Point2& o2 = (c == s) ? d : c;
    return orientation(s, o1, o2) == 0 && (o1 - s).dot(o2 - s) > 0;
  }
  return CGAL::do_intersect(K::Segment_2(cp(a), cp(b)), K::Segment_2(cp(c), cp(d)));
}


}  // namespace tbs::detail
