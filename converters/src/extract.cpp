#include <tbs/bezier.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/extract.h>
#include <tbs/predicates.h>

#include "side_eval.h"

#include <CGAL/Arr_segment_traits_2.h>
#include <CGAL/Arrangement_2.h>
#include <CGAL/Box_intersection_d/Box_with_info_d.h>
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>

#include <Eigen/LU>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <map>
#include <set>

namespace tbs {

namespace {

using K = CGAL::Exact_predicates_exact_constructions_kernel;
using EPoint = K::Point_2;
using ESegment = K::Segment_2;
using Arrangement = CGAL::Arrangement_2<CGAL::Arr_segment_traits_2<K>>;
using Fb = CGAL::Triangulation_face_base_with_info_2<int, K, CGAL::Constrained_triangulation_face_base_2<K>>;
using Tds = CGAL::Triangulation_data_structure_2<CGAL::Triangulation_vertex_base_2<K>, Fb>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<K, Tds>;

EPoint exact_point(const Point2& p) { return {p.x(), p.y()}; }

// Rounds an exact point from its exact value, so the same point rounds the same way whichever
// construction produced it.
Point2 to_double(const EPoint& p) {
  return {CGAL::to_double(CGAL::exact(p.x())), CGAL::to_double(CGAL::exact(p.y()))};
}

bool exact_less(const EPoint& a, const EPoint& b) { return CGAL::compare_xy(a, b) == CGAL::SMALLER; }

// The segments between knots that can bound a polynomial piece: pairs of knots of one knot set
// V_{J,g}, |g| = n-1, of the triangles J given (as knot ids, smaller first, deduplicated).
std::vector<std::array<int, 2>> knot_pairs(const Spline& s, std::span<const int> triangles) {
  const int n = s.degree();
  std::set<std::array<int, 2>> pairs;
  auto add = [&](int a, int b) {
    if (a == b) return;
    if (s.knots()[a] == s.knots()[b]) return;
    pairs.insert({std::min(a, b), std::max(a, b)});
  };
  for (int t : triangles) {
    const auto& tri = s.domain().triangle(t);
    for (int j = 0; j < 3; ++j) {
      // Knots of one vertex up to level n-1 meet in the set with g_j = n-1.
      for (int k = 0; k < n; ++k)
        for (int l = k + 1; l < n; ++l) add(s.knot_id(tri[j], k), s.knot_id(tri[j], l));
      // Knots of two vertices meet when their levels sum to at most n-1.
      const int o = tri[(j + 1) % 3];
      for (int k = 0; k < n; ++k)
        for (int l = 0; k + l < n; ++l) add(s.knot_id(tri[j], k), s.knot_id(o, l));
    }
  }
  return {pairs.begin(), pairs.end()};
}

struct TriangleWork {
  std::vector<ESegment> segments;             // knot segments clipped to the triangle
  std::array<std::vector<EPoint>, 3> on_edge;  // their endpoints on each edge
  std::vector<std::array<Point2, 3>> pieces;  // output, counter-clockwise
  std::vector<int> piece_cell;
  int cells = 0;
};

void clip_segments(const Spline& s, int t, std::span<const int> near, TriangleWork& w) {
  const Domain& d = s.domain();
  const auto& tri = d.triangle(t);
  const EPoint c[3] = {exact_point(d.vertex(tri[0])), exact_point(d.vertex(tri[1])),
                       exact_point(d.vertex(tri[2]))};
  const K::Triangle_2 et(c[0], c[1], c[2]);
  const CGAL::Bbox_2 tb = et.bbox();
  for (const auto& [a, b] : knot_pairs(s, near)) {
    const Point2 &pa = s.knots()[a], &pb = s.knots()[b];
    const CGAL::Bbox_2 sb(std::min(pa.x(), pb.x()), std::min(pa.y(), pb.y()),
                          std::max(pa.x(), pb.x()), std::max(pa.y(), pb.y()));
    if (!CGAL::do_overlap(sb, tb)) continue;
    const ESegment seg(exact_point(pa), exact_point(pb));
    const auto hit = CGAL::intersection(seg, et);
    if (!hit) continue;
    const ESegment* clipped = boost::get<ESegment>(&*hit);
    if (!clipped || clipped->is_degenerate()) continue;
    w.segments.push_back(*clipped);
    for (const EPoint& p : {clipped->source(), clipped->target()})
      for (int k = 0; k < 3; ++k)
        if (CGAL::collinear(c[(k + 1) % 3], c[(k + 2) % 3], p)) w.on_edge[k].push_back(p);
  }
}

void build_pieces(const Spline& s, int t, const std::array<std::vector<EPoint>, 3>& edge_points,
                  TriangleWork& w) {
  const Domain& d = s.domain();
  const auto& tri = d.triangle(t);
  const EPoint c[3] = {exact_point(d.vertex(tri[0])), exact_point(d.vertex(tri[1])),
                       exact_point(d.vertex(tri[2]))};
  using Curve = Arrangement::Geometry_traits_2::Curve_2;
  std::vector<Curve> curves;
  curves.reserve(w.segments.size() + 3);
  for (const auto& seg : w.segments) curves.emplace_back(seg);
  for (int k = 0; k < 3; ++k) curves.emplace_back(ESegment(c[k], c[(k + 1) % 3]));
  Arrangement arr;
  CGAL::insert(arr, curves.begin(), curves.end());
  // Points where the neighbour's segments reach the shared edge: the pieces on both sides
  // then have the same corners along it.
  for (int k = 0; k < 3; ++k)
    for (const EPoint& p : edge_points[k]) CGAL::insert_point(arr, p);

  Cdt cdt;
  for (auto v = arr.vertices_begin(); v != arr.vertices_end(); ++v) cdt.insert(v->point());
  for (auto e = arr.edges_begin(); e != arr.edges_end(); ++e)
    cdt.insert_constraint(e->source()->point(), e->target()->point());
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = -1;
  // Cells = the faces connected across unconstrained edges.
  int cells = 0;
  std::vector<Cdt::Face_handle> stack;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    if (f->info() >= 0) continue;
    f->info() = cells;
    stack.push_back(f);
    while (!stack.empty()) {
      const Cdt::Face_handle g = stack.back();
      stack.pop_back();
      for (int i = 0; i < 3; ++i) {
        const Cdt::Face_handle h = g->neighbor(i);
        if (cdt.is_infinite(h) || h->info() >= 0 || cdt.is_constrained({g, i})) continue;
        h->info() = cells;
        stack.push_back(h);
      }
    }
    ++cells;
  }
  const int bounded = static_cast<int>(arr.number_of_faces() - arr.number_of_unbounded_faces());
  if (cells != bounded)
    throw Error("extract_bezier: triangle " + std::to_string(t) + ": " +
                std::to_string(cells) + " triangulated cells, but the arrangement has " +
                std::to_string(bounded));
  w.cells = cells;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    w.pieces.push_back({to_double(f->vertex(0)->point()), to_double(f->vertex(1)->point()),
                        to_double(f->vertex(2)->point())});
    w.piece_cell.push_back(f->info());
  }
  // Deterministic order: by cell, then by corners.
  std::vector<int> order(w.pieces.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  auto key = [&](int i) {
    const auto& p = w.pieces[i];
    return std::tuple(w.piece_cell[i], p[0].x(), p[0].y(), p[1].x(), p[1].y());
  };
  std::sort(order.begin(), order.end(), [&](int a, int b) { return key(a) < key(b); });
  std::vector<std::array<Point2, 3>> pieces;
  std::vector<int> cell;
  for (int i : order) pieces.push_back(w.pieces[i]), cell.push_back(w.piece_cell[i]);
  w.pieces.swap(pieces);
  w.piece_cell.swap(cell);
  w.segments.clear();
  w.segments.shrink_to_fit();
}

// Triangles J whose knots' bounding box overlaps triangle D's box, for every D.
std::vector<std::vector<int>> nearby_triangles(const Spline& s) {
  const Domain& d = s.domain();
  const int n = s.degree();
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 2, int>;
  std::vector<Box> knot_boxes, tri_boxes;
  for (int t = 0; t < d.triangle_count(); ++t) {
    CGAL::Bbox_2 kb, tb;
    bool first = true;
    for (int v : d.triangle(t)) {
      const Point2& p = d.vertex(v);
      const CGAL::Bbox_2 pb(p.x(), p.y(), p.x(), p.y());
      tb = first ? pb : tb + pb;
      for (int l = 0; l < std::max(n, 1); ++l) {
        const Point2& k = s.knot(v, l);
        const CGAL::Bbox_2 b(k.x(), k.y(), k.x(), k.y());
        kb = first ? b : kb + b;
        first = false;
      }
    }
    knot_boxes.emplace_back(kb, t);
    tri_boxes.emplace_back(tb, t);
  }
  std::vector<std::vector<int>> near(d.triangle_count());
  CGAL::box_intersection_d(
      knot_boxes.begin(), knot_boxes.end(), tri_boxes.begin(), tri_boxes.end(),
      [&](const Box& k, const Box& t) { near[t.info()].push_back(k.info()); },
      std::ptrdiff_t(16), CGAL::Box_intersection_d::CLOSED);
  for (auto& v : near) std::sort(v.begin(), v.end());
  return near;
}

// Interpolation matrices for the Bezier net of a degree-n polynomial from its values at the
// domain points i/n of a triangle: boundary control points first (from the edge values),
// then the interior ones.
struct NetSolver {
  int n;
  Eigen::MatrixXd edge_inv;       // (n-1) x (n-1): interior edge values -> edge control points
  Eigen::VectorXd edge_b0, edge_bn;  // B_0(k/n), B_n(k/n), k = 1..n-1
  std::vector<int> inner, outer;  // beta indices of interior / boundary control points
  Eigen::MatrixXd inner_inv, inner_outer;

  explicit NetSolver(int degree) : n(degree) {
    std::vector<double> b(n + 1);
    if (n >= 2) {
      Eigen::MatrixXd a(n - 1, n - 1);
      edge_b0.resize(n - 1);
      edge_bn.resize(n - 1);
      for (int k = 1; k < n; ++k) {
        bernstein_curve_local(n, static_cast<double>(k) / n, b);
        for (int j = 1; j < n; ++j) a(k - 1, j - 1) = b[j];
        edge_b0[k - 1] = b[0];
        edge_bn[k - 1] = b[n];
      }
      edge_inv = a.inverse();
    }
    for (int i = 0; i < beta_count(n); ++i) {
      const Beta g = beta_at(n, i);
      (g[0] > 0 && g[1] > 0 && g[2] > 0 ? inner : outer).push_back(i);
    }
    if (!inner.empty()) {
      const int ni = static_cast<int>(inner.size()), no = static_cast<int>(outer.size());
      Eigen::MatrixXd mii(ni, ni), mio(ni, no);
      std::vector<double> bt(beta_count(n));
      for (int p = 0; p < ni; ++p) {
        const Beta g = beta_at(n, inner[p]);
        bernstein_triangle_local(n, Bary(g[0], g[1], g[2]) / n, bt);
        for (int q = 0; q < ni; ++q) mii(p, q) = bt[inner[q]];
        for (int q = 0; q < no; ++q) mio(p, q) = bt[outer[q]];
      }
      inner_inv = mii.inverse();
      inner_outer = mio;
    }
  }
  static void bernstein_curve_local(int m, double t, std::vector<double>& out) {
    out.assign(m + 1, 0.0);
    bernstein_curve(m, t, out);
  }
  static void bernstein_triangle_local(int m, const Bary& b, std::vector<double>& out) {
    out.assign(beta_count(m), 0.0);
    bernstein_triangle(m, b, out);
  }
};

}  // namespace

Extraction extract_bezier(const Spline& s, const ExtractOptions& options) {
  const Domain& d = s.domain();
  if (d.triangle_count() == 0) throw InvalidInput("extract_bezier: the spline has no triangles");
  const int n = s.degree();
  const int nt = d.triangle_count();
  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);

  const auto near = nearby_triangles(s);
  std::vector<TriangleWork> work(nt);
  arena.execute([&] {
    tbb::parallel_for(0, nt, [&](int t) { clip_segments(s, t, near[t], work[t]); });
  });
  // Every domain edge gets the union of the points both of its triangles put on it.
  std::vector<std::vector<EPoint>> edge_points(d.edge_count());
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      auto& dst = edge_points[d.triangle_edge(t, k)];
      dst.insert(dst.end(), work[t].on_edge[k].begin(), work[t].on_edge[k].end());
    }
  for (auto& pts : edge_points) {
    std::sort(pts.begin(), pts.end(), exact_less);
    pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  }
  arena.execute([&] {
    tbb::parallel_for(0, nt, [&](int t) {
      std::array<std::vector<EPoint>, 3> mine;
      for (int k = 0; k < 3; ++k) mine[k] = edge_points[d.triangle_edge(t, k)];
      build_pieces(s, t, mine, work[t]);
    });
  });

  Extraction out;
  out.degree = n;
  std::map<std::pair<double, double>, int> vertex_id;
  out.piece_start.push_back(0);
  for (int t = 0; t < nt; ++t) {
    out.cells.push_back(work[t].cells);
    for (size_t i = 0; i < work[t].pieces.size(); ++i) {
      BezierPiece piece;
      piece.triangle = t;
      piece.cell = work[t].piece_cell[i];
      for (int j = 0; j < 3; ++j) {
        const Point2& p = work[t].pieces[i][j];
        const auto [it, added] =
            vertex_id.try_emplace({p.x(), p.y()}, static_cast<int>(out.vertices.size()));
        if (added) out.vertices.push_back(p);
        piece.corners[j] = it->second;
      }
      out.pieces.push_back(piece);
    }
    out.piece_start.push_back(static_cast<int>(out.pieces.size()));
    work[t] = TriangleWork{};
  }

  // Control points. Values at vertices and along edges are computed once, from the first piece
  // that has them, and copied into every piece that shares them: shared boundaries are equal
  // bit for bit.
  const Evaluator ev(s);
  const int np = static_cast<int>(out.pieces.size());
  const int nv = static_cast<int>(out.vertices.size());
  auto corner = [&](int p, int j) -> const Point2& { return out.vertices[out.pieces[p].corners[j]]; };
  // A point of piece p evaluated on p's side.
  auto eval_in = [&](int p, const Point2& u) {
    return detail::evaluate_in_triangle(ev, {corner(p, 0), corner(p, 1), corner(p, 2)}, u).position;
  };

  std::vector<int> vertex_piece(nv, -1);
  std::map<std::pair<int, int>, int> edge_piece;  // (lower, higher vertex) -> first piece
  for (int p = 0; p < np; ++p)
    for (int j = 0; j < 3; ++j) {
      const int a = out.pieces[p].corners[j];
      if (vertex_piece[a] < 0) vertex_piece[a] = p;
      const int b = out.pieces[p].corners[(j + 1) % 3];
      edge_piece.try_emplace({std::min(a, b), std::max(a, b)}, p);
    }
  std::vector<Point3> vertex_value(nv);
  arena.execute([&] {
    tbb::parallel_for(0, nv, [&](int v) {
      if (vertex_piece[v] >= 0) vertex_value[v] = eval_in(vertex_piece[v], out.vertices[v]);
    });
  });

  const NetSolver solver(n);
  std::vector<std::pair<std::pair<int, int>, int>> edges(edge_piece.begin(), edge_piece.end());
  // n-1 inner control points per edge, from the lower vertex to the higher.
  std::vector<Point3> edge_cps(edges.size() * static_cast<size_t>(std::max(n - 1, 0)));
  if (n >= 2) {
    arena.execute([&] {
      tbb::parallel_for(0, static_cast<int>(edges.size()), [&](int e) {
        const auto [a, b] = edges[e].first;
        const int p = edges[e].second;
        Eigen::MatrixXd f(n - 1, 3);
        for (int k = 1; k < n; ++k) {
          const Point2 u = out.vertices[a] + (static_cast<double>(k) / n) *
                                                 (out.vertices[b] - out.vertices[a]);
          const Point3 v = eval_in(p, u) - solver.edge_b0[k - 1] * vertex_value[a] -
                           solver.edge_bn[k - 1] * vertex_value[b];
          f.row(k - 1) = v.transpose();
        }
        const Eigen::MatrixXd c = solver.edge_inv * f;
        for (int k = 0; k < n - 1; ++k) edge_cps[static_cast<size_t>(e) * (n - 1) + k] = c.row(k).transpose();
      });
    });
  }
  std::map<std::pair<int, int>, int> edge_index;
  for (size_t e = 0; e < edges.size(); ++e) edge_index[edges[e].first] = static_cast<int>(e);

  const int nb = beta_count(n);
  out.control_points.resize(static_cast<size_t>(np) * nb);
  arena.execute([&] {
    tbb::parallel_for(0, np, [&](int p) {
      Point3* net = out.control_points.data() + static_cast<size_t>(p) * nb;
      const auto& cs = out.pieces[p].corners;
      for (int j = 0; j < 3; ++j) {
        Beta g{0, 0, 0};
        g[j] = n;
        net[beta_index(g)] = vertex_value[cs[j]];
      }
      for (int k = 0; k < 3 && n >= 2; ++k) {
        const int a = cs[(k + 1) % 3], b = cs[(k + 2) % 3];
        const int e = edge_index.at({std::min(a, b), std::max(a, b)});
        const auto side = bezier_side_indices(n, k);  // from corner k+1 to corner k+2
        for (int i = 1; i < n; ++i) {
          const int from_lower = a < b ? i : n - i;
          net[side[i]] = edge_cps[static_cast<size_t>(e) * (n - 1) + from_lower - 1];
        }
      }
      if (!solver.inner.empty()) {
        const int ni = static_cast<int>(solver.inner.size());
        Eigen::MatrixXd f(ni, 3), known(solver.outer.size(), 3);
        for (size_t q = 0; q < solver.outer.size(); ++q) known.row(q) = net[solver.outer[q]].transpose();
        for (int q = 0; q < ni; ++q) {
          const Beta g = beta_at(n, solver.inner[q]);
          const Point2 u = (g[0] * corner(p, 0) + g[1] * corner(p, 1) + g[2] * corner(p, 2)) / n;
          f.row(q) = eval_in(p, u).transpose();
        }
        const Eigen::MatrixXd c = solver.inner_inv * (f - solver.inner_outer * known);
        for (int q = 0; q < ni; ++q) net[solver.inner[q]] = c.row(q).transpose();
      }
    });
  });
  return out;
}

}  // namespace tbs
