#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/predicates.h>
#include <tbs/tessellate.h>

#include "side_eval.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <functional>
#include <map>
#include <numeric>

namespace tbs {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using Fb = CGAL::Triangulation_face_base_with_info_2<int, K, CGAL::Constrained_triangulation_face_base_2<K>>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<Vb, Fb>,
                                                       CGAL::Exact_predicates_tag>;

// A mesh vertex, named the same way from both triangles of an edge: a domain vertex (kind 0,
// a = vertex, c = sector when split), a point i/k along a domain edge from its lower vertex
// (kind 1, a = edge, b = i, c = k, side = triangle when split), or a lattice point (i, j) of
// triangle a (kind 2).
struct VKey {
  int kind = 0, a = 0, b = 0, c = 0, d = 0, side = -1;
  auto operator<=>(const VKey&) const = default;
};

// Flat triangle vs surface: the largest distance at the centroid and edge midpoints of the
// lattice faces of triangle t at resolution r.
double chordal_deviation(const Evaluator& ev, const std::array<Point2, 3>& c, int r) {
  auto at = [&](double i, double j) {
    const double l1 = i / r, l2 = j / r;
    return Point2((1 - l1 - l2) * c[0] + l1 * c[1] + l2 * c[2]);
  };
  const Point2 centre = (c[0] + c[1] + c[2]) / 3.0;
  auto f = [&](const Point2& u) { return detail::evaluate_toward(ev, u, centre, c[0] == u ? c[1] : c[0]).position; };
  std::vector<Point3> grid((r + 1) * (r + 2) / 2);
  auto idx = [&](int i, int j) { return j * (r + 1) - j * (j - 1) / 2 + i; };
  for (int j = 0; j <= r; ++j)
    for (int i = 0; i + j <= r; ++i) grid[idx(i, j)] = f(at(i, j));
  double worst = 0;
  auto face = [&](int a0, int a1, int b0, int b1, int c0, int c1) {
    const Point3 &pa = grid[idx(a0, a1)], &pb = grid[idx(b0, b1)], &pc = grid[idx(c0, c1)];
    const Point3 mid = (pa + pb + pc) / 3.0;
    worst = std::max(worst, (f(at((a0 + b0 + c0) / 3.0, (a1 + b1 + c1) / 3.0)) - mid).norm());
    worst = std::max(worst, (f(at((a0 + b0) / 2.0, (a1 + b1) / 2.0)) - (pa + pb) / 2.0).norm());
    worst = std::max(worst, (f(at((b0 + c0) / 2.0, (b1 + c1) / 2.0)) - (pb + pc) / 2.0).norm());
    worst = std::max(worst, (f(at((c0 + a0) / 2.0, (c1 + a1) / 2.0)) - (pc + pa) / 2.0).norm());
  };
  for (int j = 0; j < r; ++j)
    for (int i = 0; i + j < r; ++i) {
      face(i, j, i + 1, j, i, j + 1);
      if (i + j + 2 <= r) face(i + 1, j, i + 1, j + 1, i, j + 1);
    }
  return worst;
}

struct LocalVertex {
  VKey key;
  Point2 u;
};

}  // namespace

Mesh tessellate(const Spline& s, const TessellateOptions& o) {
  const Domain& d = s.domain();
  const bool adaptive = o.chordal_tolerance > 0 || o.chordal_tolerance_abs > 0;
  if (!adaptive && (o.resolution < 1 || o.resolution > 4096))
    throw InvalidInput("tessellation resolution must be 1 to 4096, got " + std::to_string(o.resolution));
  if (adaptive && (o.max_resolution < 1 || o.max_resolution > 4096))
    throw InvalidInput("tessellation max_resolution must be 1 to 4096, got " + std::to_string(o.max_resolution));
  if (o.chordal_tolerance < 0 || o.chordal_tolerance_abs < 0)
    throw InvalidInput("chordal tolerance must not be negative");
  const int nt = d.triangle_count();
  const Evaluator ev(s);
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  auto corners = [&](int t) {
    const auto& tri = d.triangle(t);
    return std::array<Point2, 3>{d.vertex(tri[0]), d.vertex(tri[1]), d.vertex(tri[2])};
  };

  Mesh mesh;
  mesh.resolution.assign(nt, o.resolution);
  const double tol = o.chordal_tolerance_abs > 0 ? o.chordal_tolerance_abs : o.chordal_tolerance * detail::model_size(s);
  if (adaptive) {
    arena.execute([&] {
      tbb::parallel_for(0, nt, [&](int t) {
        int r = 1;
        while (r < o.max_resolution && chordal_deviation(ev, corners(t), r) > tol) r = std::min(2 * r, o.max_resolution);
        mesh.resolution[t] = r;
      });
    });
  }
  // Sectors of feature vertices: triangles around a vertex joined across non-feature edges.
  std::map<std::pair<int, int>, int> sector;  // (vertex, triangle) -> sector id
  if (o.split_features && !d.feature_edges().empty()) {
    for (int v = 0; v < d.vertex_count(); ++v) {
      const auto tris = d.vertex_triangles(v);
      std::vector<int> parent(tris.size());
      std::iota(parent.begin(), parent.end(), 0);
      std::function<int(int)> find = [&](int i) { return parent[i] == i ? i : parent[i] = find(parent[i]); };
      for (size_t i = 0; i < tris.size(); ++i)
        for (size_t j = i + 1; j < tris.size(); ++j) {
          // Shared edge through v?
          for (int a : d.triangle(tris[i]))
            if (a != v && std::find(d.triangle(tris[j]).begin(), d.triangle(tris[j]).end(), a) != d.triangle(tris[j]).end()) {
              const int e = d.find_edge(v, a);
              if (!d.is_feature_edge(e)) parent[find(static_cast<int>(i))] = find(static_cast<int>(j));
            }
        }
      for (size_t i = 0; i < tris.size(); ++i) sector[{v, tris[i]}] = tris[find(static_cast<int>(i))];
    }
  }

  // Adaptive mode repeats: a triangle whose faces (which next to finer neighbours are not the
  // lattice its resolution was chosen with) are still too far from the surface doubles.
  for (;;) {
  mesh.positions.clear();
  mesh.normals.clear();
  mesh.parameters.clear();
  mesh.faces.clear();
  mesh.face_triangle.clear();
  mesh.max_chordal_deviation = 0;
  // Each edge takes the finer resolution of its two triangles.
  std::vector<int> edge_res(d.edge_count(), 1);
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      int& e = edge_res[d.triangle_edge(t, k)];
      e = std::max(e, mesh.resolution[t]);
    }

  // Per triangle: local vertices and faces.
  struct Local {
    std::vector<LocalVertex> vertices;
    std::vector<std::array<int, 3>> faces;
  };
  std::vector<Local> local(nt);
  arena.execute([&] {
    tbb::parallel_for(0, nt, [&](int t) {
      const auto& tri = d.triangle(t);
      const auto c = corners(t);
      const int r = mesh.resolution[t];
      Local& L = local[t];
      auto vertex_key = [&](int k) {
        VKey key{0, tri[k], 0, 0, 0, -1};
        if (o.split_features) {
          const auto it = sector.find({tri[k], t});
          if (it != sector.end()) key.side = it->second;
        }
        return key;
      };
      // Boundary polygon: corner k, then the points of the edge to corner k+1.
      std::vector<int> boundary;
      for (int k = 0; k < 3; ++k) {
        boundary.push_back(static_cast<int>(L.vertices.size()));
        L.vertices.push_back({vertex_key(k), c[k]});
        const int a = tri[k], b = tri[(k + 1) % 3];
        const int e = d.find_edge(a, b);
        const int ke = edge_res[e];
        const int lo = std::min(a, b), hi = std::max(a, b);
        for (int i = 1; i < ke; ++i) {
          const int from_lo = a == lo ? i : ke - i;
          VKey key{1, e, from_lo, ke, 0, -1};
          if (o.split_features && d.is_feature_edge(e)) key.side = t;
          const Point2 u = d.vertex(lo) + (static_cast<double>(from_lo) / ke) * (d.vertex(hi) - d.vertex(lo));
          boundary.push_back(static_cast<int>(L.vertices.size()));
          L.vertices.push_back({key, u});
        }
      }
      // Interior lattice points (i along corner 1, j along corner 2).
      std::map<std::pair<int, int>, int> lattice;
      for (int j = 1; j < r; ++j)
        for (int i = 1; i + j < r; ++i) {
          const double l1 = static_cast<double>(i) / r, l2 = static_cast<double>(j) / r;
          lattice[{i, j}] = static_cast<int>(L.vertices.size());
          L.vertices.push_back({VKey{2, t, i, j, 0, -1}, (1 - l1 - l2) * c[0] + l1 * c[1] + l2 * c[2]});
        }
      bool regular = true;
      for (int k = 0; k < 3; ++k) regular = regular && edge_res[d.triangle_edge(t, k)] == r;
      if (regular) {
        // The lattice itself. Boundary points are found by their lattice coordinates.
        auto id = [&](int i, int j) -> int {
          if (i + j < r && i > 0 && j > 0) return lattice.at({i, j});
          // On the boundary: position along the boundary polygon (corner 0 -> 1 -> 2).
          if (j == 0) return boundary[i];                 // edge 0-1
          if (i + j == r) return boundary[r + j];         // edge 1-2
          return boundary[(3 * r - j) % (3 * r)];         // edge 2-0 (i == 0)
        };
        for (int j = 0; j < r; ++j)
          for (int i = 0; i + j < r; ++i) {
            L.faces.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
            if (i + j + 2 <= r) L.faces.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
          }
      } else {
        Cdt cdt;
        std::vector<Cdt::Vertex_handle> vh(L.vertices.size());
        for (size_t i = 0; i < L.vertices.size(); ++i) {
          vh[i] = cdt.insert(K::Point_2(L.vertices[i].u.x(), L.vertices[i].u.y()));
          vh[i]->info() = static_cast<int>(i);
        }
        for (size_t i = 0; i < boundary.size(); ++i)
          cdt.insert_constraint(vh[boundary[i]], vh[boundary[(i + 1) % boundary.size()]]);
        // Faces inside the boundary polygon: flood from outside across unconstrained edges.
        for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = 0;
        std::vector<Cdt::Face_handle> stack{cdt.infinite_face()};
        cdt.infinite_face()->info() = 1;
        while (!stack.empty()) {
          const auto f = stack.back();
          stack.pop_back();
          for (int i = 0; i < 3; ++i) {
            const auto g = f->neighbor(i);
            if (g->info() || cdt.is_constrained({f, i})) continue;
            g->info() = 1;
            stack.push_back(g);
          }
        }
        for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
          if (!f->info())
            L.faces.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
        std::sort(L.faces.begin(), L.faces.end());
      }
    });
  });

  // Global vertices, in order of first use.
  std::map<VKey, int> id;
  std::vector<std::pair<int, int>> owner;  // (triangle, local index) that evaluates the vertex
  for (int t = 0; t < nt; ++t) {
    std::vector<int> map(local[t].vertices.size());
    for (size_t i = 0; i < local[t].vertices.size(); ++i) {
      const auto [it, added] = id.try_emplace(local[t].vertices[i].key, static_cast<int>(owner.size()));
      if (added) owner.emplace_back(t, static_cast<int>(i));
      map[i] = it->second;
    }
    for (const auto& f : local[t].faces) {
      mesh.faces.push_back({map[f[0]], map[f[1]], map[f[2]]});
      mesh.face_triangle.push_back(t);
    }
  }
  const int nv = static_cast<int>(owner.size());
  mesh.positions.resize(nv);
  mesh.normals.resize(nv);
  mesh.parameters.resize(nv);
  // Copies of a vertex split along a feature share one position (evaluated once, from the
  // first copy's side); each has the normal of its own side.
  std::vector<int> base(nv);
  {
    std::map<VKey, int> first;
    for (const auto& [key, v] : id) {
      VKey b = key;
      b.side = -1;
      base[v] = first.try_emplace(b, v).first->second;
    }
    for (int v = 0; v < nv; ++v) base[v] = std::min(base[v], base[base[v]]);
  }
  auto side_eval = [&](int v, const Point2& u, Point2* used) {
    const auto [t, i] = owner[v];
    const auto c = corners(t);
    const Point2 centre = (c[0] + c[1] + c[2]) / 3.0;
    const Point2 second = (c[0] - u).norm() > (c[1] - u).norm() ? c[0] : c[1];
    return detail::evaluate_toward(ev, u, centre, second, used);
  };
  arena.execute([&] {
    tbb::parallel_for(0, nv, [&](int v) {
      if (base[v] != v) return;
      const auto [t, i] = owner[v];
      Point2 used;
      const SurfacePoint p = side_eval(v, local[t].vertices[i].u, &used);
      mesh.positions[v] = p.position;
      mesh.normals[v] = detail::unit_normal(p);
      mesh.parameters[v] = used;
    });
    tbb::parallel_for(0, nv, [&](int v) {
      if (base[v] == v) return;
      mesh.positions[v] = mesh.positions[base[v]];
      mesh.parameters[v] = mesh.parameters[base[v]];
      mesh.normals[v] = detail::unit_normal(side_eval(v, mesh.parameters[v], nullptr));
    });
  });
  // Measured deviation at face centroids and edge midpoints.
  std::vector<double> dev(mesh.faces.size(), 0.0);
  arena.execute([&] {
    tbb::parallel_for(size_t(0), mesh.faces.size(), [&](size_t f) {
      const auto& fc = mesh.faces[f];
      const auto c = corners(mesh.face_triangle[f]);
      const Point2 centre = (c[0] + c[1] + c[2]) / 3.0;
      auto surf = [&](const Point2& u) { return detail::evaluate_toward(ev, u, centre, c[0] == u ? c[1] : c[0]).position; };
      const Point2 *u[3] = {&mesh.parameters[fc[0]], &mesh.parameters[fc[1]], &mesh.parameters[fc[2]]};
      const Point3 *p[3] = {&mesh.positions[fc[0]], &mesh.positions[fc[1]], &mesh.positions[fc[2]]};
      double w = (surf((*u[0] + *u[1] + *u[2]) / 3.0) - (*p[0] + *p[1] + *p[2]) / 3.0).norm();
      for (int k = 0; k < 3; ++k)
        w = std::max(w, (surf((*u[k] + *u[(k + 1) % 3]) / 2.0) - (*p[k] + *p[(k + 1) % 3]) / 2.0).norm());
      dev[f] = w;
    });
  });
  for (double w : dev) mesh.max_chordal_deviation = std::max(mesh.max_chordal_deviation, w);
  if (!adaptive) break;
  std::vector<double> worst(nt, 0.0);
  for (size_t f = 0; f < dev.size(); ++f) worst[mesh.face_triangle[f]] = std::max(worst[mesh.face_triangle[f]], dev[f]);
  bool again = false;
  for (int t = 0; t < nt; ++t)
    if (worst[t] > tol && mesh.resolution[t] < o.max_resolution) {
      mesh.resolution[t] = std::min(2 * mesh.resolution[t], o.max_resolution);
      again = true;
    }
  if (!again) break;
  }
  return mesh;
}

}  // namespace tbs
