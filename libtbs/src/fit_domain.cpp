#include "fit_domain.h"

#include <tbs/errors.h>
#include <tbs/predicates.h>

#include "box_grid.h"
#include "nesting_levels.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_2.h>
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <Eigen/Eigenvalues>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <numbers>
#include <numeric>
#include <unordered_map>
#include <unordered_set>

namespace tbs::detail {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using CPoint = K::Point_2;

// Region triangulation of bare parameters.
using DtVb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using DtFb = CGAL::Triangulation_face_base_with_info_2<int, K>;
using Dt = CGAL::Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<DtVb, DtFb>>;

// Initial meshing.
using MVb = CGAL::Triangulation_vertex_base_with_info_2<int, K, CGAL::Delaunay_mesh_vertex_base_2<K>>;
using MFb = CGAL::Delaunay_mesh_face_base_2<K>;
using MCdt = CGAL::Constrained_Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<MVb, MFb>>;
using MCriteria = CGAL::Delaunay_mesh_size_criteria_2<MCdt>;

// The working triangulation: vertex info = stable id, face info = inside the domain.
using WVb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using WFb = CGAL::Triangulation_face_base_with_info_2<int, K, CGAL::Constrained_triangulation_face_base_2<K>>;
using WCdt = CGAL::Constrained_Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<WVb, WFb>>;

CPoint cp(const Point2& p) { return {p.x(), p.y()}; }
Point2 ep(const CPoint& p) { return {p.x(), p.y()}; }

// Mesh size following the parameter density (paper section 4.2: "areas with dense parameter
// points should have more triangles"): the size bound at a point is h * sqrt(mean density /
// local density), clamped to [h / 2, 2 h]; the density is counted on a grid and smoothed.
class SizeField {
 public:
  SizeField(std::span<const Point2> uv, const std::vector<char>& excluded, double h, double area) : h_(h) {
    for (size_t i = 0; i < uv.size(); ++i)
      if (!excluded[i]) box_.extend(uv[i]);
    size_t used = 0;
    for (char e : excluded) used += !e;
    g_ = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(used)) / 4), 4, 256);
    const double w = std::max(box_.max.x() - box_.min.x(), box_.max.y() - box_.min.y());
    cell_ = w / g_ * (1 + 1e-9);
    std::vector<double> count(static_cast<size_t>(g_) * g_, 0.0);
    for (size_t i = 0; i < uv.size(); ++i)
      if (!excluded[i]) count[index(uv[i])] += 1;
    // 3 x 3 box blur, so that cells cut by the outline or a hole do not read as sparse.
    density_.assign(count.size(), 0.0);
    for (int y = 0; y < g_; ++y)
      for (int x = 0; x < g_; ++x) {
        double sum = 0;
        int cells = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= g_ || yy >= g_ || count[yy * g_ + xx] == 0) continue;
            sum += count[yy * g_ + xx];
            ++cells;
          }
        density_[y * g_ + x] = cells > 0 ? sum / cells / (cell_ * cell_) : 0;
      }
    mean_ = static_cast<double>(used) / area;
  }
  double operator()(const Point2& p) const {
    const double d = density_[index(p)];
    if (!(d > 0)) return 2 * h_;
    return h_ * std::clamp(std::sqrt(mean_ / d), 0.5, 2.0);
  }

 private:
  size_t index(const Point2& p) const {
    const int x = std::clamp(static_cast<int>((p.x() - box_.min.x()) / cell_), 0, g_ - 1);
    const int y = std::clamp(static_cast<int>((p.y() - box_.min.y()) / cell_), 0, g_ - 1);
    return static_cast<size_t>(y) * g_ + x;
  }
  double h_;
  Box2 box_;
  int g_ = 1;
  double cell_ = 1, mean_ = 1;
  std::vector<double> density_;
};


// CGAL's size criteria with the size bound taken from a SizeField at each triangle's centroid.
class DensityCriteria : public MCriteria {
 public:
  DensityCriteria(const SizeField* field) : MCriteria(0.125, 1.0), field_(field) {}
  class Is_bad : public MCriteria::Is_bad {
   public:
    Is_bad(const SizeField* field, double aspect, const K& traits)
        : MCriteria::Is_bad(aspect, 1.0, traits), field_(field) {}
    using MCriteria::Is_bad::operator();
    CGAL::Mesh_2::Face_badness operator()(const MCdt::Face_handle& fh, Quality& q) const {
      const CPoint& pa = fh->vertex(0)->point();
      const CPoint& pb = fh->vertex(1)->point();
      const CPoint& pc = fh->vertex(2)->point();
      double l[3] = {CGAL::squared_distance(pb, pc), CGAL::squared_distance(pc, pa),
                     CGAL::squared_distance(pa, pb)};
      std::sort(l, l + 3);
      const Point2 c((pa.x() + pb.x() + pc.x()) / 3, (pa.y() + pb.y() + pc.y()) / 3);
      const double bound = (*field_)(c);
      q.second = l[2] / (bound * bound);
      if (q.size() > 1) {
        q.first = 1;
        return CGAL::Mesh_2::IMPERATIVELY_BAD;
      }
      const double area = 2 * CGAL::area(pa, pb, pc);
      q.first = area * area / (l[2] * l[1]);
      return q.sine() < this->B ? CGAL::Mesh_2::BAD : CGAL::Mesh_2::NOT_BAD;
    }

   private:
    const SizeField* field_;
  };
  Is_bad is_bad_object() const { return Is_bad(field_, this->bound(), this->traits); }

 private:
  const SizeField* field_;
};

uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
}

// A triangulated region of the parameter plane, over input point indices, CCW in uv.
struct Region {
  std::vector<std::array<int, 3>> tris;
};

double signed_area2(const Point2& a, const Point2& b, const Point2& c) { return det3(a, b, c); }

// Triangle neighbours through each point's star (the triangles using it, by index): linear
// in the region's size, and without the hash tables that made a million-point region slow.
struct Adjacency {
  std::vector<int> start, star;  // the star of point v: star[start[v]] .. star[start[v + 1] - 1]
  // across[f][k]: the first other triangle (by index) with both ends of edge (t[k], t[k + 1]);
  // -1 on the outline.
  std::vector<std::array<int, 3>> across;
  // The first triangle (by index) that runs an edge in the same direction as an earlier one
  // (the region is then not manifold), with that edge; face -1 if there is none.
  struct Duplicate {
    int face = -1, a = -1, b = -1;
  } duplicate;

  std::span<const int> star_of(int v) const {
    return {star.data() + start[v], static_cast<size_t>(start[v + 1] - start[v])};
  }
};

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
size_t keep_largest_component(Region& r, std::span<const Point2> uv, Adjacency& adj) {
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
  const int best = static_cast<int>(std::max_element(area.begin(), area.end()) - area.begin());
  // A kept triangle's neighbours are in its component: renumbered, they stay its neighbours
  // (taken over where each edge has at most the one neighbour, searched again otherwise).
  Region kept;
  std::vector<int> renumbered(r.tris.size(), -1);
  for (size_t f = 0; f < r.tris.size(); ++f)
    if (comp[f] == best) renumbered[f] = static_cast<int>(kept.tris.size()), kept.tris.push_back(r.tris[f]);
  std::vector<std::array<int, 3>> across;
  if (manifold)
    for (size_t f = 0; f < r.tris.size(); ++f)
      if (comp[f] == best) {
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

// Sharp edges of the region (dihedral angle of the 3D triangles above the threshold), chained
// into polylines of point indices.
std::vector<std::vector<int>> feature_chains(const Region& r, const Adjacency& adj, std::span<const Point3> pos,
                                             double angle_deg) {
  std::vector<Vector3> fn(r.tris.size());
  for (size_t f = 0; f < r.tris.size(); ++f) {
    const auto& t = r.tris[f];
    const Vector3 n = (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]);
    fn[f] = n.norm() > 0 ? Vector3(n.normalized()) : Vector3::Zero();
  }
  const double cos_limit = std::cos(angle_deg * std::numbers::pi / 180);
  std::map<int, std::vector<int>> nbr;  // ordered: deterministic chaining
  std::vector<std::pair<int, int>> sharp;
  for (size_t f = 0; f < r.tris.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int g = adj.across[f][k];
      if (g < static_cast<int>(f)) continue;  // the outline, or seen from g
      if (fn[f].isZero() || fn[g].isZero()) continue;
      if (fn[f].dot(fn[g]) >= cos_limit) continue;
      const int a = r.tris[f][k], b = r.tris[f][(k + 1) % 3];
      sharp.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(sharp.begin(), sharp.end());
  for (auto [a, b] : sharp) nbr[a].push_back(b), nbr[b].push_back(a);
  for (auto& [v, list] : nbr) std::sort(list.begin(), list.end());
  std::unordered_set<uint64_t> used;
  std::vector<std::vector<int>> chains;
  auto walk = [&](int start, int first) {
    std::vector<int> chain{start};
    int p = start, q = first;
    while (!used.count(edge_key(p, q))) {
      used.insert(edge_key(p, q));
      chain.push_back(q);
      const auto& nq = nbr[q];
      if (nq.size() != 2) break;
      const int nx = nq[0] == p ? nq[1] : nq[0];
      p = q;
      q = nx;
    }
    if (chain.size() >= 2) chains.push_back(std::move(chain));
  };
  for (const auto& [v, list] : nbr)
    if (list.size() != 2)
      for (int w : list) walk(v, w);
  for (const auto& [v, list] : nbr)
    for (int w : list) walk(v, w);  // closed loops
  return chains;
}

// Creases that no edge follows (bare points, or meshes whose edges cross the crease): the
// triangles straddling a crease share its angle between several edges, none of them sharp. A
// band of edges bent by more than a third of the feature angle, long and thin, whose two sides
// have normals more than the feature angle apart, is a crease; its centre line (centroids of
// the band's triangles, averaged in bins along the band's main axis) goes into the domain.
std::vector<std::vector<Point2>> band_creases(const Region& r, const Adjacency& adj, std::span<const Point2> uv,
                                              std::span<const Point3> pos, double angle_deg,
                                              double h, const std::unordered_set<uint64_t>& taken) {
  const size_t F = r.tris.size();
  std::vector<Vector3> fn(F);
  std::vector<Point2> centroid(F);
  tbb::parallel_for(size_t{0}, F, [&](size_t f) {
    const auto& t = r.tris[f];
    const Vector3 nrm = (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]);
    fn[f] = nrm.norm() > 0 ? Vector3(nrm.normalized()) : Vector3::Zero();
    centroid[f] = (uv[t[0]] + uv[t[1]] + uv[t[2]]) / 3.0;
  });
  const double cos_band = std::cos(angle_deg / 3 * std::numbers::pi / 180);
  const double cos_crease = std::cos(angle_deg * std::numbers::pi / 180);
  // Triangles at the region's outline are stretched and tilted (alpha shape): not crease clues.
  std::vector<char> rim(uv.size(), 0);
  for (size_t f = 0; f < F; ++f)
    for (int k = 0; k < 3; ++k)
      if (adj.across[f][k] < 0) rim[r.tris[f][k]] = rim[r.tris[f][(k + 1) % 3]] = 1;
  auto at_rim = [&](int f) {
    for (int v : r.tris[f])
      if (rim[v]) return true;
    return false;
  };
  // Whether the edge k of f, to its neighbour g, bends by more than the band angle.
  auto bent = [&](size_t f, int k, int g) {
    if (taken.count(edge_key(r.tris[f][k], r.tris[f][(k + 1) % 3])) || fn[f].isZero() || fn[g].isZero()) return false;
    if (at_rim(static_cast<int>(f)) || at_rim(g)) return false;
    return fn[f].dot(fn[g]) < cos_band;
  };
  std::vector<char> band(F, 0);
  if (adj.duplicate.face < 0) {
    // Every edge has at most two triangles, each the other's neighbour: each triangle looks at
    // its own edges, in parallel.
    tbb::parallel_for(size_t{0}, F, [&](size_t f) {
      for (int k = 0; k < 3; ++k)
        if (const int g = adj.across[f][k]; g >= 0 && bent(f, k, g)) band[f] = 1;
    });
  } else {
    for (size_t f = 0; f < F; ++f)
      for (int k = 0; k < 3; ++k)
        if (const int g = adj.across[f][k]; g > static_cast<int>(f) && bent(f, k, g)) band[f] = band[g] = 1;
  }
  // Components of band triangles, each listed by index, ordered by their first triangle.
  // Band triangles sharing a vertex are neighbours (a crease passing near a vertex leaves
  // gaps between edge-adjacent ones). Union-find: at a million noisy points most triangles
  // are band triangles.
  std::vector<int> parent(F);
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int f) {
    while (parent[f] != f) f = parent[f] = parent[parent[f]];
    return f;
  };
  for (size_t v = 0; v < uv.size(); ++v) {
    int last = -1;
    for (int f : adj.star_of(static_cast<int>(v))) {
      if (!band[f]) continue;
      if (last >= 0) {
        const int a = root(last), b = root(f);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
      last = f;
    }
  }
  std::vector<int> comp_of(F, -1);
  std::vector<std::vector<int>> comps;
  for (size_t f = 0; f < F; ++f) {
    if (!band[f]) continue;
    int& c = comp_of[root(static_cast<int>(f))];
    if (c < 0) c = static_cast<int>(comps.size()), comps.emplace_back();
    comps[c].push_back(static_cast<int>(f));
  }
  std::vector<std::vector<Point2>> lines;
  for (const auto& c : comps) {
    if (c.size() < 8) continue;
    Point2 mean = Point2::Zero();
    for (int f : c) mean += centroid[f];
    mean /= static_cast<double>(c.size());
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (int f : c) cov += (centroid[f] - mean) * (centroid[f] - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
    const Vector2 axis = es.eigenvectors().col(1), side(-axis.y(), axis.x());
    double tmin = 1e300, tmax = -1e300, wmax = 0;
    for (int f : c) {
      const double t = (centroid[f] - mean).dot(axis);
      tmin = std::min(tmin, t), tmax = std::max(tmax, t);
      wmax = std::max(wmax, std::fabs((centroid[f] - mean).dot(side)));
    }
    const double length = tmax - tmin;
    if (length < 2 * h || 2 * wmax > 0.25 * length) continue;
    // The two sides: non-band triangles next to the band.
    Vector3 nl = Vector3::Zero(), nr = Vector3::Zero();
    size_t cl = 0, cr = 0;
    for (int f : c)
      for (int k = 0; k < 3; ++k) {
        const int g = adj.across[f][k];
        if (g < 0 || band[g]) continue;
        if ((centroid[g] - mean).dot(side) < 0)
          nl += fn[g], ++cl;
        else
          nr += fn[g], ++cr;
      }
    // Both sides must be well represented, and bent against each other by the feature angle.
    const size_t need = std::max<size_t>(3, c.size() / 8);
    if (cl < need || cr < need || nl.normalized().dot(nr.normalized()) >= cos_crease) continue;
    // Centre line: centroids averaged in bins of h / 2 along the axis.
    const int bins = std::max(3, static_cast<int>(std::ceil(length / (0.5 * h))));
    std::vector<Point2> sum(bins, Point2::Zero());
    std::vector<int> count(bins, 0);
    for (int f : c) {
      const double t = (centroid[f] - mean).dot(axis);
      const int b = std::min(bins - 1, static_cast<int>((t - tmin) / length * bins));
      sum[b] += centroid[f];
      ++count[b];
    }
    std::vector<Point2> line;
    for (int b = 0; b < bins; ++b)
      if (count[b] > 0) line.push_back(sum[b] / count[b]);
    if (line.size() >= 2) lines.push_back(std::move(line));
  }
  return lines;
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

}  // namespace

struct FitDomain::Impl {
  DomainStats stats;
  std::vector<char> excluded;
  double grid = 0;
  WCdt cdt;
  std::unordered_set<uint64_t> boundary_edges;  // stable id pairs
  int next_id = 0;
  Domain domain;
  std::vector<int> ids;
  std::vector<WCdt::Vertex_handle> handle_of;  // stable id -> handle

  Point2 snap(const Point2& p) const {
    return {std::round(p.x() / grid) * grid, std::round(p.y() / grid) * grid};
  }

  void mark_domain() {
    const auto level = nesting_levels(cdt, [&](WCdt::Vertex_handle a, WCdt::Vertex_handle b) {
      return boundary_edges.count(edge_key(a->info(), b->info())) > 0;
    });
    for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = level.at(f);
  }

  void rebuild_domain() {
    mark_domain();
    std::vector<std::array<int, 3>> tris;
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
      if (f->info() % 2 != 1) continue;
      std::array<int, 3> t{f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()};
      std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
      tris.push_back(t);
    }
    std::sort(tris.begin(), tris.end());
    std::vector<int> local(next_id, -1);
    for (const auto& t : tris)
      for (int v : t) local[v] = 0;
    ids.clear();
    std::vector<Point2> verts;
    for (int id = 0; id < next_id; ++id)
      if (local[id] == 0) {
        local[id] = static_cast<int>(ids.size());
        ids.push_back(id);
        verts.push_back(ep(handle_of[id]->point()));
      }
    for (auto& t : tris)
      for (int& v : t) v = local[v];
    std::vector<std::array<int, 2>> feats;
    for (auto e = cdt.finite_edges_begin(); e != cdt.finite_edges_end(); ++e) {
      auto [f, k] = *e;
      if (!f->is_constrained(k)) continue;
      auto g = f->neighbor(k);
      if (f->info() % 2 != 1 || cdt.is_infinite(g) || g->info() % 2 != 1) continue;
      const int a = local[f->vertex(WCdt::cw(k))->info()], b = local[f->vertex(WCdt::ccw(k))->info()];
      feats.push_back({std::min(a, b), std::max(a, b)});
    }
    std::sort(feats.begin(), feats.end());
    domain = Domain(std::move(verts), std::move(tris), std::move(feats));
  }

  WCdt::Vertex_handle add_vertex(const Point2& p) {
    const auto count = cdt.number_of_vertices();
    auto v = cdt.insert(cp(p));
    if (cdt.number_of_vertices() != count) {  // a new vertex, whose info() is not set yet
      v->info() = next_id++;
      handle_of.push_back(v);
    }
    return v;
  }
};

FitDomain::FitDomain(const DomainInput& in) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const size_t n = in.uv.size();
  if (n < 3) throw InvalidInput("a fit needs at least 3 points with parameters, got " + std::to_string(n));

  std::vector<std::array<int, 3>> across;
  Region region = in.faces.empty() ? region_from_points(in.uv, across) : region_from_faces(in.uv, in.faces);
  // One adjacency for both (it took a second for each of two builds on 1M bare points); a
  // Delaunay region comes with its neighbours.
  Adjacency adj = in.faces.empty() ? adjacency(region, n, std::move(across)) : adjacency(region, n);
  keep_largest_component(region, in.uv, adj);
  m.excluded.assign(n, 1);
  double area = 0;
  Box2 box;
  for (const auto& t : region.tris) {
    area += 0.5 * signed_area2(in.uv[t[0]], in.uv[t[1]], in.uv[t[2]]);
    for (int v : t) m.excluded[v] = 0, box.extend(in.uv[v]);
  }
  // Bare points at the same (u, v) as a point of the region (duplicates in the scan) share its
  // Delaunay vertex, so no triangle names them: they belong to the region too.
  if (in.faces.empty()) include_duplicates(in.uv, m.excluded);
  const double extent = std::max(box.max.x() - box.min.x(), box.max.y() - box.min.y());
  if (!(area > 0) || !(extent > 0))
    throw InvalidInput("the parameters (u, v) do not span an area");
  // A sliver region (parameters close to a curve) would be meshed with triangles of its width
  // along its whole length: millions of vertices. A 1:1000 strip is 100 times above this.
  if (area < 1e-5 * extent * extent)
  {
    char text[160];
    std::snprintf(text, sizeof text, "the parameters (u, v) span almost no area (%.4g over an extent of %.4g)",
                  area, extent);
    throw InvalidInput(std::string(text) + ": they lie close to a curve; the fit needs parameters that span a region");
  }
  // Vertices on a power-of-two grid: exact midpoints and dyadic fractions keep feature knots
  // exactly collinear (knots.h, default_knots).
  m.grid = std::ldexp(1.0, static_cast<int>(std::ceil(std::log2(extent))) - 24);
  m.stats.grid = m.grid;

  const int target = std::max(2, in.target_triangles);
  const double h = std::sqrt(4 * area / (std::sqrt(3.0) * target));
  m.stats.target_edge = h;

  auto loops = boundary_loops(region, adj, n);
  std::vector<std::vector<int>> chains;
  // Sharp edges only mean something on a given mesh; the Delaunay triangles of bare points
  // straddle creases (found as bands below) and are stretched at the outline.
  if (in.features && !in.faces.empty()) chains = feature_chains(region, adj, in.positions, in.feature_angle_deg);
  // Short chains are noise, not features.
  std::erase_if(chains, [&](const std::vector<int>& c) {
    double len = 0;
    for (size_t i = 0; i + 1 < c.size(); ++i) len += (in.uv[c[i + 1]] - in.uv[c[i]]).norm();
    return c.size() < 3 || len < 2 * h;
  });
  std::vector<char> forced(n, 0);
  for (const auto& c : chains) forced[c.front()] = forced[c.back()] = 1;
  std::vector<std::vector<Point2>> bands;
  if (in.features) {
    std::unordered_set<uint64_t> taken;
    for (const auto& c : chains)
      for (size_t i = 0; i + 1 < c.size(); ++i) taken.insert(edge_key(c[i], c[i + 1]));
    bands = band_creases(region, adj, in.uv, in.positions, in.feature_angle_deg, h, taken);
  }

  // The points the domain must hold, in the order the region's triangles first name them
  // (neighbouring triangles are near each other in the list), then the rest: each check below
  // walks from the face of the point before, a short way. In input order, points scattered
  // over a scan made every walk cross the domain.
  std::vector<size_t> to_check;
  {
    std::vector<char> listed(n, 0);
    for (const auto& t : region.tris)
      for (int v : t)
        if (!listed[static_cast<size_t>(v)]) listed[static_cast<size_t>(v)] = 1, to_check.push_back(static_cast<size_t>(v));
    for (size_t i = 0; i < n; ++i)
      if (!m.excluded[i] && !listed[i]) to_check.push_back(i);
  }

  // Simplify, offset and mesh; retry with a tighter tolerance while a point is left outside.
  double tau = 0.5 * h;
  for (int attempt = 0;; ++attempt) {
    if (attempt >= 4) tau = 0;
    m.stats.boundary_tolerance = tau;
    // Boundary loops as polygons; `moved` holds where forced loop vertices ended up.
    std::unordered_map<int, Point2> moved;
    std::vector<std::vector<Point2>> polys;
    for (const auto& loop : loops) {
      const size_t L = loop.size();
      std::vector<size_t> anchors;
      for (size_t i = 0; i < L; ++i)
        if (forced[loop[i]]) anchors.push_back(i);
      if (anchors.empty()) {
        size_t far = 0;
        for (size_t i = 1; i < L; ++i)
          if ((in.uv[loop[i]] - in.uv[loop[0]]).norm() > (in.uv[loop[far]] - in.uv[loop[0]]).norm()) far = i;
        anchors = {0};
        if (far != 0) anchors.push_back(far);
      }
      // Seam ends: where a closed surface was cut open, the loop runs out along one copy of the
      // seam and back along the other, and at each end of the seam it turns around a vertex
      // whose two loop neighbours are (nearly: within 5 % of the way out and back) the same 3D
      // point. The notch there must stay open: bridged, the domain spans two copies of one
      // curve, and the surface over it has to fold.
      std::vector<char> pinned(L, 0);
      if (!in.positions.empty() && L > 2)
        for (size_t i = 0; i < L; ++i) {
          const Point3& a = in.positions[loop[(i + L - 1) % L]];
          const Point3& b = in.positions[loop[(i + 1) % L]];
          const Point3& v = in.positions[loop[i]];
          const double out_and_back = (a - v).norm() + (b - v).norm();
          if (out_and_back > 0 && (a - b).norm() <= 0.05 * out_and_back) pinned[i] = 1;
        }
      for (size_t i = 0; i < L; ++i)
        if (pinned[i] && std::find(anchors.begin(), anchors.end(), i) == anchors.end()) anchors.push_back(i);
      std::sort(anchors.begin(), anchors.end());
      std::vector<char> keep(L, 0);
      for (size_t a : anchors) keep[a] = 1;
      for (size_t i = 0; i < L; ++i)
        if (pinned[i]) keep[(i + L - 1) % L] = keep[(i + 1) % L] = 1;
      for (size_t k = 0; k < anchors.size(); ++k) {
        const size_t i = anchors[k], j = k + 1 < anchors.size() ? anchors[k + 1] : anchors[0] + L;
        std::vector<Point2> piece;
        for (size_t q = i; q <= j; ++q) piece.push_back(in.uv[loop[q % L]]);
        std::vector<char> pk(piece.size(), 0);
        douglas_peucker(piece, 0, piece.size() - 1, tau, pk);
        for (size_t q = 0; q < piece.size(); ++q)
          if (pk[q]) keep[(i + q) % L] = 1;
      }
      std::vector<int> kept;
      for (size_t i = 0; i < L; ++i)
        if (keep[i]) kept.push_back(static_cast<int>(i));
      if (kept.size() < 3) {
        kept.clear();
        for (int q = 0; q < 3; ++q) kept.push_back(static_cast<int>(q * L / 3));
      }
      // Each kept edge must hold the dropped chain: offset it outward by its chain's largest
      // outward distance, vertices at the mitre points of neighbouring offset lines.
      const size_t K2 = kept.size();
      std::vector<double> off(K2, 0);
      std::vector<Vector2> normal(K2);
      for (size_t e = 0; e < K2; ++e) {
        const size_t i = kept[e], j = e + 1 < K2 ? kept[e + 1] : kept[0] + L;
        const Point2 a = in.uv[loop[i]], b = in.uv[loop[j % L]];
        const Vector2 d = (b - a).normalized();
        normal[e] = Vector2(d.y(), -d.x());  // right of a -> b: outside
        for (size_t q = i + 1; q < j; ++q) off[e] = std::max(off[e], (in.uv[loop[q % L]] - a).dot(normal[e]));
        // Every edge moves out by at least two grid steps, past its own end points too: the
        // snap below moves a vertex by at most 0.71 steps, so every point of the loop stays
        // strictly inside, as the evaluator locates it (hole loops as the outer one).
        off[e] = off[e] > 0 ? off[e] + 0.05 * tau + 2 * m.grid : 2 * m.grid;
      }
      std::vector<Point2> poly;
      for (size_t e = 0; e < K2; ++e) {
        const size_t prev = (e + K2 - 1) % K2;
        const Point2 p = in.uv[loop[kept[e]]];
        const double d1 = off[prev], d2 = off[e];
        Point2 q = p;
        const bool seam_end = pinned[kept[e]];
        if (seam_end || d1 > 0 || d2 > 0) {
          // Along the bisector b of the two outward normals, far enough that both edges move
          // out by at least their offset: n_i . x = max(d1, d2) (n_i . b = cos(half angle)).
          // A seam end moves by the least step only: its edges to its loop neighbours, kept
          // too, drop no point.
          const Vector2 sum = normal[prev] + normal[e];
          const Vector2 b = sum.norm() > 1e-12 ? Vector2(sum.normalized()) : normal[e];
          const double c = std::max(normal[e].dot(b), 0.25);
          q = p + b * (seam_end ? 4 * m.grid : std::max(d1, d2) / c);
        }
        poly.push_back(q);
        if (forced[loop[kept[e]]]) moved[loop[kept[e]]] = q;
      }
      polys.push_back(std::move(poly));
    }

    // Feature polylines, with ends moved with the boundary.
    std::vector<std::vector<Point2>> flines;
    for (const auto& c : chains) {
      std::vector<Point2> raw;
      for (int v : c) raw.push_back(moved.count(v) ? moved[v] : in.uv[v]);
      const bool closed = c.front() == c.back();
      std::vector<Point2> line = simplified(raw, 0.5 * tau);
      if (closed) line.pop_back();
      flines.push_back(resample(line, 1.2 * h, closed));
      if (closed) flines.back().push_back(flines.back().front());
    }
    for (auto& p : polys) p = resample(p, 1.2 * h, true);
    // Band creases: each end that stops within 2 h of the boundary is extended to it, and the
    // boundary gets a vertex there.
    for (const auto& b : bands) {
      std::vector<Point2> line = b;
      for (int end = 0; end < 2; ++end) {
        const Point2 tip = end == 0 ? line.front() : line.back();
        const Point2 prev = end == 0 ? line[1] : line[line.size() - 2];
        const Vector2 dir = (tip - prev).normalized();
        const Point2 far = tip + 2 * h * dir;
        double best = 1e300;
        size_t bl = 0, bi = 0;
        Point2 hit;
        for (size_t l = 0; l < polys.size(); ++l)
          for (size_t i = 0; i < polys[l].size(); ++i) {
            const Point2& a = polys[l][i];
            const Point2& c = polys[l][(i + 1) % polys[l].size()];
            const double d1 = det3(a, c, tip), d2 = det3(a, c, far);
            const double e1 = det3(tip, far, a), e2 = det3(tip, far, c);
            if ((d1 > 0) == (d2 > 0) || (e1 > 0) == (e2 > 0)) continue;
            const double s = d1 / (d1 - d2);
            if (s < best) best = s, bl = l, bi = i, hit = tip + s * (far - tip);
          }
        if (best > 1) continue;
        polys[bl].insert(polys[bl].begin() + static_cast<long>(bi) + 1, hit);
        if (end == 0)
          line.insert(line.begin(), hit);
        else
          line.push_back(hit);
      }
      flines.push_back(resample(simplified(line, 0.1 * h), 1.2 * h, false));
    }
    for (auto& p : polys)
      for (auto& q : p) q = m.snap(q);
    for (auto& l : flines)
      for (auto& q : l) q = m.snap(q);

    // Boundary segments must not cross; feature segments that cross the boundary or each other
    // are dropped.
    std::vector<std::array<Point2, 2>> bsegs;
    std::vector<Box2> bbox;
    for (const auto& p : polys)
      for (size_t i = 0; i < p.size(); ++i) {
        bsegs.push_back({p[i], p[(i + 1) % p.size()]});
        Box2 b;
        b.extend(p[i]);
        b.extend(p[(i + 1) % p.size()]);
        bbox.push_back(b);
      }
    detail::BoxGrid bgrid;
    bgrid.build(bbox, bbox.size());
    bool simple = true;
    for (size_t i = 0; i < bsegs.size() && simple; ++i)
      bgrid.query(bbox[i], [&](int j) {
        if (static_cast<size_t>(j) <= i || !simple) return;
        if (segments_cross(bsegs[i][0], bsegs[i][1], bsegs[j][0], bsegs[j][1])) simple = false;
      });
    if (!simple) {
      if (tau == 0)
        throw InvalidInput("the boundary of the parameter region crosses itself; the parameterization "
                           "is not bijective");
      tau *= 0.25;
      continue;
    }
    std::vector<std::array<Point2, 2>> fsegs;
    for (const auto& l : flines)
      for (size_t i = 0; i + 1 < l.size(); ++i) {
        if (l[i] == l[i + 1]) continue;
        Box2 b;
        b.extend(l[i]);
        b.extend(l[i + 1]);
        bool bad = false;
        bgrid.query(b, [&](int j) {
          if (!bad && segments_cross(l[i], l[i + 1], bsegs[j][0], bsegs[j][1])) {
            // Touching the boundary at the feature's own end is fine.
            const bool end_on_boundary = (l[i] == bsegs[j][0] || l[i] == bsegs[j][1] ||
                                          l[i + 1] == bsegs[j][0] || l[i + 1] == bsegs[j][1]);
            if (!end_on_boundary) bad = true;
          }
        });
        for (const auto& s : fsegs)
          if (!bad && segments_cross(l[i], l[i + 1], s[0], s[1])) bad = true;
        if (!bad) fsegs.push_back({l[i], l[i + 1]});
      }

    // Constrained Delaunay triangulation and refinement to the target size.
    MCdt mcdt;
    std::vector<CPoint> seeds;
    for (const auto& p : polys) {
      std::vector<MCdt::Vertex_handle> vh;
      for (const auto& q : p) vh.push_back(mcdt.insert(cp(q)));
      for (size_t i = 0; i < vh.size(); ++i)
        if (vh[i] != vh[(i + 1) % vh.size()]) mcdt.insert_constraint(vh[i], vh[(i + 1) % vh.size()]);
    }
    for (const auto& s : fsegs) mcdt.insert_constraint(cp(s[0]), cp(s[1]));
    // Seeds: a point inside each hole (the loops after the outer one wind clockwise).
    {
      // Mark nesting levels on boundary constraints only to find faces inside holes.
      std::unordered_set<uint64_t> bset;
      std::map<std::pair<double, double>, int> vid;
      for (auto v = mcdt.finite_vertices_begin(); v != mcdt.finite_vertices_end(); ++v)
        v->info() = static_cast<int>(vid.size()), vid[{v->point().x(), v->point().y()}] = v->info();
      for (const auto& s : bsegs) {
        auto a = vid.find({s[0].x(), s[0].y()}), b = vid.find({s[1].x(), s[1].y()});
        if (a != vid.end() && b != vid.end()) bset.insert(edge_key(a->second, b->second));
      }
      auto level = nesting_levels(mcdt, [&](MCdt::Vertex_handle a, MCdt::Vertex_handle b) {
        return bset.count(edge_key(a->info(), b->info())) > 0;
      });
      for (auto f = mcdt.finite_faces_begin(); f != mcdt.finite_faces_end(); ++f)
        if (level[f] > 0 && level[f] % 2 == 0)
          seeds.push_back(CGAL::centroid(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point()));
    }
    const SizeField field(in.uv, m.excluded, 1.4 * h, area);
    CGAL::refine_Delaunay_mesh_2(mcdt, seeds.begin(), seeds.end(), DensityCriteria(&field));

    // The working triangulation from snapped vertices.
    m.cdt.clear();
    m.boundary_edges.clear();
    m.handle_of.clear();
    m.next_id = 0;
    std::unordered_map<MCdt::Vertex_handle, WCdt::Vertex_handle> map;
    // Insert in a fixed order: by snapped coordinates.
    std::vector<std::pair<Point2, MCdt::Vertex_handle>> order;
    for (auto v = mcdt.finite_vertices_begin(); v != mcdt.finite_vertices_end(); ++v)
      order.emplace_back(m.snap(ep(v->point())), v);
    std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) {
      return a.first.x() != b.first.x() ? a.first.x() < b.first.x() : a.first.y() < b.first.y();
    });
    for (auto& [p, v] : order) map[v] = m.add_vertex(p);
    for (auto e = mcdt.finite_edges_begin(); e != mcdt.finite_edges_end(); ++e) {
      auto [f, k] = *e;
      if (!f->is_constrained(k)) continue;
      auto g = f->neighbor(k);
      const bool fin = !mcdt.is_infinite(f) && f->is_in_domain();
      const bool gin = !mcdt.is_infinite(g) && g->is_in_domain();
      if (!fin && !gin) continue;
      auto a = map[f->vertex(MCdt::cw(k))], b = map[f->vertex(MCdt::ccw(k))];
      if (a == b) continue;
      m.cdt.insert_constraint(a, b);
      if (fin != gin) m.boundary_edges.insert(edge_key(a->info(), b->info()));
    }
    m.rebuild_domain();

    // Every parameter point of the region must be in the domain (closed: on its boundary counts),
    // which is where the evaluator locates points. Past the fourth try (tau = 0) a point still
    // outside is left to the fit, which leaves it out and counts it (points_excluded).
    size_t outside = 0;
    WCdt::Face_handle hint;
    for (size_t q = 0; q < to_check.size() && (outside == 0 || tau > 0); ++q) {
      const size_t i = to_check[q];
      WCdt::Locate_type lt;
      int li;
      auto f = m.cdt.locate(cp(in.uv[i]), lt, li, hint);
      hint = f;
      bool in_domain = !m.cdt.is_infinite(f) && f->info() % 2 == 1;
      if (!in_domain && (lt == WCdt::EDGE || lt == WCdt::VERTEX)) {
        // On a boundary edge or vertex: inside in the closed sense.
        if (lt == WCdt::EDGE) {
          auto g = f->neighbor(li);
          in_domain = !m.cdt.is_infinite(g) && g->info() % 2 == 1;
        } else {
          auto c = m.cdt.incident_faces(f->vertex(li)), done = c;
          do {
            if (!m.cdt.is_infinite(c) && c->info() % 2 == 1) in_domain = true;
          } while (++c != done);
        }
      }
      if (!in_domain) ++outside;
    }
    if (outside > 0 && tau > 0) {
      tau *= 0.25;
      continue;
    }
    m.stats.holes = static_cast<int>(m.domain.boundary_loops().size()) - 1;
    m.stats.feature_chains = static_cast<int>(chains.size() + bands.size());
    break;
  }
}

FitDomain::~FitDomain() = default;
const Domain& FitDomain::domain() const { return impl_->domain; }
const std::vector<int>& FitDomain::ids() const { return impl_->ids; }
const DomainStats& FitDomain::stats() const { return impl_->stats; }
const std::vector<char>& FitDomain::excluded() const { return impl_->excluded; }
Point2 FitDomain::snap(const Point2& p) const { return impl_->snap(p); }

void FitDomain::move_vertex(int id, const Point2& p) {
  Impl& m = *impl_;
  auto v = m.handle_of.at(id);
  if (ep(v->point()) == p) return;
  const auto it = std::lower_bound(m.ids.begin(), m.ids.end(), id);
  if (it != m.ids.end() && *it == id) m.domain.move_vertex(static_cast<int>(it - m.ids.begin()), p);
  m.cdt.remove(v);
  auto w = m.cdt.insert(cp(p));
  w->info() = id;
  m.handle_of[id] = w;
}

void FitDomain::split(std::span<const int> triangles) {
  // Longest-edge bisection: each triangle gets a vertex at the midpoint of its longest edge
  // (centroids would leave long boundary edges alone and make slivers along them). Midpoints
  // of boundary and feature edges are exact (no snap), so those lines stay straight.
  Impl& m = *impl_;
  const Domain& d = m.domain;
  std::vector<int> edges;
  for (int t : triangles) {
    int best = -1;
    double len = -1;
    for (int k = 0; k < 3; ++k) {
      const int e = d.triangle_edge(t, k);
      const auto& ev = d.edges()[e];
      const double l = (d.vertex(ev[0]) - d.vertex(ev[1])).squaredNorm();
      if (l > len) len = l, best = e;
    }
    edges.push_back(best);
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  std::vector<std::pair<int, int>> boundary_splits;  // stable ids of split boundary edges
  std::vector<Point2> points;
  for (int e : edges) {
    const auto& ev = d.edges()[e];
    const Point2 mid = 0.5 * (d.vertex(ev[0]) + d.vertex(ev[1]));
    const bool constrained = d.is_boundary_edge(e) || d.is_feature_edge(e);
    points.push_back(constrained ? mid : m.snap(mid));
    boundary_splits.emplace_back(d.is_boundary_edge(e) ? m.ids[ev[0]] : -1, m.ids[ev[1]]);
  }
  for (size_t q = 0; q < points.size(); ++q) {
    const int before = m.next_id;
    auto v = m.add_vertex(points[q]);
    if (m.next_id == before) continue;  // an existing vertex
    const auto [a, b] = boundary_splits[q];
    if (a >= 0 && m.boundary_edges.erase(edge_key(a, b))) {
      m.boundary_edges.insert(edge_key(a, v->info()));
      m.boundary_edges.insert(edge_key(v->info(), b));
    }
  }
  m.rebuild_domain();
}

}  // namespace tbs::detail
