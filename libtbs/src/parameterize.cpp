// Parameters for raw scans: mesh repair (CGAL Polygon_mesh_processing), topology, a seam cut
// for closed surfaces, LSCM (our sparse solve, which takes holes as they are), the mean-value
// fallback (CGAL Surface_mesh_parameterization) and advancing-front reconstruction for point
// clouds.

#include <tbs/errors.h>
#include <tbs/parameterize.h>

#include "nesting_levels.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Eigen_solver_traits.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_mesh_to_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/Surface_mesh_parameterization/Circular_border_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/Mean_value_coordinates_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>
#include <CGAL/box_intersection_d.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Geometry>
#include <Eigen/Sparse>
#include <Eigen/SparseLU>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <queue>
#include <unordered_map>

// CGAL's advancing-front reconstruction, made to depend on the points alone. Two things in it
// followed memory addresses, so the same points meshed differently from one process layout to
// the next (the command against Python, or a second call in one process):
// - its border edges wait in a std::set ordered by (priority, pointer), and equal priorities
//   are common (the same candidate facet for two edges, the fixed marks for edges put off);
// - its clean-up removes vertices from the Delaunay triangulation, whose re-triangulation
//   orders and hashes vertex and cell handles by address.
// Here the handles carry time stamps (CGAL's Compact_container then compares and hashes them
// by creation order, as Mesh_3 does for the same reason) and equal priorities go by the
// indices of the edge's two points, which identify a border edge for as long as it waits.
namespace tbs::afsr {

template <typename Base>
struct Stamped : Base {
  using Base::Base;
  template <typename Tds2>
  struct Rebind_TDS {
    using Other = Stamped<typename Base::template Rebind_TDS<Tds2>::Other>;
  };
  using Has_timestamp = CGAL::Tag_true;
  std::size_t time_stamp() const { return stamp; }
  void set_time_stamp(const std::size_t& s) { stamp = s; }
  std::size_t stamp = std::size_t(-1);
};

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Tds = CGAL::Triangulation_data_structure_3<
    Stamped<CGAL::Advancing_front_surface_reconstruction_vertex_base_3<Kernel>>,
    Stamped<CGAL::Advancing_front_surface_reconstruction_cell_base_3<Kernel>>>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, Tds>;
using Vertex = Delaunay::Vertex;
using WaitingEdge = Vertex::Radius_ptr_type;  // (priority, the border edge's facets)
static_assert(CGAL::internal::Has_timestamp<Vertex>::value && CGAL::internal::Has_timestamp<Delaunay::Cell>::value);

}  // namespace tbs::afsr

// Must be seen before Advancing_front_surface_reconstruction<afsr::Delaunay> instantiates its set.
template <>
struct std::less<tbs::afsr::WaitingEdge> {
  static std::pair<std::size_t, std::size_t> ends(const tbs::afsr::Vertex::IO_edge_type* e) {
    const auto& edge = e->first.first;  // (cell, i, j): the edge from vertex i to vertex j
    const std::size_t a = edge.first->vertex(edge.second)->info(), b = edge.first->vertex(edge.third)->info();
    return a < b ? std::make_pair(a, b) : std::make_pair(b, a);
  }
  bool operator()(const tbs::afsr::WaitingEdge& x, const tbs::afsr::WaitingEdge& y) const {
    if (x.first != y.first) return x.first < y.first;
    if (x.second == y.second) return false;
    const auto ex = ends(x.second), ey = ends(y.second);
    return ex != ey ? ex < ey : x.second < y.second;  // one entry per border edge: the last never decides
  }
};

namespace tbs {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P3 = K::Point_3;
using P2 = K::Point_2;
using SM = CGAL::Surface_mesh<P3>;
using Tri = std::array<int, 3>;
using HoleVb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using HoleFb = CGAL::Constrained_triangulation_face_base_2<K>;
using HoleCdt = CGAL::Constrained_Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<HoleVb, HoleFb>>;
namespace PMP = CGAL::Polygon_mesh_processing;
namespace SMP = CGAL::Surface_mesh_parameterization;

// A number for a message, in 4 significant digits.
std::string short_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

std::string plural(size_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

uint64_t edge_key(int a, int b) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(std::min(a, b))) << 32) | static_cast<uint32_t>(std::max(a, b));
}
uint64_t directed_key(int a, int b) { return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b); }

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(int a, int b) { parent[find(a)] = find(b); }
};

// A triangle soup with int indices.
struct Mesh3 {
  std::vector<Point3> points;
  std::vector<Tri> faces;
};

// Boundary loops of an oriented manifold mesh as vertex cycles (a boundary halfedge a->b has
// no opposite b->a).
std::vector<std::vector<int>> boundary_loops(const std::vector<Tri>& faces) {
  std::unordered_map<uint64_t, int> directed;
  for (const Tri& t : faces)
    for (int k = 0; k < 3; ++k) directed[directed_key(t[k], t[(k + 1) % 3])] = 1;
  std::unordered_map<int, int> next;  // boundary halfedge a->b, keyed by a
  for (const Tri& t : faces)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      if (!directed.count(directed_key(b, a))) next[b] = a;  // the boundary runs b->a
    }
  std::vector<std::vector<int>> loops;
  std::vector<int> starts;
  for (const auto& [a, b] : next) starts.push_back(a);
  std::sort(starts.begin(), starts.end());
  std::unordered_map<int, char> seen;
  for (int s : starts) {
    if (seen[s]) continue;
    std::vector<int> loop;
    int v = s;
    while (!seen[v]) {
      seen[v] = 1;
      loop.push_back(v);
      auto it = next.find(v);
      if (it == next.end()) break;
      v = it->second;
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

// ---- Repair --------------------------------------------------------------------------------

// Merges duplicate vertices, drops degenerate and duplicate faces and unused vertices, orients
// the faces consistently (splitting non-manifold vertices), and removes zero-area faces by
// edge collapses and flips, all with CGAL's Polygon_mesh_processing.
Mesh3 repair(const std::vector<Point3>& positions, const std::vector<Tri>& triangles, ParameterizeReport& rep) {
  std::vector<P3> pts;
  pts.reserve(positions.size());
  for (const Point3& p : positions) pts.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::vector<size_t>> polys;
  polys.reserve(triangles.size());
  std::vector<char> used(positions.size(), 0);
  for (const Tri& t : triangles) {
    polys.push_back({size_t(t[0]), size_t(t[1]), size_t(t[2])});
    for (int v : t) used[v] = 1;
  }
  rep.isolated_points = static_cast<size_t>(std::count(used.begin(), used.end(), 0));
  const size_t faces_in = polys.size(), points_used = positions.size() - rep.isolated_points;
  PMP::repair_polygon_soup(pts, polys);
  rep.vertices_merged = points_used > pts.size() ? points_used - pts.size() : 0;
  rep.faces_removed = faces_in - polys.size();

  // Orientation: remember each face's corners to tell which were flipped.
  std::vector<std::array<P3, 3>> before;
  for (const auto& p : polys)
    if (p.size() == 3) before.push_back({pts[p[0]], pts[p[1]], pts[p[2]]});
  const size_t points_before = pts.size();
  PMP::orient_polygon_soup(pts, polys);
  rep.vertices_split = pts.size() - points_before;
  for (size_t i = 0; i < polys.size() && i < before.size() && !rep.reoriented; ++i) {
    const auto& b = before[i];
    const P3 a0 = pts[polys[i][0]], a1 = pts[polys[i][1]];
    for (int k = 0; k < 3; ++k)
      if (a0 == b[k] && a1 == b[(k + 2) % 3]) rep.reoriented = true;
  }

  SM sm;
  PMP::polygon_soup_to_polygon_mesh(pts, polys, sm);
  const size_t faces_before = sm.number_of_faces();
  PMP::remove_degenerate_faces(sm);
  sm.collect_garbage();
  rep.faces_removed += faces_before - sm.number_of_faces();

  Mesh3 m;
  std::vector<P3> out_pts;
  std::vector<std::vector<size_t>> out_polys;
  PMP::polygon_mesh_to_polygon_soup(sm, out_pts, out_polys);
  for (const P3& p : out_pts) m.points.emplace_back(p.x(), p.y(), p.z());
  for (const auto& p : out_polys)
    if (p.size() == 3) m.faces.push_back({int(p[0]), int(p[1]), int(p[2])});
  return m;
}

// Components by shared edges, numbered by decreasing face count (ties: first face first).
std::vector<int> face_components(const std::vector<Tri>& faces, int& count) {
  UnionFind uf(faces.size());
  std::unordered_map<uint64_t, int> first;
  for (size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const auto [it, added] = first.try_emplace(edge_key(faces[f][k], faces[f][(k + 1) % 3]), int(f));
      if (!added) uf.join(int(f), it->second);
    }
  std::map<int, std::pair<int, int>> size;  // root -> (faces, first face)
  for (size_t f = 0; f < faces.size(); ++f) {
    auto& s = size.try_emplace(uf.find(int(f)), 0, int(f)).first->second;
    ++s.first;
  }
  std::vector<std::pair<std::pair<int, int>, int>> order;
  for (const auto& [root, s] : size) order.push_back({{-s.first, s.second}, root});
  std::sort(order.begin(), order.end());
  std::unordered_map<int, int> rank;
  for (size_t i = 0; i < order.size(); ++i) rank[order[i].second] = int(i);
  std::vector<int> label(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) label[f] = rank[uf.find(int(f))];
  count = static_cast<int>(order.size());
  return label;
}

// ---- Seam cut ------------------------------------------------------------------------------

// Cuts a closed genus-0 mesh open along a shortest path between two far apart vertices: the
// path's inner vertices are duplicated, the faces on its left taking the copies. Returns the
// number of seam edges.
size_t cut_along_seam(Mesh3& m) {
  const int nv = static_cast<int>(m.points.size());
  std::vector<std::vector<std::pair<int, double>>> adj(nv);
  std::unordered_map<uint64_t, int> face_of;  // directed edge -> face
  for (size_t f = 0; f < m.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = m.faces[f][k], b = m.faces[f][(k + 1) % 3];
      face_of[directed_key(a, b)] = int(f);
      adj[a].push_back({b, (m.points[a] - m.points[b]).norm()});
    }
  auto dijkstra = [&](int s, std::vector<int>& pred) {
    std::vector<double> d(nv, std::numeric_limits<double>::infinity());
    pred.assign(nv, -1);
    using Q = std::pair<double, int>;
    std::priority_queue<Q, std::vector<Q>, std::greater<>> q;
    d[s] = 0;
    q.push({0, s});
    while (!q.empty()) {
      const auto [dist, v] = q.top();
      q.pop();
      if (dist > d[v]) continue;
      for (const auto& [w, len] : adj[v])
        if (dist + len < d[w]) d[w] = dist + len, pred[w] = v, q.push({d[w], w});
    }
    return int(std::max_element(d.begin(), d.end(), [](double a, double b) {
                 return (std::isfinite(a) ? a : -1) < (std::isfinite(b) ? b : -1);
               }) - d.begin());
  };
  std::vector<int> pred;
  const int s = dijkstra(0, pred);
  const int t = dijkstra(s, pred);
  std::vector<int> path;
  for (int v = t; v >= 0; v = pred[v]) path.push_back(v);
  if (path.size() < 3) throw InvalidInput("the closed surface is too small to cut open along a seam");
  // Inner path vertices: the faces from (p -> v) around v to (v -> q), on the path's left, get
  // a copy of v. All fans are found on the uncut mesh first.
  std::vector<std::vector<int>> fans(path.size());
  for (size_t i = 1; i + 1 < path.size(); ++i) {
    const int p = path[i - 1], v = path[i], q = path[i + 1];
    int x = p;
    for (size_t guard = 0; guard <= adj[v].size() + 1 && x != q; ++guard) {
      const auto it = face_of.find(directed_key(x, v));
      if (it == face_of.end()) break;
      const Tri& f = m.faces[it->second];
      fans[i].push_back(it->second);
      const int k = int(std::find(f.begin(), f.end(), v) - f.begin());
      x = f[(k + 1) % 3];  // the face's edge v -> x
    }
    if (x != q) throw InvalidInput("the closed surface is not manifold along the seam");
  }
  for (size_t i = 1; i + 1 < path.size(); ++i) {
    const int v = path[i], copy = static_cast<int>(m.points.size());
    m.points.push_back(m.points[v]);
    for (int f : fans[i])
      for (int& c : m.faces[f])
        if (c == v) c = copy;
  }
  return path.size() - 1;
}

// ---- Flattening ----------------------------------------------------------------------------

// Above this mean area distortion (area-weighted, of the map scaled to the surface's area),
// `auto` relaxes a fold-free LSCM map toward equal areas (relax_areas). Measured on
// libcgal-demo's meshes: head 35.9 and lion 21.1 gain (their largest |F_u|, |F_v| fall 3 to 4
// times, lion's folds 28 -> 6); fandisk 4.66, sphere966 2.62 and patch-20 1.35 lose (folds
// appear), docs/benchmarks.md#flattening-relaxed-toward-equal-areas-2026-12-06.
constexpr double kRelaxAbove = 10;

// A triangle's corners in a 2D frame of its plane: (0, 0), (l, 0), (x, y) with y > 0.
std::array<Eigen::Vector2d, 3> local_frame(const Point3& a, const Point3& b, const Point3& c) {
  const Vector3 e1 = b - a, e2 = c - a;
  const double l = e1.norm();
  const Vector3 ex = e1 / l;
  const Vector3 ey = e1.cross(e2).cross(e1).normalized();
  return {Eigen::Vector2d(0, 0), Eigen::Vector2d(l, 0), Eigen::Vector2d(e2.dot(ex), e2.dot(ey))};
}

double area3(const Mesh3& m, const Tri& t) {
  return 0.5 * (m.points[t[1]] - m.points[t[0]]).cross(m.points[t[2]] - m.points[t[0]]).norm();
}

// LSCM (Levy et al. 2002): the least-squares conformal energy sum_T |sum_j W_j U_j|^2 / A_T,
// W_j the edge opposite corner j as a complex number in the triangle's frame, U_j = u_j + i v_j,
// with two boundary vertices pinned. Holes need nothing special.
std::vector<P2> lscm(const Mesh3& m, int pin_a, int pin_b) {
  const int nv = static_cast<int>(m.points.size());
  const double d = (m.points[pin_a] - m.points[pin_b]).norm();
  std::vector<int> column(2 * nv, -1);
  int free = 0;
  for (int v = 0; v < nv; ++v)
    if (v != pin_a && v != pin_b) column[2 * v] = free++, column[2 * v + 1] = free++;
  auto pinned = [&](int var) { return var == 2 * pin_b ? d : 0.0; };  // a at (0, 0), b at (d, 0)
  std::vector<Eigen::Triplet<double>> trip;
  std::vector<double> rhs;
  int row = 0;
  for (const Tri& t : m.faces) {
    const double area = area3(m, t);
    if (!(area > 0)) continue;
    const auto p = local_frame(m.points[t[0]], m.points[t[1]], m.points[t[2]]);
    const double s = 1 / std::sqrt(area);
    double b_re = 0, b_im = 0;
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector2d w = (p[(j + 2) % 3] - p[(j + 1) % 3]) * s;
      const int iu = 2 * t[j], iv = iu + 1;
      // Re: a u - b v; Im: b u + a v.
      const double re[2] = {w.x(), -w.y()}, im[2] = {w.y(), w.x()};
      const int var[2] = {iu, iv};
      for (int k = 0; k < 2; ++k) {
        if (column[var[k]] >= 0) {
          trip.emplace_back(row, column[var[k]], re[k]);
          trip.emplace_back(row + 1, column[var[k]], im[k]);
        } else {
          b_re -= re[k] * pinned(var[k]);
          b_im -= im[k] * pinned(var[k]);
        }
      }
    }
    rhs.push_back(b_re);
    rhs.push_back(b_im);
    row += 2;
  }
  Eigen::SparseMatrix<double> a(row, free);
  a.setFromTriplets(trip.begin(), trip.end());
  const Eigen::Map<const Eigen::VectorXd> b(rhs.data(), row);
  const Eigen::SparseMatrix<double> n = (a.transpose() * a).eval();
  const Eigen::VectorXd r = a.transpose() * b;
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> chol;
  chol.compute(n);
  if (chol.info() != Eigen::Success) throw SolverError("LSCM: the conformal system could not be factorised");
  const Eigen::VectorXd x = chol.solve(r);
  if (chol.info() != Eigen::Success || !x.allFinite()) throw SolverError("LSCM: the conformal system could not be solved");
  std::vector<P2> uv(nv);
  for (int v = 0; v < nv; ++v)
    uv[v] = column[2 * v] >= 0 ? P2(x[column[2 * v]], x[column[2 * v + 1]]) : P2(pinned(2 * v), 0);
  return uv;
}

// Mean-value coordinates (CGAL) with the longest boundary loop on a circle; the other loops
// (holes) are filled by a fan around their centroid while solving, so the mesh is a disk, and
// the map cannot fold (positive weights, convex boundary: Tutte / Floater).
std::vector<P2> mean_value(const Mesh3& m, const std::vector<std::vector<int>>& loops, int outer) {
  SM sm;
  std::vector<SM::Vertex_index> vh;
  for (const Point3& p : m.points) vh.push_back(sm.add_vertex(P3(p.x(), p.y(), p.z())));
  for (const Tri& t : m.faces)
    if (sm.add_face(vh[t[0]], vh[t[1]], vh[t[2]]) == SM::null_face())
      throw InvalidInput("the mesh could not be built for the mean-value parameterization (non-manifold)");
  for (size_t l = 0; l < loops.size(); ++l) {
    if (int(l) == outer) continue;
    Point3 c = Point3::Zero();
    for (int v : loops[l]) c += m.points[v];
    c /= double(loops[l].size());
    const auto cv = sm.add_vertex(P3(c.x(), c.y(), c.z()));
    const auto& loop = loops[l];
    for (size_t i = 0; i < loop.size(); ++i) {
      // The boundary runs loop[i] -> loop[i+1]; the fan face takes that direction.
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      if (sm.add_face(vh[a], vh[b], cv) == SM::null_face())
        throw InvalidInput("a hole could not be filled for the mean-value parameterization");
    }
  }
  using Border = SMP::Circular_border_arc_length_parameterizer_3<SM>;
  using Solver = CGAL::Eigen_solver_traits<
      Eigen::SparseLU<CGAL::Eigen_sparse_matrix<double>::EigenType, Eigen::COLAMDOrdering<int>>>;
  using Mvc = SMP::Mean_value_coordinates_parameterizer_3<SM, Border, Solver>;
  // The outer loop's first halfedge: a border halfedge (no face) from loop[0] to loop[1].
  const auto& lo = loops[outer];
  const auto h = sm.halfedge(vh[lo[0]], vh[lo[1]]);
  if (h == SM::null_halfedge() || !sm.is_border(h))
    throw InvalidInput("the outer boundary could not be found for the mean-value parameterization");
  auto uvmap = sm.add_property_map<SM::Vertex_index, P2>("v:uv").first;
  const SMP::Error_code err = SMP::parameterize(sm, Mvc(), h, uvmap);
  if (err != SMP::OK)
    throw SolverError(std::string("mean-value parameterization failed: ") + SMP::get_error_message(err));
  std::vector<P2> uv(m.points.size());
  for (size_t v = 0; v < uv.size(); ++v) uv[v] = uvmap[vh[v]];
  return uv;
}

// Where the map folds: the number of triangles not positively oriented, and whether two
// boundary edges cross or overlap.
struct Folds {
  size_t flipped = 0;
  bool boundary_crosses = false;
  bool ok() const { return flipped == 0 && !boundary_crosses; }
  std::string describe() const {
    std::string s;
    if (flipped) s = plural(flipped, "triangle", "triangles") + " flipped";
    if (boundary_crosses) s += (s.empty() ? "" : ", ") + std::string("the boundary crosses itself");
    return s;
  }
};

Folds find_folds(const Mesh3& m, const std::vector<P2>& uv, const std::vector<std::vector<int>>& loops) {
  Folds f;
  for (const Tri& t : m.faces)
    if (CGAL::orientation(uv[t[0]], uv[t[1]], uv[t[2]]) != CGAL::LEFT_TURN) ++f.flipped;
  std::vector<std::array<int, 2>> seg;
  for (const auto& loop : loops)
    for (size_t i = 0; i < loop.size(); ++i) seg.push_back({loop[i], loop[(i + 1) % loop.size()]});
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 2, size_t>;
  std::vector<Box> boxes;
  for (size_t i = 0; i < seg.size(); ++i)
    boxes.emplace_back(uv[seg[i][0]].bbox() + uv[seg[i][1]].bbox(), i);
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& a, const Box& b) {
    if (f.boundary_crosses) return;
    const auto& s = seg[a.info()];
    const auto& t = seg[b.info()];
    int shared = -1, ps = -1, pt = -1;
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j)
        if (s[i] == t[j]) shared = s[i], ps = s[1 - i], pt = t[1 - j];
    if (shared >= 0) {
      // Adjacent edges meet at their shared vertex; they fold if they overlap.
      const P2 &o = uv[shared], &p = uv[ps], &q = uv[pt];
      if (CGAL::orientation(o, p, q) == CGAL::COLLINEAR && (p - o) * (q - o) > 0) f.boundary_crosses = true;
      return;
    }
    if (CGAL::do_intersect(K::Segment_2(uv[s[0]], uv[s[1]]), K::Segment_2(uv[t[0]], uv[t[1]])))
      f.boundary_crosses = true;
  });
  return f;
}

// Fills the holes of a flattened disk with triangles, for a map that moves: a fan around the
// hole's centroid where that fan is positive in (u, v), else the hole polygon's constrained
// Delaunay triangulation. Appends the new points and faces to `ext` and `uv`; returns the
// loops still to be checked for crossings (the outer one, and any hole left open).
std::vector<std::vector<int>> fill_holes(Mesh3& ext, std::vector<P2>& uv, const std::vector<std::vector<int>>& loops,
                                         int outer) {
  std::vector<std::vector<int>> open{loops[outer]};
  for (size_t l = 0; l < loops.size(); ++l) {
    if (int(l) == outer) continue;
    const auto& loop = loops[l];
    const size_t L = loop.size();
    Point3 c = Point3::Zero();
    double cu = 0, cv = 0;
    for (int v : loop) c += ext.points[v], cu += uv[v].x(), cv += uv[v].y();
    const P2 centre(cu / double(L), cv / double(L));
    bool star = true;
    for (size_t i = 0; i < L && star; ++i)
      star = CGAL::orientation(uv[loop[i]], uv[loop[(i + 1) % L]], centre) == CGAL::LEFT_TURN;
    if (star) {
      const int id = static_cast<int>(ext.points.size());
      ext.points.push_back(c / double(L));
      uv.push_back(centre);
      for (size_t i = 0; i < L; ++i) ext.faces.push_back({loop[i], loop[(i + 1) % L], id});
      continue;
    }
    HoleCdt cdt;
    std::vector<HoleCdt::Vertex_handle> vh;
    for (int v : loop) {
      vh.push_back(cdt.insert(uv[v]));
      vh.back()->info() = v;
    }
    for (size_t i = 0; i < L; ++i) cdt.insert_constraint(vh[i], vh[(i + 1) % L]);
    // Inside the polygon: level 1 (every constraint is an edge of the loop).
    const auto level = detail::nesting_levels(cdt, [](HoleCdt::Vertex_handle, HoleCdt::Vertex_handle) { return true; });
    std::vector<Tri> fill;
    bool simple = cdt.number_of_vertices() == L;  // no two loop vertices at one (u, v)
    for (auto f = cdt.finite_faces_begin(); simple && f != cdt.finite_faces_end(); ++f)
      if (level.at(f) == 1) fill.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
    if (simple && fill.size() + 2 == L)
      ext.faces.insert(ext.faces.end(), fill.begin(), fill.end());
    else
      open.push_back(loop);
  }
  return open;
}

// Relaxes a fold-free flattening toward equal areas, keeping it fold-free. SLIM (Rabinovich
// et al. 2017) on the symmetric Dirichlet energy sum_T A_T (|J_T|^2 + |J_T^-1|^2), J_T the map
// of triangle T from its rest shape: infinite where a triangle degenerates, so no step flips
// one. The rest shape of each triangle is its 3D shape scaled by sqrt(r_T), r_T its area in the
// starting map over its 3D area (the map scaled to the surface's area): half of the way, on a
// log scale, from the start's areas to the surface's. The starting map's angles are largely
// kept and its largest area ratios fall to about their square root. Each step solves a
// weighted least-squares problem toward the nearest rotations (the u and v of every vertex
// together; `pin` keeps its place), then moves as far as keeps every triangle positive and the
// boundary free of crossings and lowers the energy. Holes are filled while it moves
// (fill_holes, the fill weighing a hundredth), so they cannot close or cross.
std::vector<P2> relax_areas(const Mesh3& m, const std::vector<P2>& start, const std::vector<std::vector<int>>& loops,
                            int outer, int pin, const std::function<void(const std::string&)>& say) {
  constexpr double kFillWeight = 0.01;
  constexpr int kMaxSteps = 100;
  constexpr double kStall = 1e-5;  // stop when a step lowers the energy by less (relative)
  Mesh3 ext = m;
  std::vector<P2> uv = start;
  const auto open = fill_holes(ext, uv, loops, outer);
  const int nv = static_cast<int>(ext.points.size());
  struct Face {
    Tri t;
    double weight;                  // 3D area (times kFillWeight for the fill)
    Eigen::Matrix<double, 2, 3> d;  // the gradient of a function of the corners on the rest shape
  };
  std::vector<Face> faces;
  double a3 = 0, a2 = 0;
  for (const Tri& t : m.faces) a3 += area3(m, t), a2 += std::fabs(CGAL::area(uv[t[0]], uv[t[1]], uv[t[2]]));
  if (!(a3 > 0) || !(a2 > 0)) return start;
  const double scale = std::sqrt(a3 / a2);
  for (P2& p : uv) p = P2(scale * p.x(), scale * p.y());
  for (size_t fi = 0; fi < ext.faces.size(); ++fi) {
    const Tri& t = ext.faces[fi];
    const double area = area3(ext, t);
    if (!(area > 0)) continue;
    const auto p = local_frame(ext.points[t[0]], ext.points[t[1]], ext.points[t[2]]);
    Eigen::Matrix2d ps;
    ps << p[1] - p[0], p[2] - p[0];
    const Eigen::Matrix2d pinv = ps.inverse();
    Eigen::Matrix<double, 2, 3> d;
    for (int k = 0; k < 2; ++k) d.row(k) << -(pinv(0, k) + pinv(1, k)), pinv(0, k), pinv(1, k);
    const bool fill = fi >= m.faces.size();
    if (!fill) {
      const double ratio = std::fabs(CGAL::area(uv[t[0]], uv[t[1]], uv[t[2]])) / area;
      if (ratio > 0) d /= std::pow(ratio, 0.25);  // rest edges times ratio^(1/4): areas times sqrt(ratio)
    }
    faces.push_back({t, fill ? kFillWeight * area : area, d});
  }
  using Vec = Eigen::VectorXd;
  auto jacobian = [](const Face& f, const Vec& x) {
    Eigen::Matrix2d j;
    for (int c = 0; c < 2; ++c)
      for (int k = 0; k < 2; ++k)
        j(c, k) = f.d(k, 0) * x[2 * f.t[0] + c] + f.d(k, 1) * x[2 * f.t[1] + c] + f.d(k, 2) * x[2 * f.t[2] + c];
    return j;
  };
  auto energy = [&](const Vec& x) {
    double e = 0;
    for (const Face& f : faces) {
      const Eigen::Matrix2d j = jacobian(f, x);
      const double det = j.determinant();
      if (!(det > 0)) return std::numeric_limits<double>::infinity();
      e += f.weight * j.squaredNorm() * (1 + 1 / (det * det));  // |J^-1|^2 = |J|^2 / det^2 in 2D
    }
    return e;
  };
  auto to_uv = [](const Vec& x, size_t count) {
    std::vector<P2> r(count);
    for (size_t v = 0; v < count; ++v) r[v] = P2(x[2 * v], x[2 * v + 1]);
    return r;
  };
  Vec x(2 * nv);
  for (int v = 0; v < nv; ++v) x[2 * v] = uv[v].x(), x[2 * v + 1] = uv[v].y();
  double e = energy(x);
  if (!std::isfinite(e)) return start;
  std::vector<int> column(2 * nv, -1);
  int unknowns = 0;
  for (int v = 0; v < 2 * nv; ++v)
    if (v / 2 != pin) column[v] = unknowns++;
  const int rows = 4 * static_cast<int>(faces.size());
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> chol;
  std::vector<Eigen::Triplet<double>> trip;
  Vec b(rows);
  int taken = 0;
  auto last_said = std::chrono::steady_clock::now();
  for (int step = 0; step < kMaxSteps; ++step) {
    if (say && std::chrono::steady_clock::now() - last_said > std::chrono::seconds(2)) {
      say("relaxing toward equal areas: step " + std::to_string(step + 1) + " of at most " + std::to_string(kMaxSteps));
      last_said = std::chrono::steady_clock::now();
    }
    // Local step: per triangle the nearest rotation R and the weight W = U diag(w) U^T with
    // w = sqrt(f'(s) / (2 (s - 1))) for f(s) = s^2 + s^-2, that is sqrt((s + 1)(s^2 + 1) / s^3).
    // Global step: min sum_T weight_T |W_T (J_T - R_T)|^2, rows (i, k) of each triangle.
    trip.clear();
    for (size_t fi = 0; fi < faces.size(); ++fi) {
      const Face& f = faces[fi];
      const Eigen::JacobiSVD<Eigen::Matrix2d> svd(jacobian(f, x), Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Eigen::Matrix2d u = svd.matrixU();
      Eigen::Vector2d w;
      for (int i = 0; i < 2; ++i) {
        const double sv = std::max(svd.singularValues()[i], 1e-8);
        w[i] = std::sqrt((sv + 1) * (sv * sv + 1) / (sv * sv * sv));
      }
      const Eigen::Matrix2d wm = u * w.asDiagonal() * u.transpose();
      const Eigen::Matrix2d target = wm * u * svd.matrixV().transpose();
      const double sw = std::sqrt(f.weight);
      for (int i = 0; i < 2; ++i)
        for (int k = 0; k < 2; ++k) {
          const int row = static_cast<int>(4 * fi + 2 * i + k);
          double rhs = sw * target(i, k);
          for (int c = 0; c < 2; ++c)
            for (int j = 0; j < 3; ++j) {
              const double coef = sw * wm(i, c) * f.d(k, j);
              const int var = 2 * f.t[j] + c;
              if (column[var] >= 0)
                trip.emplace_back(row, column[var], coef);
              else
                rhs -= coef * x[var];
            }
          b[row] = rhs;
        }
    }
    Eigen::SparseMatrix<double> a(rows, unknowns);
    a.setFromTriplets(trip.begin(), trip.end());
    const Eigen::SparseMatrix<double> at = a.transpose();
    const Eigen::SparseMatrix<double> n = (at * a).eval();
    if (taken == 0) chol.analyzePattern(n);
    chol.factorize(n);
    if (chol.info() != Eigen::Success) break;
    const Vec sol = chol.solve(at * b);
    if (chol.info() != Eigen::Success || !sol.allFinite()) break;
    Vec dir = Vec::Zero(2 * nv);
    for (int v = 0; v < 2 * nv; ++v)
      if (column[v] >= 0) dir[v] = sol[column[v]] - x[v];
    // The first step length tried: 0.9 times the largest that keeps every triangle positive,
    // the smallest positive root of det(J + t D) = det J + t c1 + t^2 det D.
    double t = 1;
    for (const Face& f : faces) {
      const Eigen::Matrix2d j = jacobian(f, x), dj = jacobian(f, dir);
      const double c0 = j.determinant(), c2 = dj.determinant();
      const double c1 = j(0, 0) * dj(1, 1) + dj(0, 0) * j(1, 1) - j(0, 1) * dj(1, 0) - dj(0, 1) * j(1, 0);
      double root = std::numeric_limits<double>::infinity();
      if (c2 == 0) {
        if (c1 < 0) root = -c0 / c1;
      } else if (const double disc = c1 * c1 - 4 * c2 * c0; disc >= 0) {
        const double sq = std::sqrt(disc);
        for (const double r : {(-c1 - sq) / (2 * c2), (-c1 + sq) / (2 * c2)})
          if (r > 0) root = std::min(root, r);
      }
      t = std::min(t, 0.9 * root);
    }
    bool moved = false;
    double gain = 0;
    for (int tries = 0; tries < 30 && !moved; ++tries, t *= 0.5) {
      const Vec y = x + t * dir;
      const double ey = energy(y);
      if (!(ey < e)) continue;
      if (!find_folds(ext, to_uv(y, ext.points.size()), open).ok()) continue;
      gain = (e - ey) / e;
      x = y, e = ey, moved = true;
      ++taken;
    }
    if (!moved || gain < kStall) break;
  }
  if (say) say("relaxed toward equal areas in " + plural(static_cast<size_t>(taken), "step", "steps"));
  return to_uv(x, m.points.size());
}

// Scales the parameters to the surface's area, turns them to their principal axes (a rotation,
// so orientation is kept) and moves their box to the origin.
void normalise(const Mesh3& m, std::vector<P2>& uv) {
  double a3 = 0, a2 = 0;
  for (const Tri& t : m.faces) {
    a3 += area3(m, t);
    a2 += std::fabs(CGAL::area(uv[t[0]], uv[t[1]], uv[t[2]]));
  }
  const double s = a2 > 0 ? std::sqrt(a3 / a2) : 1.0;
  Eigen::Vector2d mean(0, 0);
  for (const P2& p : uv) mean += Eigen::Vector2d(p.x(), p.y());
  mean /= double(uv.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const P2& p : uv) {
    const Eigen::Vector2d d = Eigen::Vector2d(p.x(), p.y()) - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  Eigen::Vector2d ax = eig.eigenvectors().col(1);  // the largest spread along u
  if (ax.x() < 0) ax = -ax;
  const Eigen::Vector2d ay(-ax.y(), ax.x());
  double umin = 1e300, vmin = 1e300;
  std::vector<Eigen::Vector2d> q(uv.size());
  for (size_t i = 0; i < uv.size(); ++i) {
    const Eigen::Vector2d d = Eigen::Vector2d(uv[i].x(), uv[i].y()) - mean;
    q[i] = s * Eigen::Vector2d(d.dot(ax), d.dot(ay));
    umin = std::min(umin, q[i].x());
    vmin = std::min(vmin, q[i].y());
  }
  for (size_t i = 0; i < uv.size(); ++i) uv[i] = P2(q[i].x() - umin, q[i].y() - vmin);
}

Distortion distortion(const Mesh3& m, const std::vector<P2>& uv) {
  Distortion d;
  double wsum = 0, angle = 0, area = 0;
  d.angle_max = d.area_max = 1;
  for (const Tri& t : m.faces) {
    const double w = area3(m, t);
    if (!(w > 0)) continue;
    const auto p = local_frame(m.points[t[0]], m.points[t[1]], m.points[t[2]]);
    Eigen::Matrix2d ps, qs;
    ps << p[1] - p[0], p[2] - p[0];
    qs << uv[t[1]].x() - uv[t[0]].x(), uv[t[2]].x() - uv[t[0]].x(), uv[t[1]].y() - uv[t[0]].y(),
        uv[t[2]].y() - uv[t[0]].y();
    const Eigen::Matrix2d j = qs * ps.inverse();
    const Eigen::Vector2d sv = Eigen::JacobiSVD<Eigen::Matrix2d>(j).singularValues();
    const double a = sv[1] > 0 ? sv[0] / sv[1] : std::numeric_limits<double>::infinity();
    const double r = sv[0] * sv[1] > 0 ? std::max(sv[0] * sv[1], 1 / (sv[0] * sv[1])) : std::numeric_limits<double>::infinity();
    angle += w * a;
    area += w * r;
    wsum += w;
    d.angle_max = std::max(d.angle_max, a);
    d.area_max = std::max(d.area_max, r);
  }
  if (wsum > 0) d.angle_mean = angle / wsum, d.area_mean = area / wsum;
  return d;
}

// Flattens a disk with holes; tries LSCM first unless told otherwise.
std::vector<P2> flatten(const Mesh3& m, const ParameterizeOptions& o, ParameterizeReport& rep) {
  const auto loops = boundary_loops(m.faces);
  if (loops.empty()) throw InvalidInput("the surface has no boundary to flatten");
  auto loop_length = [&](const std::vector<int>& l) {
    double len = 0;
    for (size_t i = 0; i < l.size(); ++i) len += (m.points[l[(i + 1) % l.size()]] - m.points[l[i]]).norm();
    return len;
  };
  int outer = 0;
  for (size_t l = 1; l < loops.size(); ++l)
    if (loop_length(loops[l]) > loop_length(loops[outer])) outer = int(l);
  auto say = [&](const std::string& s) {
    if (o.progress) o.progress(s);
  };
  std::vector<P2> uv;
  if (o.method != FlattenMethod::MeanValue) {
    // Pins: two far apart vertices of the outer boundary.
    const auto& lo = loops[outer];
    int a = lo[0], b = lo[0];
    for (int v : lo)
      if ((m.points[v] - m.points[lo[0]]).squaredNorm() > (m.points[a] - m.points[lo[0]]).squaredNorm()) a = v;
    for (int v : lo)
      if ((m.points[v] - m.points[a]).squaredNorm() > (m.points[b] - m.points[a]).squaredNorm()) b = v;
    if (a == b) throw InvalidInput("the surface's boundary has no extent");
    say("flattening " + plural(m.faces.size(), "triangle", "triangles") + " (LSCM)");
    try {
      uv = lscm(m, a, b);
    } catch (const SolverError& e) {
      if (o.method == FlattenMethod::Lscm) throw;
      uv.clear();
      rep.fallback_reason = std::string("LSCM could not be solved: ") + e.what();
    }
    Folds f = uv.empty() ? Folds{} : find_folds(m, uv, loops);
    if (f.flipped > m.faces.size() / 2) {  // a mirror image: LSCM keeps orientation, so only if
      for (P2& p : uv) p = P2(p.x(), -p.y());  // the pins made it so; flip back
      f = find_folds(m, uv, loops);
    }
    if (!uv.empty() && f.ok()) {
      rep.method = "LSCM";
      if (o.method == FlattenMethod::Auto) {
        // A conformal map shrinks a part of a surface that bulges away from its boundary
        // exponentially (a near-closed surface opened at one small loop): relaxed toward equal
        // areas where the mean area distortion exceeds kRelaxAbove.
        std::vector<P2> scaled = uv;
        normalise(m, scaled);
        const Distortion conformal = distortion(m, scaled);
        if (conformal.area_mean > kRelaxAbove) {
          char text[160];
          std::snprintf(text, sizeof text, "LSCM shrinks parts of the surface (area distortion %.3g mean, %.3g max); "
                        "relaxing it toward equal areas", conformal.area_mean, conformal.area_max);
          say(text);
          std::vector<P2> relaxed = relax_areas(m, uv, loops, outer, a, o.progress);
          if (find_folds(m, relaxed, loops).ok()) {
            rep.method = "LSCM, areas relaxed";
            rep.conformal = conformal;
            return relaxed;
          }
        }
      }
      return uv;
    }
    if (!uv.empty()) rep.fallback_reason = "LSCM folds: " + f.describe();
    if (o.method == FlattenMethod::Lscm)
      throw InvalidInput("the LSCM parameterization folds (" + f.describe() + "); use the default method, which falls back to mean-value coordinates");
    say(rep.fallback_reason + "; using mean-value coordinates with a circular boundary");
  } else {
    say("flattening " + plural(m.faces.size(), "triangle", "triangles") + " (mean-value coordinates)");
  }
  uv = mean_value(m, loops, outer);
  const Folds f = find_folds(m, uv, loops);
  if (!f.ok())
    throw InvalidInput("no bijective parameterization found: the mean-value map folds too (" + f.describe() +
                       "), which happens only for degenerate meshes; repair the mesh (e.g. remove slivers) and retry");
  rep.method = "mean value (circular boundary)";
  return uv;
}

// Unit normal of each face corner: the area-weighted mean of the normals of the faces around
// the vertex that turn by less than `sharp_deg` from this face (so creases stay creases).
std::vector<std::array<Vector3, 3>> corner_normals(const Mesh3& m, double sharp_deg) {
  std::vector<Vector3> fn(m.faces.size());
  std::vector<std::vector<int>> around(m.points.size());
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const Tri& t = m.faces[f];
    fn[f] = (m.points[t[1]] - m.points[t[0]]).cross(m.points[t[2]] - m.points[t[0]]);  // |.| = 2 area
    for (int v : t) around[v].push_back(int(f));
  }
  const double cos_sharp = std::cos(sharp_deg * M_PI / 180);
  std::vector<std::array<Vector3, 3>> out(m.faces.size());
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const Vector3 nf = fn[f].normalized();
    for (int k = 0; k < 3; ++k) {
      Vector3 sum = Vector3::Zero();
      for (int g : around[m.faces[f][k]])
        if (fn[g].normalized().dot(nf) >= cos_sharp) sum += fn[g];
      out[f][k] = sum.norm() > 0 ? Vector3(sum.normalized()) : nf;
    }
  }
  return out;
}

// One 1-to-4 subdivision with new vertices on a smooth surface through the old ones: the
// midpoint of each edge's cubic curve of the PN triangle (Vlachos et al. 2001) built from the
// end points and their corner normals. Where the two faces of an edge disagree on a normal (a
// crease) the edge stays straight. Parameters are the midpoints in (u, v). `origin` maps each
// vertex to an original vertex (for normals).
void subdivide(Mesh3& m, std::vector<P2>& uv, std::vector<int>& origin, double sharp_deg) {
  const auto normals = corner_normals(m, sharp_deg);
  struct Mid {
    int vertex;
    Vector3 na, nb;  // the corner normals of the face that made it
  };
  std::unordered_map<uint64_t, Mid> mid;
  auto curve_mid = [&](int a, int b, const Vector3& na, const Vector3& nb) {
    const Point3 &pa = m.points[a], &pb = m.points[b];
    const Point3 b1 = (2 * pa + pb - (pb - pa).dot(na) * na) / 3;
    const Point3 b2 = (2 * pb + pa - (pa - pb).dot(nb) * nb) / 3;
    return Point3((pa + 3 * b1 + 3 * b2 + pb) / 8);
  };
  std::vector<Tri> faces;
  faces.reserve(4 * m.faces.size());
  const size_t old_count = m.points.size();
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const Tri& t = m.faces[f];
    int e[3];
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const Vector3 &na = normals[f][k], &nb = normals[f][(k + 1) % 3];
      auto it = mid.find(edge_key(a, b));
      if (it == mid.end()) {
        const int v = static_cast<int>(m.points.size());
        m.points.push_back(curve_mid(a, b, na, nb));
        uv.push_back(CGAL::midpoint(uv[a], uv[b]));
        origin.push_back(origin[std::min(a, b)]);
        // Keyed by (min, max): store the normals in that order.
        it = mid.emplace(edge_key(a, b), a < b ? Mid{v, na, nb} : Mid{v, nb, na}).first;
      } else {
        // The second face of the edge: if it sees other normals, the edge is a crease.
        const Vector3 &ma = a < b ? na : nb, &mb = a < b ? nb : na;
        if (ma.dot(it->second.na) < 1 - 1e-12 || mb.dot(it->second.nb) < 1 - 1e-12)
          m.points[it->second.vertex] = 0.5 * (m.points[a] + m.points[b]);
      }
      e[k] = it->second.vertex;
    }
    faces.push_back({t[0], e[0], e[2]});
    faces.push_back({e[0], t[1], e[1]});
    faces.push_back({e[2], e[1], t[2]});
    faces.push_back({e[0], e[1], e[2]});
  }
  (void)old_count;
  m.faces = std::move(faces);
}

}  // namespace

std::string MeshTopology::describe() const {
  return plural(size_t(components), "component", "components") + ", " +
         plural(size_t(boundary_loops), "boundary loop", "boundary loops") + ", genus " + std::to_string(genus);
}

MeshTopology mesh_topology(size_t vertex_count, const std::vector<std::array<int, 3>>& triangles) {
  MeshTopology t;
  t.faces = triangles.size();
  std::unordered_map<uint64_t, int> edges;
  std::vector<char> used(vertex_count, 0);
  for (const Tri& f : triangles)
    for (int k = 0; k < 3; ++k) {
      ++edges[edge_key(f[k], f[(k + 1) % 3])];
      used[f[k]] = 1;
    }
  t.edges = edges.size();
  t.vertices = static_cast<size_t>(std::count(used.begin(), used.end(), 1));
  int comps = 0;
  face_components(triangles, comps);
  t.components = comps;
  // Boundary loops: components of the graph of boundary edges (edges in one face).
  UnionFind uf(vertex_count);
  std::vector<char> on_boundary(vertex_count, 0);
  for (const auto& [key, count] : edges)
    if (count == 1) {
      const int a = int(key >> 32), b = int(key & 0xffffffffu);
      uf.join(a, b);
      on_boundary[a] = on_boundary[b] = 1;
    }
  for (size_t v = 0; v < vertex_count; ++v)
    if (on_boundary[v] && uf.find(int(v)) == int(v)) ++t.boundary_loops;
  const long chi = long(t.vertices) - long(t.edges) + long(t.faces);
  t.genus = static_cast<int>((2L * t.components - t.boundary_loops - chi) / 2);
  return t;
}

std::string ParameterizeReport::to_json() const {
  auto topo = [](const MeshTopology& t) {
    return nlohmann::ordered_json{{"vertices", t.vertices}, {"edges", t.edges},        {"faces", t.faces},
                                  {"components", t.components}, {"boundary_loops", t.boundary_loops},
                                  {"genus", t.genus}};
  };
  nlohmann::ordered_json j;
  j["input"] = input;
  j["input_points"] = input_points;
  j["input_faces"] = input_faces;
  if (input == "point cloud") {
    j["reconstructed_faces"] = reconstructed_faces;
    j["bridge_faces_removed"] = bridge_faces_removed;
  }
  j["repair"] = {{"vertices_merged", vertices_merged},
                 {"faces_removed", faces_removed},
                 {"vertices_split", vertices_split},
                 {"reoriented", reoriented},
                 {"isolated_points", isolated_points}};
  j["topology"] = topo(topology);
  j["component"] = component;
  j["component_topology"] = topo(used);
  j["seam_edges"] = seam_edges;
  j["method"] = method;
  j["fallback_reason"] = fallback_reason;
  if (method == "LSCM, areas relaxed")
    j["conformal_distortion"] = {{"angle", {{"mean", conformal.angle_mean}, {"max", conformal.angle_max}}},
                                 {"area", {{"mean", conformal.area_mean}, {"max", conformal.area_max}}}};
  j["angle_distortion"] = {{"mean", distortion.angle_mean}, {"max", distortion.angle_max}};
  j["area_distortion"] = {{"mean", distortion.area_mean}, {"max", distortion.area_max}};
  j["points_projected"] = points_projected;
  j["points_dropped"] = points_dropped;
  j["subdivisions"] = subdivisions;
  j["points_added"] = points_added;
  j["seconds"] = seconds;
  return j.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

ParameterizedScan parameterize_scan(const Scan& scan, const ParameterizeOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string name = scan.source.empty() ? "the scan" : scan.source;
  auto say = [&](const std::string& s) {
    if (o.progress) o.progress(s);
  };
  ParameterizedScan out;
  ParameterizeReport& rep = out.report;
  const bool cloud = scan.triangles.empty();
  rep.input = cloud ? "point cloud" : "mesh";
  rep.input_points = scan.positions.size();
  rep.input_faces = scan.triangles.size();
  if (scan.positions.size() < 3) throw InvalidInput(name + ": too few points to parameterize (" + std::to_string(scan.positions.size()) + ")");
  // What read_scan guarantees, checked again for scans built in code.
  for (size_t i = 0; i < scan.positions.size(); ++i)
    if (!scan.positions[i].allFinite() || scan.positions[i].cwiseAbs().maxCoeff() > 1e30)
      throw InvalidInput(name + ": point " + std::to_string(i) + " is not finite or larger than 1e30 in magnitude");
  if (!scan.normals.empty() && scan.normals.size() != scan.positions.size())
    throw InvalidInput(name + ": " + std::to_string(scan.normals.size()) + " normals for " +
                       std::to_string(scan.positions.size()) + " points; give one per point or none");
  for (size_t i = 0; i < scan.normals.size(); ++i)
    if (!scan.normals[i].allFinite() || !(scan.normals[i].stableNorm() > 0))
      throw InvalidInput(name + ": normal " + std::to_string(i) + " is not a finite, non-zero vector");
  for (size_t f = 0; f < scan.triangles.size(); ++f)
    for (int v : scan.triangles[f])
      if (v < 0 || static_cast<size_t>(v) >= scan.positions.size())
        throw InvalidInput(name + ": triangle " + std::to_string(f) + " refers to point " + std::to_string(v) +
                           ", but the points are numbered 0 to " + std::to_string(scan.positions.size() - 1));

  std::vector<Tri> triangles = scan.triangles;
  if (cloud) {
    // A surface needs points that span a plane at least; CGAL's triangulation would only
    // complain on stderr.
    {
      Point3 mean = Point3::Zero();
      for (const Point3& p : scan.positions) mean += p;
      mean /= static_cast<double>(scan.positions.size());
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (const Point3& p : scan.positions) cov += (p - mean) * (p - mean).transpose();
      const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();
      if (!(ev[2] > 0))
        throw InvalidInput(name + ": all " + std::to_string(scan.positions.size()) +
                           " points are identical; there is no surface to fit");
      if (ev[1] <= 1e-20 * ev[2])
        throw InvalidInput(name + ": all points lie on one line; there is no surface to fit");
    }
    say("reconstructing a surface from " + plural(scan.positions.size(), "point", "points") + " (advancing front)");
    std::vector<std::pair<P3, std::size_t>> pts;  // each point with its index
    pts.reserve(scan.positions.size());
    for (const Point3& p : scan.positions) pts.emplace_back(P3(p.x(), p.y(), p.z()), pts.size());
    std::vector<std::array<std::size_t, 3>> facets;
    {
      afsr::Delaunay dt(pts.begin(), pts.end());
      // The local spacing of each point: its third-nearest Delaunay neighbour (the nearest
      // neighbours are among them), before the reconstruction removes any vertex.
      std::vector<double> spacing(pts.size(), 0.0);
      std::vector<double> len;
      std::vector<afsr::Delaunay::Vertex_handle> around;
      for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) {
        around.clear();
        len.clear();
        dt.finite_adjacent_vertices(v, std::back_inserter(around));
        for (auto w : around) len.push_back(std::sqrt(CGAL::squared_distance(v->point(), w->point())));
        if (len.empty()) continue;
        const auto k = static_cast<long>(std::min<size_t>(2, len.size() - 1));
        std::nth_element(len.begin(), len.begin() + k, len.end());
        spacing[v->info()] = len[static_cast<size_t>(k)];
      }
      CGAL::Advancing_front_surface_reconstruction<afsr::Delaunay> reconstruction(dt);
      reconstruction.run();  // CGAL's defaults: radius ratio bound 5, beta 0.52
      CGAL::write_triple_indices(std::back_inserter(facets), reconstruction);
      // Bridges: a face with an edge longer than kBridgeRatio times the spacing at both of its
      // ends spans a gap in the samples (the reconstruction joins separate clusters of points
      // that way). Such long, thin faces made LSCM fold on poste_france.xyz and its fallback
      // distort the map 90-fold; they are removed, and a cluster they alone held on becomes a
      // component of its own.
      constexpr double kBridgeRatio = 20;
      const size_t before = facets.size();
      std::erase_if(facets, [&](const std::array<std::size_t, 3>& f) {
        for (int k = 0; k < 3; ++k) {
          const std::size_t a = f[k], b = f[(k + 1) % 3];
          if ((scan.positions[a] - scan.positions[b]).norm() > kBridgeRatio * std::max(spacing[a], spacing[b]))
            return true;
        }
        return false;
      });
      rep.bridge_faces_removed = before - facets.size();
    }
    // The facets come in the order of the reconstruction's surface data structure: each now
    // starts at its smallest index (orientation kept) and they are sorted.
    for (auto& f : facets) std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
    std::sort(facets.begin(), facets.end());
    for (const auto& f : facets) triangles.push_back({int(f[0]), int(f[1]), int(f[2])});
    rep.reconstructed_faces = triangles.size();
    if (triangles.empty())
      throw InvalidInput(name + ": no surface could be reconstructed from these points (they may be collinear, "
                         "coplanar in a line, or too few); give a mesh instead");
  }

  say("repairing the mesh");
  Mesh3 mesh = repair(scan.positions, triangles, rep);
  if (mesh.faces.empty()) throw InvalidInput(name + ": no usable triangle is left after removing degenerate ones");
  int components = 0;
  const std::vector<int> label = face_components(mesh.faces, components);
  rep.topology = mesh_topology(mesh.points.size(), mesh.faces);
  const int want = o.component <= 0 ? 1 : o.component;
  if (want > components)
    throw InvalidInput(name + ": there is no component " + std::to_string(want) + ": the mesh has " + rep.topology.describe() +
                       "; choose --component 1 to " + std::to_string(components));
  rep.component = want;

  // The chosen component, vertices renumbered in order of first use.
  Mesh3 part;
  std::vector<int> local(mesh.points.size(), -1), face_local(mesh.faces.size(), -1);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (label[f] != want - 1) continue;
    Tri t;
    for (int k = 0; k < 3; ++k) {
      int& l = local[mesh.faces[f][k]];
      if (l < 0) l = int(part.points.size()), part.points.push_back(mesh.points[mesh.faces[f][k]]);
      t[k] = l;
    }
    face_local[f] = int(part.faces.size());
    part.faces.push_back(t);
  }
  rep.used = mesh_topology(part.points.size(), part.faces);
  const std::string found = "component " + std::to_string(want) + " of " + std::to_string(components) + " has " +
                            plural(rep.used.vertices, "vertex", "vertices") + ", " +
                            plural(size_t(rep.used.boundary_loops), "boundary loop", "boundary loops") +
                            ", genus " + std::to_string(rep.used.genus);
  {
    // Faces that are all slivers (nearly collinear corners) survive the exact degeneracy test
    // but flatten onto a curve.
    double area = 0;
    Eigen::AlignedBox3d box;
    for (const Tri& t : part.faces) {
      const Point3 &a = part.points[t[0]], &b = part.points[t[1]], &c = part.points[t[2]];
      area += 0.5 * (b - a).cross(c - a).norm();
      box.extend(a), box.extend(b), box.extend(c);
    }
    const double diagonal = box.diagonal().norm();
    if (!(area > 1e-10 * diagonal * diagonal))
      throw InvalidInput(name + ": " + found + ", but its " + plural(part.faces.size(), "face has", "faces have") +
                         " almost no area (" + short_number(area) + " in a box of diagonal " +
                         short_number(diagonal) + "): they are slivers; remesh the scan");
  }
  if (rep.used.genus > 0)
    throw InvalidInput(name + ": " + found + ": tbs fits one surface that unfolds onto the plane (a disk, "
                       "possibly with holes, or a closed surface of genus 0); " +
                       (rep.input == "point cloud"
                            ? std::string("the surface reconstructed from the points has handles, which happens "
                                          "when the points are too sparse for the surface's curvature; give a "
                                          "denser scan or a mesh")
                            : std::string("cut this one open into a disk (e.g. in Blender or MeshLab) or split it "
                                          "into pieces and fit each")));
  if (rep.used.boundary_loops == 0) {
    if (!o.cut_closed)
      throw InvalidInput(name + ": " + found + ": the surface is closed; cut it open into a disk, or allow a seam");
    say("cutting the closed surface open along a seam");
    rep.seam_edges = cut_along_seam(part);
  }

  std::vector<P2> uv = flatten(part, o, rep);
  normalise(part, uv);
  rep.distortion = distortion(part, uv);

  // The input point of each part vertex: exact positions, first index.
  std::unordered_map<std::string, size_t> index_of;
  auto key = [](const Point3& p) { return std::string(reinterpret_cast<const char*>(p.data()), 3 * sizeof(double)); };
  for (size_t i = scan.positions.size(); i-- > 0;) index_of[key(scan.positions[i])] = i;
  Scan& s = out.scan;
  s.source = scan.source;
  if (!cloud) {
    const size_t copies = rep.seam_edges > 0 ? rep.seam_edges - 1 : 0;
    rep.points_dropped = scan.positions.size() - (part.points.size() - copies);
    // Each vertex's input point; subdivision vertices take their edge's first vertex's (for the
    // normal) and are marked as new in `source` below.
    std::vector<int> origin(part.points.size());
    std::iota(origin.begin(), origin.end(), 0);
    const size_t original = part.points.size();
    while (o.min_points > 0 && part.points.size() < o.min_points && rep.subdivisions < 4) {
      subdivide(part, uv, origin, o.sharp_angle);
      ++rep.subdivisions;
    }
    rep.points_added = part.points.size() - original;
    if (rep.subdivisions) say("subdivided the mesh " + std::to_string(rep.subdivisions) + " times: " +
                              plural(part.points.size(), "point", "points"));
    for (size_t v = 0; v < part.points.size(); ++v) {
      const auto it = index_of.find(key(part.points[origin[v]]));
      const size_t src = it == index_of.end() ? 0 : it->second;
      out.source.push_back(src);
      if (original < part.points.size()) s.guide.push_back(v >= original ? 1 : 0);
      s.positions.push_back(part.points[v]);
      s.uv.emplace_back(uv[v].x(), uv[v].y());
      if (scan.has_normals()) s.normals.push_back(scan.normals[src].stableNormalized());
    }
    s.triangles = part.faces;
  } else {
    // Every point takes the parameter of its closest point on the mesh, if that lies on the
    // chosen component.
    say("projecting the points onto the mesh");
    std::vector<K::Triangle_3> tris;
    for (const Tri& t : mesh.faces)
      tris.emplace_back(P3(mesh.points[t[0]].x(), mesh.points[t[0]].y(), mesh.points[t[0]].z()),
                        P3(mesh.points[t[1]].x(), mesh.points[t[1]].y(), mesh.points[t[1]].z()),
                        P3(mesh.points[t[2]].x(), mesh.points[t[2]].y(), mesh.points[t[2]].z()));
    using Prim = CGAL::AABB_triangle_primitive<K, std::vector<K::Triangle_3>::const_iterator>;
    using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Prim>>;
    Tree tree(tris.begin(), tris.end());
    tree.accelerate_distance_queries();
    for (size_t i = 0; i < scan.positions.size(); ++i) {
      const Point3& p = scan.positions[i];
      const auto [q, prim] = tree.closest_point_and_primitive(P3(p.x(), p.y(), p.z()));
      const size_t f = static_cast<size_t>(prim - tris.begin());
      if (face_local[f] < 0) {
        ++rep.points_dropped;
        continue;
      }
      const Tri& t = part.faces[face_local[f]];
      // Barycentric coordinates of q in the 3D triangle.
      const Vector3 e1 = part.points[t[1]] - part.points[t[0]], e2 = part.points[t[2]] - part.points[t[0]];
      const Vector3 r = Vector3(q.x(), q.y(), q.z()) - part.points[t[0]];
      Eigen::Matrix2d g;
      g << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
      Eigen::Vector2d l = g.ldlt().solve(Eigen::Vector2d(e1.dot(r), e2.dot(r)));
      l = l.cwiseMax(0.0);
      if (l.sum() > 1) l /= l.sum();
      const P2 &a = uv[t[0]], &b = uv[t[1]], &c = uv[t[2]];
      s.positions.push_back(p);
      s.uv.emplace_back(a.x() + l[0] * (b.x() - a.x()) + l[1] * (c.x() - a.x()),
                        a.y() + l[0] * (b.y() - a.y()) + l[1] * (c.y() - a.y()));
      if (scan.has_normals()) s.normals.push_back(scan.normals[i].stableNormalized());
      out.source.push_back(i);
      ++rep.points_projected;
    }
  }
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace tbs
