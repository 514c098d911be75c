// The mesh parameterize_scan() flattens, made usable: repair (CGAL Polygon_mesh_processing),
// face components, boundary loops and topology (mesh_topology), and the seam that cuts a
// closed surface open.

#include "scan_mesh.h"

#include <tbs/errors.h>

#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_mesh_to_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <queue>
#include <unordered_map>

namespace tbs::detail {

namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using SM = CGAL::Surface_mesh<P3>;

}  // namespace

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

}  // namespace tbs::detail

namespace tbs {

using namespace detail;

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

}  // namespace tbs
