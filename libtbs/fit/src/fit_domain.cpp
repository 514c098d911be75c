// The fit domain (paper section 4.2) and its refinement: the outline of the region the points
// cover (fit_outline.cpp) and the features in it (fit_features.cpp) become the constraints of a
// constrained Delaunay triangulation, meshed to a size that follows the point density, then
// split and kept Delaunay as the fit refines it.

#include "fit_domain.h"

#include "fit_region.h"

#include <tbs/errors.h>
#include <tbs/predicates.h>

#include "box_grid.h"
#include "nesting_levels.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_2.h>
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
#include <cstdio>
#include <map>
#include <unordered_map>
#include <unordered_set>

namespace tbs::detail {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using CPoint = K::Point_2;

// Initial meshing.
using MVb = CGAL::Triangulation_vertex_base_with_info_2<int, K, CGAL::Delaunay_mesh_vertex_base_2<K>>;
using MFb = CGAL::Delaunay_mesh_face_base_2<K>;
using MCdt = CGAL::Constrained_Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<MVb, MFb>>;
using MCriteria = CGAL::Delaunay_mesh_size_criteria_2<MCdt>;

// The working triangulation: vertex info = stable id, face info = inside the domain.
using WVb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using WFb = CGAL::Triangulation_face_base_with_info_2<int, K, CGAL::Constrained_triangulation_face_base_2<K>>;
using WCdt = CGAL::Constrained_Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<WVb, WFb>>;

// Components of the region below this share of the largest's area are specks (outliers of a
// point cloud), not charts of an atlas.
constexpr double kChartShare = 1e-4;
// The least distance, in target edges, from a chart's outline (its seams) to its domain's.
constexpr double kChartMargin = 0.5;

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
  keep_largest_component(region, in.uv, adj, in.charts ? kChartShare : 2.0);
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
  double margin = kChartMargin * h;
  for (int attempt = 0;; ++attempt) {
    if (attempt >= 4) tau = 0;
    // A chart's margin shrinks with the tolerance on each try: offset far, a narrow chart's
    // outline can cross itself.
    if (attempt > 0) margin *= 0.25;
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
        // The charts of an atlas keep a margin of kChartMargin h beyond their seams: the
        // spline is tied there to the other side, and bends toward it within that margin.
        const double least = std::max(2 * m.grid, in.charts ? margin : 0.0);
        off[e] = off[e] > 0 ? std::max(off[e] + 0.05 * tau + 2 * m.grid, least) : least;
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
      if (tau == 0 && !(in.charts && margin > 2 * m.grid))
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
