// tbs::Domain (domain.h): a planar triangulation checked for validity, with its edges,
// boundary loops, holes and feature edges.

#include <tbs/domain.h>
#include <tbs/errors.h>
#include <tbs/predicates.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <unordered_map>

namespace tbs {
namespace {

std::string pt(const Point2& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.17g, %.17g)", p.x(), p.y());
  return buf;
}

std::string tri_str(int t, const std::array<int, 3>& v) {
  return "triangle " + std::to_string(t) + " (vertices " + std::to_string(v[0]) + " " +
         std::to_string(v[1]) + " " + std::to_string(v[2]) + ")";
}

bool on_segment_collinear(const Point2& p, const Point2& q, const Point2& r) {
  // r is collinear with pq; is it within the closed segment?
  return std::min(p.x(), q.x()) <= r.x() && r.x() <= std::max(p.x(), q.x()) &&
         std::min(p.y(), q.y()) <= r.y() && r.y() <= std::max(p.y(), q.y());
}

bool segments_intersect(const Point2& p1, const Point2& q1, const Point2& p2, const Point2& q2) {
  const int o1 = orientation(p1, q1, p2);
  const int o2 = orientation(p1, q1, q2);
  const int o3 = orientation(p2, q2, p1);
  const int o4 = orientation(p2, q2, q1);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  if (o1 == 0 && on_segment_collinear(p1, q1, p2)) return true;
  if (o2 == 0 && on_segment_collinear(p1, q1, q2)) return true;
  if (o3 == 0 && on_segment_collinear(p2, q2, p1)) return true;
  if (o4 == 0 && on_segment_collinear(p2, q2, q1)) return true;
  return false;
}

}  // namespace

Domain::Domain(std::vector<Point2> vertices, std::vector<std::array<int, 3>> triangles,
               std::vector<std::array<int, 2>> feature_edges)
    : vertices_(std::move(vertices)), triangles_(std::move(triangles)) {
  build_topology();
  check_boundary_simple();

  is_feature_edge_.assign(edges_.size(), 0);
  for (size_t k = 0; k < feature_edges.size(); ++k) {
    auto [a, b] = feature_edges[k];
    const std::string where = "feature edge " + std::to_string(k) + " (" + std::to_string(a) +
                              ", " + std::to_string(b) + ")";
    if (a < 0 || b < 0 || a >= vertex_count() || b >= vertex_count())
      throw InvalidInput(where + ": vertex index out of range [0, " +
                         std::to_string(vertex_count()) + ")");
    const int e = find_edge(a, b);
    if (e < 0) throw InvalidInput(where + ": not an edge of the domain triangulation");
    if (is_boundary_edge(e))
      throw InvalidInput(where + ": lies on the domain boundary; feature edges must be interior "
                                 "edges (the boundary needs no feature)");
    is_feature_edge_[e] = 1;
  }
  for (int e = 0; e < edge_count(); ++e)
    if (is_feature_edge_[e]) feature_edges_.push_back(edges_[e]);
}

void Domain::build_topology() {
  const int nv = vertex_count();
  const int nt = triangle_count();
  if (nt == 0) throw InvalidInput("the domain has no triangles");
  for (int i = 0; i < nv; ++i)
    if (!vertices_[i].allFinite())
      throw InvalidInput("vertex " + std::to_string(i) + " has a non-finite coordinate");
  for (int t = 0; t < nt; ++t) {
    const auto& v = triangles_[t];
    for (int k = 0; k < 3; ++k)
      if (v[k] < 0 || v[k] >= nv)
        throw InvalidInput(tri_str(t, v) + ": vertex index out of range [0, " +
                           std::to_string(nv) + ")");
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
      throw InvalidInput(tri_str(t, v) + ": repeats a vertex");
    const int o = orientation(vertices_[v[0]], vertices_[v[1]], vertices_[v[2]]);
    if (o == 0) throw InvalidInput(tri_str(t, v) + " is degenerate (zero area)");
    if (o < 0)
      throw InvalidInput(tri_str(t, v) +
                         " is clockwise; triangles must be counter-clockwise in the (u, v) plane");
  }

  // Half-edges sorted by undirected key give the edge numbering.
  struct Half {
    int lo, hi, t, k;  // edge opposite corner k of triangle t
    bool forward;      // triangle traverses lo -> hi
  };
  std::vector<Half> halves;
  halves.reserve(3 * static_cast<size_t>(nt));
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles_[t][(k + 1) % 3], b = triangles_[t][(k + 2) % 3];
      halves.push_back({std::min(a, b), std::max(a, b), t, k, a < b});
    }
  std::sort(halves.begin(), halves.end(), [](const Half& x, const Half& y) {
    return std::tie(x.lo, x.hi, x.t, x.k) < std::tie(y.lo, y.hi, y.t, y.k);
  });
  triangle_edges_.assign(3 * static_cast<size_t>(nt), -1);
  for (size_t i = 0; i < halves.size();) {
    size_t j = i;
    while (j < halves.size() && halves[j].lo == halves[i].lo && halves[j].hi == halves[i].hi) ++j;
    const std::string where =
        "edge (" + std::to_string(halves[i].lo) + ", " + std::to_string(halves[i].hi) + ")";
    if (j - i > 2) {
      std::string list;
      for (size_t m = i; m < j; ++m) list += (m > i ? ", " : "") + std::to_string(halves[m].t);
      throw InvalidInput(where + " is shared by " + std::to_string(j - i) + " triangles (" + list +
                         "); the domain must be a manifold triangulation");
    }
    if (j - i == 2 && halves[i].forward == halves[i + 1].forward)
      throw InvalidInput(where + " is traversed in the same direction by triangles " +
                         std::to_string(halves[i].t) + " and " + std::to_string(halves[i + 1].t) +
                         ": they overlap");
    const int e = static_cast<int>(edges_.size());
    edges_.push_back({halves[i].lo, halves[i].hi});
    edge_triangles_.push_back({halves[i].t, j - i == 2 ? halves[i + 1].t : -1});
    for (size_t m = i; m < j; ++m) triangle_edges_[3 * halves[m].t + halves[m].k] = e;
    i = j;
  }

  // Vertex -> triangles (CSR).
  vertex_triangle_start_.assign(nv + 1, 0);
  for (const auto& tri : triangles_)
    for (int v : tri) ++vertex_triangle_start_[v + 1];
  for (int i = 0; i < nv; ++i) {
    if (vertex_triangle_start_[i + 1] == 0)
      throw InvalidInput("vertex " + std::to_string(i) + " " + pt(vertices_[i]) +
                         " is not used by any triangle");
    vertex_triangle_start_[i + 1] += vertex_triangle_start_[i];
  }
  vertex_triangles_.assign(vertex_triangle_start_[nv], -1);
  {
    std::vector<int> fill(vertex_triangle_start_.begin(), vertex_triangle_start_.end() - 1);
    for (int t = 0; t < nt; ++t)
      for (int v : triangles_[t]) vertex_triangles_[fill[v]++] = t;
  }

  // Boundary: each boundary edge directed as its triangle traverses it (domain on the left).
  boundary_next_.assign(nv, -1);
  boundary_prev_.assign(nv, -1);
  for (int e = 0; e < edge_count(); ++e) {
    if (edge_triangles_[e][1] >= 0) continue;
    const int t = edge_triangles_[e][0];
    int a = -1, b = -1;
    for (int k = 0; k < 3; ++k)
      if (triangle_edges_[3 * t + k] == e) {
        a = triangles_[t][(k + 1) % 3];
        b = triangles_[t][(k + 2) % 3];
      }
    if (boundary_next_[a] >= 0 || boundary_prev_[b] >= 0) {
      const int v = boundary_next_[a] >= 0 ? a : b;
      throw InvalidInput("vertex " + std::to_string(v) + " " + pt(vertices_[v]) +
                         " is a pinch point (the domain boundary passes through it twice); "
                         "split the domain there or remove a triangle");
    }
    boundary_next_[a] = b;
    boundary_prev_[b] = a;
  }

  // Each vertex must have a single fan of triangles.
  for (int v = 0; v < nv; ++v) {
    auto tris = vertex_triangles(v);
    // Walk around v: in triangle (v, x, y) counter-clockwise, the next triangle shares (v, y).
    auto corner_next = [&](int t) {
      const auto& tri = triangles_[t];
      const int k = tri[0] == v ? 0 : (tri[1] == v ? 1 : 2);
      return std::pair{tri[(k + 1) % 3], tri[(k + 2) % 3]};
    };
    int start = tris[0];
    if (boundary_next_[v] >= 0) {
      // Start at the triangle holding the boundary edge v -> next.
      for (int t : tris)
        if (corner_next(t).first == boundary_next_[v]) start = t;
    }
    size_t visited = 0;
    int t = start;
    do {
      ++visited;
      const int y = corner_next(t).second;
      const int e = find_edge(v, y);
      const auto et = edge_triangles_[e];
      const int nt2 = et[0] == t ? et[1] : et[0];
      t = nt2;
    } while (t >= 0 && t != start && visited <= tris.size());
    if (visited != tris.size())
      throw InvalidInput("vertex " + std::to_string(v) + " " + pt(vertices_[v]) +
                         " is non-manifold: its triangles do not form a single fan");
  }

  // Boundary loops in order of their smallest... first vertex met in index order.
  std::vector<char> seen(nv, 0);
  for (int v = 0; v < nv; ++v) {
    if (boundary_next_[v] < 0 || seen[v]) continue;
    std::vector<int> loop;
    int w = v;
    do {
      seen[w] = 1;
      loop.push_back(w);
      w = boundary_next_[w];
    } while (w != v);
    boundary_loops_.push_back(std::move(loop));
  }
}

int Domain::find_edge(int a, int b) const {
  const std::array<int, 2> key{std::min(a, b), std::max(a, b)};
  auto it = std::lower_bound(edges_.begin(), edges_.end(), key);
  if (it == edges_.end() || *it != key) return -1;
  return static_cast<int>(it - edges_.begin());
}

void Domain::check_boundary_simple() const {
  struct Seg {
    int a, b;
  };
  std::vector<Seg> segs;
  for (const auto& loop : boundary_loops_)
    for (size_t i = 0; i < loop.size(); ++i) segs.push_back({loop[i], loop[(i + 1) % loop.size()]});
  if (segs.empty()) return;

  // Consecutive segments must not fold back onto each other.
  for (const auto& loop : boundary_loops_)
    for (size_t i = 0; i < loop.size(); ++i) {
      const Point2& a = vertices_[loop[i]];
      const Point2& b = vertices_[loop[(i + 1) % loop.size()]];
      const Point2& c = vertices_[loop[(i + 2) % loop.size()]];
      if (orientation(a, b, c) == 0 && (c - b).dot(a - b) > 0)
        throw InvalidInput("the domain boundary folds back on itself at vertex " +
                           std::to_string(loop[(i + 1) % loop.size()]) + " " + pt(b));
    }

  // Uniform grid over the boundary's bounding box.
  Box2 box;
  double total = 0;
  for (const auto& s : segs) {
    box.extend(vertices_[s.a]);
    box.extend(vertices_[s.b]);
    total += (vertices_[s.b] - vertices_[s.a]).norm();
  }
  const double cell = std::max(total / static_cast<double>(segs.size()), 1e-300);
  const Point2 ext = box.max - box.min;
  const int nx = std::clamp(static_cast<int>(ext.x() / cell) + 1, 1, 2048);
  const int ny = std::clamp(static_cast<int>(ext.y() / cell) + 1, 1, 2048);
  const double sx = nx / std::max(ext.x(), 1e-300), sy = ny / std::max(ext.y(), 1e-300);
  auto cx = [&](double x) { return std::clamp(static_cast<int>((x - box.min.x()) * sx), 0, nx - 1); };
  auto cy = [&](double y) { return std::clamp(static_cast<int>((y - box.min.y()) * sy), 0, ny - 1); };
  std::vector<std::vector<int>> cells(static_cast<size_t>(nx) * ny);
  for (int i = 0; i < static_cast<int>(segs.size()); ++i) {
    const Point2& p = vertices_[segs[i].a];
    const Point2& q = vertices_[segs[i].b];
    for (int x = cx(std::min(p.x(), q.x())); x <= cx(std::max(p.x(), q.x())); ++x)
      for (int y = cy(std::min(p.y(), q.y())); y <= cy(std::max(p.y(), q.y())); ++y)
        cells[static_cast<size_t>(y) * nx + x].push_back(i);
  }
  for (const auto& c : cells)
    for (size_t i = 0; i < c.size(); ++i)
      for (size_t j = i + 1; j < c.size(); ++j) {
        const Seg& s = segs[c[i]];
        const Seg& r = segs[c[j]];
        if (s.a == r.a || s.a == r.b || s.b == r.a || s.b == r.b) continue;  // adjacent
        if (segments_intersect(vertices_[s.a], vertices_[s.b], vertices_[r.a], vertices_[r.b]))
          throw InvalidInput("the domain boundary intersects itself: boundary edges (" +
                             std::to_string(s.a) + ", " + std::to_string(s.b) + ") and (" +
                             std::to_string(r.a) + ", " + std::to_string(r.b) +
                             ") cross or touch, so triangles overlap");
      }
}

Box2 Domain::bounding_box() const {
  Box2 b;
  for (const auto& p : vertices_) b.extend(p);
  return b;
}

void Domain::move_vertex(int v, const Point2& p) {
  if (!p.allFinite()) throw InvalidInput("vertex " + std::to_string(v) + ": non-finite position");
  const Point2 old = vertices_[v];
  vertices_[v] = p;
  for (int t : vertex_triangles(v)) {
    const auto& tri = triangles_[t];
    if (orientation(vertices_[tri[0]], vertices_[tri[1]], vertices_[tri[2]]) <= 0) {
      vertices_[v] = old;
      throw InvalidInput("moving vertex " + std::to_string(v) + " to " + pt(p) + " flips " +
                         tri_str(t, tri));
    }
  }
}

}  // namespace tbs
