// The three surface forms as OpenCASCADE shells with shared topology (cad_shapes.h).

#include "cad_shapes.h"

#include "shell_builder.h"

#include <tbs/bezier.h>
#include <tbs/errors.h>

#include <Geom2d_BezierCurve.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_BezierCurve.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array1OfPnt.hxx>
#include <TColgp_Array1OfPnt2d.hxx>
#include <TColgp_Array2OfPnt.hxx>

#include <algorithm>
#include <cmath>
#include <map>

namespace tbs::detail {

namespace {

gp_Pnt pnt(const Point3& p) { return {p.x(), p.y(), p.z()}; }

// A full (clamped) knot vector as OCCT's distinct knots and multiplicities.
void knots_and_mults(const std::vector<double>& full, TColStd_Array1OfReal*& knots, TColStd_Array1OfInteger*& mults) {
  std::vector<double> k;
  std::vector<int> m;
  for (double x : full) {
    if (!k.empty() && x == k.back()) {
      ++m.back();
    } else {
      k.push_back(x);
      m.push_back(1);
    }
  }
  knots = new TColStd_Array1OfReal(1, static_cast<int>(k.size()));
  mults = new TColStd_Array1OfInteger(1, static_cast<int>(k.size()));
  for (size_t i = 0; i < k.size(); ++i) {
    knots->SetValue(static_cast<int>(i) + 1, k[i]);
    mults->SetValue(static_cast<int>(i) + 1, m[i]);
  }
}

Handle(Geom_BSplineCurve) occt_curve(const BSplineCurve3& c) {
  TColgp_Array1OfPnt poles(1, static_cast<int>(c.poles.size()));
  for (size_t i = 0; i < c.poles.size(); ++i) poles.SetValue(static_cast<int>(i) + 1, pnt(c.poles[i]));
  TColStd_Array1OfReal* k = nullptr;
  TColStd_Array1OfInteger* m = nullptr;
  knots_and_mults(c.knots, k, m);
  Handle(Geom_BSplineCurve) out = new Geom_BSplineCurve(poles, *k, *m, c.degree);
  delete k;
  delete m;
  return out;
}

Handle(Geom_BSplineSurface) occt_surface(const BSplineSurface3& s) {
  const int nu = s.pole_count_u(), nv = s.pole_count_v();
  TColgp_Array2OfPnt poles(1, nu, 1, nv);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) poles.SetValue(i + 1, j + 1, pnt(s.poles[static_cast<size_t>(i + nu * j)]));
  TColStd_Array1OfReal *ku = nullptr, *kv = nullptr;
  TColStd_Array1OfInteger *mu = nullptr, *mv = nullptr;
  knots_and_mults(s.knots_u, ku, mu);
  knots_and_mults(s.knots_v, kv, mv);
  Handle(Geom_BSplineSurface) out = new Geom_BSplineSurface(poles, *ku, *kv, *mu, *mv, s.degree_u, s.degree_v);
  delete ku;
  delete kv;
  delete mu;
  delete mv;
  return out;
}

// The Bezier surface of bidegree (m, m) with poles i + (m+1) j (i along s) as a B-spline.
Handle(Geom_BSplineSurface) occt_bezier_surface(std::span<const Point3> cps, int m) {
  TColgp_Array2OfPnt poles(1, m + 1, 1, m + 1);
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i <= m; ++i) poles.SetValue(i + 1, j + 1, pnt(cps[static_cast<size_t>(i + (m + 1) * j)]));
  TColStd_Array1OfReal knots(1, 2);
  knots.SetValue(1, 0.0);
  knots.SetValue(2, 1.0);
  TColStd_Array1OfInteger mults(1, 2);
  mults.SetValue(1, m + 1);
  mults.SetValue(2, m + 1);
  return new Geom_BSplineSurface(poles, knots, knots, mults, mults, m, m);
}

Handle(Geom_Curve) occt_bezier_curve(std::span<const Point3> cps) {
  TColgp_Array1OfPnt poles(1, static_cast<int>(cps.size()));
  for (size_t i = 0; i < cps.size(); ++i) poles.SetValue(static_cast<int>(i) + 1, pnt(cps[i]));
  return new Geom_BezierCurve(poles);
}

// The segment a + sigma (b - a), sigma in [0, 1], in a face's parameters.
Handle(Geom2d_Curve) segment(double ax, double ay, double bx, double by) {
  TColgp_Array1OfPnt2d poles(1, 2);
  poles.SetValue(1, gp_Pnt2d(ax, ay));
  poles.SetValue(2, gp_Pnt2d(bx, by));
  return new Geom2d_BezierCurve(poles);
}

// One piece of an edge of the patch set, as a BRep edge: edge `edge` over [s0, s1] of its
// curve's parameter.
struct Piece {
  int brep_edge = -1;
  double s0 = 0, s1 = 1;
  int v0 = -1, v1 = -1;  // BRep vertices at s0 and s1
};

// A stretch of a patch side: a piece, where it lies on the side (tau from corner k+1 to
// corner k+2), and whether its parameter runs with tau.
struct Stretch {
  const Piece* piece;
  double tau0, tau1;  // at s0 and s1
  bool with_tau() const { return tau1 > tau0; }
  double low() const { return std::min(tau0, tau1); }
};

constexpr double kSame = 1e-9;

// The straight trim from a to b (parameter t in [0, length], the arc length in (u, v)) as a
// degree-1 B-spline with a knot wherever it crosses a knot line of the face's surface. The same
// line as a Geom2d_Line, but integrators that take their Gauss points per curve span (OCCT's
// BRepGProp, which FreeCAD's Area uses) then integrate the face span by span: along a single
// span crossing dozens of surface spans, they were off by up to 0.7 % on a trimmed face.
Handle(Geom2d_Curve) trim_line(const Point2& a, const Point2& b, double length, const BSplineSurface3& s) {
  std::vector<double> ts{0.0, length};
  for (int axis = 0; axis < 2; ++axis) {
    const double d = b[axis] - a[axis];
    if (std::fabs(d) < 1e-300) continue;
    for (double k : axis == 0 ? s.knots_u : s.knots_v) {
      const double t = (k - a[axis]) / d * length;
      if (t > 0 && t < length) ts.push_back(t);
    }
  }
  std::sort(ts.begin(), ts.end());
  std::vector<double> at;
  for (double t : ts)
    if (at.empty() || t - at.back() > kSame * length) at.push_back(t);
  if (length - at.back() <= kSame * length) at.back() = length;
  else at.push_back(length);
  const int n = static_cast<int>(at.size());
  TColgp_Array1OfPnt2d poles(1, n);
  TColStd_Array1OfReal knots(1, n);
  TColStd_Array1OfInteger mults(1, n);
  for (int i = 0; i < n; ++i) {
    const double f = at[static_cast<size_t>(i)] / length;
    const Point2 p = i + 1 == n ? b : Point2(a + f * (b - a));
    poles.SetValue(i + 1, gp_Pnt2d(p.x(), p.y()));
    knots.SetValue(i + 1, at[static_cast<size_t>(i)]);
    mults.SetValue(i + 1, i == 0 || i + 1 == n ? 2 : 1);
  }
  return new Geom2d_BSplineCurve(poles, knots, mults, 1);
}

// A trim of an atlas: the polyline `line` with curve parameter at[i] at line[i], as a degree-1
// B-spline, with a knot also wherever a segment crosses a knot line of the face's surface
// (as trim_line()).
Handle(Geom2d_Curve) trim_polyline(const std::vector<Point2>& line, const std::vector<double>& at,
                                   const BSplineSurface3& s) {
  std::vector<double> ts;
  std::vector<Point2> ps;
  for (size_t i = 0; i + 1 < line.size(); ++i) {
    const Point2 &a = line[i], &b = line[i + 1];
    const double t0 = at[i], t1 = at[i + 1], span = t1 - t0;
    std::vector<double> cut;
    for (int axis = 0; axis < 2; ++axis) {
      const double d = b[axis] - a[axis];
      if (std::fabs(d) < 1e-300) continue;
      for (double k : axis == 0 ? s.knots_u : s.knots_v) {
        const double f = (k - a[axis]) / d;
        if (f > kSame && f < 1 - kSame) cut.push_back(f);
      }
    }
    std::sort(cut.begin(), cut.end());
    ts.push_back(t0);
    ps.push_back(a);
    double last = 0;
    for (double f : cut) {
      if (f - last <= kSame) continue;
      ts.push_back(t0 + f * span);
      ps.push_back(a + f * (b - a));
      last = f;
    }
  }
  ts.push_back(at.back());
  ps.push_back(line.back());
  const int n = static_cast<int>(ts.size());
  TColgp_Array1OfPnt2d poles(1, n);
  TColStd_Array1OfReal knots(1, n);
  TColStd_Array1OfInteger mults(1, n);
  for (int i = 0; i < n; ++i) {
    poles.SetValue(i + 1, gp_Pnt2d(ps[static_cast<size_t>(i)].x(), ps[static_cast<size_t>(i)].y()));
    knots.SetValue(i + 1, ts[static_cast<size_t>(i)]);
    mults.SetValue(i + 1, i == 0 || i + 1 == n ? 2 : 1);
  }
  return new Geom2d_BSplineCurve(poles, knots, mults, 1);
}

}  // namespace

ShellResult region_shell(const CadRegions& r) {
  ShellBuilder b;
  for (const Point3& v : r.vertices) b.add_vertex(pnt(v));
  std::vector<int> edge(r.edges.size());
  for (size_t i = 0; i < r.edges.size(); ++i) {
    const RegionEdge& e = r.edges[i];
    edge[i] = b.add_edge(occt_curve(e.curve), 0, e.length, e.vertices[0], e.vertices[1]);
  }
  for (const RegionFace& f : r.faces) {
    std::vector<std::vector<ShellBuilder::Use>> wires;
    for (const auto& loop : f.loops) {
      std::vector<ShellBuilder::Use> w;
      for (const RegionEdgeUse& u : loop) {
        const RegionEdge& e = r.edges[static_cast<size_t>(u.edge)];
        if (!e.at.empty()) {
          // Over an atlas: the face on the edge's left runs it forward along trims[0], the one
          // on its right backward along trims[1].
          const auto& line = e.trims[u.reversed ? 1 : 0];
          w.push_back({edge[static_cast<size_t>(u.edge)], u.reversed, trim_polyline(line, e.at, f.surface)});
          continue;
        }
        const Point2& a = r.vertex_parameters[static_cast<size_t>(e.vertices[0])];
        const Point2& c = r.vertex_parameters[static_cast<size_t>(e.vertices[1])];
        w.push_back({edge[static_cast<size_t>(u.edge)], u.reversed, trim_line(a, c, e.length, f.surface)});
      }
      wires.push_back(std::move(w));
    }
    b.add_face(occt_surface(f.surface), wires);
  }
  ShellResult out;
  out.shell = b.finish();
  out.faces = b.face_count();
  out.max_edge_tolerance = b.max_edge_tolerance();
  return out;
}

ShellResult patch_shell(const CadPatches& c, TriangleFaces faces) {
  const int m = c.degree;
  ShellBuilder b;
  for (const Point3& v : c.vertices) b.add_vertex(pnt(v));
  const bool quads = faces == TriangleFaces::Quads;
  const size_t np = c.patches.size();

  // Where each patch side's edges lie on it.
  auto tau = [&](size_t p, int side, int vertex) {
    const auto& k = c.patches[p].corners;
    const Point2& a = c.vertex_parameters[static_cast<size_t>(k[static_cast<size_t>((side + 1) % 3)])];
    const Point2& d = c.vertex_parameters[static_cast<size_t>(k[static_cast<size_t>((side + 2) % 3)])];
    return (c.vertex_parameters[static_cast<size_t>(vertex)] - a).dot(d - a) / (d - a).squaredNorm();
  };
  // Quads cut every patch side at its midpoint: the edges that hold such a midpoint inside
  // are split there (at the same point for both patches that use them).
  // The edge uses of each patch side (boundaries[p] runs counter-clockwise from corner 1).
  std::vector<std::array<std::vector<CadEdgeUse>, 3>> side_uses(np);
  for (size_t p = 0; p < np; ++p) {
    int side = 0;
    for (const CadEdgeUse& u : c.boundaries[p]) {
      if (side > 2) throw Error("CAD export: the boundary of patch " + std::to_string(p) + " does not close");
      side_uses[p][static_cast<size_t>(side)].push_back(u);
      const CadEdge& e = c.edges[static_cast<size_t>(u.edge)];
      const int end = u.reversed ? e.vertices[0] : e.vertices[1];
      if (end == c.patches[p].corners[static_cast<size_t>((side + 2) % 3)]) ++side;
    }
    if (side != 3) throw Error("CAD export: the boundary of patch " + std::to_string(p) + " does not close");
  }
  std::vector<std::vector<double>> cuts(c.edges.size());
  if (quads) {
    for (size_t p = 0; p < np; ++p)
      for (int side = 0; side < 3; ++side)
        for (const CadEdgeUse& u : side_uses[p][static_cast<size_t>(side)]) {
          const CadEdge& e = c.edges[static_cast<size_t>(u.edge)];
          const double t0 = tau(p, side, e.vertices[0]), t1 = tau(p, side, e.vertices[1]);
          if (std::min(t0, t1) < 0.5 - kSame && std::max(t0, t1) > 0.5 + kSame)
            cuts[static_cast<size_t>(u.edge)].push_back((0.5 - t0) / (t1 - t0));
        }
  }
  std::vector<std::vector<Piece>> pieces(c.edges.size());
  for (size_t i = 0; i < c.edges.size(); ++i) {
    const CadEdge& e = c.edges[i];
    std::vector<double> s = cuts[i];
    std::sort(s.begin(), s.end());
    std::vector<double> at{0.0};
    for (double x : s)
      if (x - at.back() > kSame && 1 - x > kSame) at.push_back(x);
    at.push_back(1.0);
    const Handle(Geom_Curve) curve = occt_bezier_curve(e.control_points);
    int prev = e.vertices[0];
    for (size_t k = 0; k + 1 < at.size(); ++k) {
      const int next = k + 2 == at.size() ? e.vertices[1] : b.add_vertex(pnt(bezier_curve_value(e.control_points, at[k + 1])));
      Piece piece;
      piece.s0 = at[k];
      piece.s1 = at[k + 1];
      piece.v0 = prev;
      piece.v1 = next;
      piece.brep_edge = b.add_edge(curve, piece.s0, piece.s1, prev, next);
      pieces[i].push_back(piece);
      prev = next;
    }
  }

  for (size_t p = 0; p < np; ++p) {
    // The stretches of each side, in the order of tau.
    std::array<std::vector<Stretch>, 3> sides;
    for (int side = 0; side < 3; ++side) {
      for (const CadEdgeUse& u : side_uses[p][static_cast<size_t>(side)]) {
        const CadEdge& e = c.edges[static_cast<size_t>(u.edge)];
        const double t0 = tau(p, side, e.vertices[0]), t1 = tau(p, side, e.vertices[1]);
        for (const Piece& pc : pieces[static_cast<size_t>(u.edge)])
          sides[static_cast<size_t>(side)].push_back({&pc, t0 + pc.s0 * (t1 - t0), t0 + pc.s1 * (t1 - t0)});
      }
      std::sort(sides[static_cast<size_t>(side)].begin(), sides[static_cast<size_t>(side)].end(),
                [](const Stretch& x, const Stretch& y) { return x.low() < y.low(); });
    }
    const std::span<const Point3> net = c.net(static_cast<int>(p));
    // A stretch's pcurve, with the face's point at tau given by `at`.
    auto use = [&](const Stretch& st, auto at) {
      const auto [ax, ay] = at(st.tau0 - st.piece->s0 * (st.tau1 - st.tau0) / (st.piece->s1 - st.piece->s0));
      const auto [bx, by] = at(st.tau0 + (1 - st.piece->s0) * (st.tau1 - st.tau0) / (st.piece->s1 - st.piece->s0));
      return ShellBuilder::Use{st.piece->brep_edge, !st.with_tau(), segment(ax, ay, bx, by)};
    };
    if (!quads) {
      const std::vector<Point3> q = bezier_triangle_to_collapsed_quad(net, m);
      // (s, t) -> barycentric (1-s, s(1-t), st): side 2 is t = 0, side 0 is s = 1, side 1 is
      // t = 1 (s from 1 to 0), and s = 0 collapses to corner 0.
      std::vector<ShellBuilder::Use> w;
      for (const Stretch& st : sides[2]) w.push_back(use(st, [](double t) { return std::pair{t, 0.0}; }));
      for (const Stretch& st : sides[0]) w.push_back(use(st, [](double t) { return std::pair{1.0, t}; }));
      for (const Stretch& st : sides[1]) w.push_back(use(st, [](double t) { return std::pair{1 - t, 1.0}; }));
      const int pole = b.add_degenerate_edge(c.patches[p].corners[0], 0, 1);
      w.push_back({pole, false, segment(0, 1, 0, 0)});
      b.add_face(occt_bezier_surface(q, m), {w});
      continue;
    }
    const auto q = bezier_triangle_to_quads(net, m);
    const int centre = b.add_vertex(pnt(q[0][static_cast<size_t>(m + (m + 1) * m)]));
    // The vertex at the midpoint of each side.
    std::array<int, 3> mid{};
    for (int side = 0; side < 3; ++side) {
      mid[static_cast<size_t>(side)] = -1;
      for (const Stretch& st : sides[static_cast<size_t>(side)]) {
        if (std::fabs(st.tau0 - 0.5) < kSame) mid[static_cast<size_t>(side)] = st.piece->v0;
        if (std::fabs(st.tau1 - 0.5) < kSame) mid[static_cast<size_t>(side)] = st.piece->v1;
      }
      if (mid[static_cast<size_t>(side)] < 0)
        throw Error("CAD export: patch " + std::to_string(p) + " has no vertex at the middle of a side");
    }
    // Inner edge k: from the middle of the side between corners k and k+1 (side k+2) to the
    // centroid, along s = 1 of quad k.
    std::array<int, 3> inner{};
    for (int k = 0; k < 3; ++k) {
      std::vector<Point3> cps;
      for (int j = 0; j <= m; ++j) cps.push_back(q[static_cast<size_t>(k)][static_cast<size_t>(m + (m + 1) * j)]);
      inner[static_cast<size_t>(k)] = b.add_edge(occt_bezier_curve(cps), 0, 1, mid[static_cast<size_t>((k + 2) % 3)], centre);
    }
    for (int k = 0; k < 3; ++k) {
      std::vector<ShellBuilder::Use> w;
      // t = 0: corner k to the middle of side k+2 (tau 0 .. 1/2, s = 2 tau).
      for (const Stretch& st : sides[static_cast<size_t>((k + 2) % 3)])
        if (st.low() < 0.5 - kSame) w.push_back(use(st, [](double t) { return std::pair{2 * t, 0.0}; }));
      w.push_back({inner[static_cast<size_t>(k)], false, segment(1, 0, 1, 1)});
      w.push_back({inner[static_cast<size_t>((k + 2) % 3)], true, segment(0, 1, 1, 1)});
      // s = 0: the middle of side k+1 to corner k (tau 1/2 .. 1, t = 2 - 2 tau).
      for (const Stretch& st : sides[static_cast<size_t>((k + 1) % 3)])
        if (st.low() >= 0.5 - kSame) w.push_back(use(st, [](double t) { return std::pair{0.0, 2 - 2 * t}; }));
      b.add_face(occt_bezier_surface(q[static_cast<size_t>(k)], m), {w});
    }
  }
  ShellResult out;
  out.shell = b.finish();
  out.faces = b.face_count();
  out.max_edge_tolerance = b.max_edge_tolerance();
  return out;
}

CadPatches patches_of(const Extraction& x) {
  const int m = x.degree;
  CadPatches c;
  c.degree = m;
  c.vertex_parameters = x.vertices;
  c.vertices.assign(x.vertices.size(), Point3::Zero());
  c.control_points = x.control_points;
  std::vector<char> placed(x.vertices.size(), 0);
  std::map<std::pair<int, int>, int> edge_of;
  for (size_t p = 0; p < x.pieces.size(); ++p) {
    const BezierPiece& piece = x.pieces[p];
    c.patches.push_back({piece.triangle, 0, piece.corners});
    const std::span<const Point3> net = x.net(static_cast<int>(p));
    for (int k = 0; k < 3; ++k) {
      Beta corner{0, 0, 0};
      corner[static_cast<size_t>(k)] = m;
      const int v = piece.corners[static_cast<size_t>(k)];
      if (!placed[static_cast<size_t>(v)]) {
        c.vertices[static_cast<size_t>(v)] = net[static_cast<size_t>(beta_index(corner))];
        placed[static_cast<size_t>(v)] = 1;
      }
    }
    std::vector<CadEdgeUse> sides;
    for (int k = 0; k < 3; ++k) {
      const int a = piece.corners[static_cast<size_t>((k + 1) % 3)], b = piece.corners[static_cast<size_t>((k + 2) % 3)];
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = edge_of.find(key);
      if (it == edge_of.end()) {
        it = edge_of.emplace(key, static_cast<int>(c.edges.size())).first;
        CadEdge e;
        e.vertices = {a, b};
        e.control_points = bezier_side(net, m, k);
        c.edges.push_back(std::move(e));
      }
      sides.push_back({it->second, c.edges[static_cast<size_t>(it->second)].vertices[0] != a});
    }
    c.boundaries.push_back(std::move(sides));
  }
  return c;
}

}  // namespace tbs::detail
