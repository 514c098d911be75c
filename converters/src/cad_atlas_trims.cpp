// Region faces over an atlas (atlas_trims.h): each chart's outline becomes the trim loops of
// its face, each seam one edge shared by the two faces it glues (or twice by one face, a seam
// edge with two curves on it), each border a free edge.

#include "atlas_trims.h"

#include "trim_curve.h"

#include <tbs/atlas.h>
#include <tbs/errors.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <string>

namespace tbs::detail {

namespace {

// One stretch of a chart's outline: a seam side or a border, with its chart on the left.
struct Piece {
  std::vector<Point2> points;  // in the order the outline runs
  int chart = -1;
  int edge = -1;
  bool reversed = false;  // side b of a seam: the edge runs the other way
};

// Most segments of a seam or border in one edge: OCCT's intersections look for the points where
// a face's boundary crosses the other shape edge by edge, with a fixed number of samples per
// edge, and missed the crossings of a whole seam in one edge (no section of the egg's face at
// some planes).
constexpr size_t kMaxSegments = 16;

std::string text(const Point2& p) { return "(" + std::to_string(p.x()) + ", " + std::to_string(p.y()) + ")"; }

// Twice the signed area enclosed by a closed polyline (first point not repeated).
double twice_area(const std::vector<Point2>& loop) {
  double a = 0;
  for (size_t i = 0; i < loop.size(); ++i) {
    const Point2& p = loop[i];
    const Point2& q = loop[(i + 1) % loop.size()];
    a += p.x() * q.y() - q.x() * p.y();
  }
  return a;
}

// The point at parameter t of a polyline with parameters `at` at its points.
Point2 along(const std::vector<Point2>& line, const std::vector<double>& at, double t) {
  const size_t n = at.size();
  size_t i = static_cast<size_t>(std::upper_bound(at.begin(), at.end(), t) - at.begin());
  i = std::clamp<size_t>(i, 1, n - 1) - 1;
  const double f = std::clamp((t - at[i]) / (at[i + 1] - at[i]), 0.0, 1.0);
  return (1 - f) * line[i] + f * line[i + 1];
}

}  // namespace

void atlas_trims(const Atlas& atlas, const Evaluator& ev, const Charts& charts,
                 const std::vector<int>& face_of_chart,
                 double curve_tol, int degree, int rounds, CadRegions& out) {
  auto chart_at = [&](const Point2& u, const char* what, size_t k) {
    const int t = ev.locate(u);
    if (t < 0)
      throw Error(std::string("region faces: ") + what + " " + std::to_string(k) + " of the atlas passes outside the domain at " +
                  text(u));
    return charts.of_triangle[static_cast<size_t>(t)];
  };

  // Edges: the seams, then the borders, each cut into stretches of at most kMaxSegments
  // segments. Points where both sides stand still are dropped.
  std::vector<Piece> pieces;
  auto add_edges = [&](const std::vector<Point2>& a, const std::vector<Point2>* b, const char* what, size_t k) {
    std::vector<Point2> ka, kb;
    for (size_t i = 0; i < a.size(); ++i) {
      if (i > 0 && a[i] == ka.back() && (!b || (*b)[i] == kb.back())) continue;
      ka.push_back(a[i]);
      if (b) kb.push_back((*b)[i]);
    }
    if (ka.size() < 2) throw Error(std::string("region faces: ") + what + " " + std::to_string(k) + " of the atlas has no length");
    const size_t segments = ka.size() - 1;
    const size_t parts = (segments + kMaxSegments - 1) / kMaxSegments;
    for (size_t q = 0; q < parts; ++q) {
      const size_t i0 = segments * q / parts, i1 = segments * (q + 1) / parts;
      RegionEdge e;
      e.kind = b ? RegionEdgeKind::Seam : RegionEdgeKind::Boundary;
      e.trims[0].assign(ka.begin() + static_cast<long>(i0), ka.begin() + static_cast<long>(i1) + 1);
      if (b) e.trims[1].assign(kb.begin() + static_cast<long>(i0), kb.begin() + static_cast<long>(i1) + 1);
      const int id = static_cast<int>(out.edges.size());
      const int ca = chart_at(0.5 * (e.trims[0][0] + e.trims[0][1]), what, k);
      pieces.push_back({e.trims[0], ca, id, false});
      e.faces = {face_of_chart[static_cast<size_t>(ca)], -1};
      if (b) {
        const int cb = chart_at(0.5 * (e.trims[1][0] + e.trims[1][1]), what, k);
        pieces.push_back({{e.trims[1].rbegin(), e.trims[1].rend()}, cb, id, true});
        e.faces[1] = face_of_chart[static_cast<size_t>(cb)];
      }
      out.edges.push_back(std::move(e));
    }
  };
  for (size_t s = 0; s < atlas.seams.size(); ++s) add_edges(atlas.seams[s].a, &atlas.seams[s].b, "seam", s);
  for (size_t k = 0; k < atlas.borders.size(); ++k) add_edges(atlas.borders[k], nullptr, "border", k);

  // Vertices: the ends of the pieces; a seam's two sides end at the same vertices.
  std::map<std::pair<double, double>, int> key_id;
  std::vector<Point2> key_point;
  std::vector<int> parent;
  auto key = [&](const Point2& p) {
    const auto [it, added] = key_id.emplace(std::make_pair(p.x(), p.y()), static_cast<int>(key_point.size()));
    if (added) {
      key_point.push_back(p);
      parent.push_back(it->second);
    }
    return it->second;
  };
  auto find = [&](int x) {
    while (parent[static_cast<size_t>(x)] != x) x = parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
    return x;
  };
  for (const Piece& p : pieces) {
    key(p.points.front());
    key(p.points.back());
  }
  for (const RegionEdge& e : out.edges) {
    if (e.trims[1].empty()) continue;
    const auto& t = e.trims;
    parent[static_cast<size_t>(find(key(t[1].front())))] = find(key(t[0].front()));
    parent[static_cast<size_t>(find(key(t[1].back())))] = find(key(t[0].back()));
  }
  std::vector<int> vertex_of_root(key_point.size(), -1);
  auto vertex = [&](const Point2& p) {
    const int r = find(key(p));
    int& v = vertex_of_root[static_cast<size_t>(r)];
    if (v < 0) {
      v = static_cast<int>(out.vertex_parameters.size());
      out.vertex_parameters.push_back(key_point[static_cast<size_t>(r)]);
      out.vertex_ids.push_back(-1);
    }
    return v;
  };
  for (RegionEdge& e : out.edges) e.vertices = {vertex(e.trims[0].front()), vertex(e.trims[0].back())};

  // Loops: the pieces of each chart joined end to end (as chart_outlines() joins them), the
  // outer loop (the largest counter-clockwise one) first.
  std::multimap<std::pair<double, double>, size_t> starting;
  std::vector<char> used(pieces.size(), 0);
  std::vector<std::vector<std::pair<double, std::vector<RegionEdgeUse>>>> loops_of(out.faces.size());
  for (size_t i = 0; i < pieces.size(); ++i)
    if (pieces[i].points.front() != pieces[i].points.back())
      starting.emplace(std::make_pair(pieces[i].points.front().x(), pieces[i].points.front().y()), i);
  for (size_t i = 0; i < pieces.size(); ++i) {
    if (used[i]) continue;
    std::vector<Point2> loop;
    std::vector<RegionEdgeUse> uses;
    size_t at = i;
    for (size_t guard = 0; guard <= pieces.size(); ++guard) {
      const Piece& p = pieces[at];
      used[at] = 1;
      loop.insert(loop.end(), p.points.begin(), p.points.end() - 1);
      uses.push_back({p.edge, p.reversed});
      const Point2& end = p.points.back();
      if (end == loop.front()) break;
      size_t next = pieces.size();
      auto [lo, hi] = starting.equal_range(std::make_pair(end.x(), end.y()));
      for (auto it = lo; it != hi; ++it)
        if (!used[it->second] && pieces[it->second].chart == p.chart) {
          next = it->second;
          break;
        }
      if (next == pieces.size())
        throw Error("region faces: the outline of chart " + std::to_string(p.chart) + " stops at " + text(end) +
                    ": no seam side or border of that chart goes on from there");
      at = next;
    }
    const int face = face_of_chart[static_cast<size_t>(pieces[i].chart)];
    loops_of[static_cast<size_t>(face)].emplace_back(twice_area(loop), std::move(uses));
  }
  for (size_t f = 0; f < out.faces.size(); ++f) {
    auto& loops = loops_of[f];
    if (loops.empty()) throw Error("region faces: face " + std::to_string(f) + " has no outline in the atlas");
    const auto outer = std::max_element(loops.begin(), loops.end(),
                                        [](const auto& x, const auto& y) { return x.first < y.first; });
    if (outer->first <= 0)
      throw Error("region faces: the outline of face " + std::to_string(f) + " has no counter-clockwise loop");
    std::iter_swap(loops.begin(), outer);
    for (auto& [area, uses] : loops) out.faces[f].loops.push_back(std::move(uses));
  }

  // Vertex positions, edge curves (the middle of the two sides, parameterised by their mean
  // (u, v) arc length) and gaps.
  out.vertices.resize(out.vertex_parameters.size());
  for (size_t v = 0; v < out.vertices.size(); ++v) out.vertices[v] = ev.evaluate(out.vertex_parameters[v]).position;
  tbb::parallel_for(size_t(0), out.edges.size(), [&](size_t i) {
    RegionEdge& e = out.edges[i];
    const bool seam = !e.trims[1].empty();
    e.at.assign(e.trims[0].size(), 0.0);
    for (size_t k = 1; k < e.at.size(); ++k) {
      double len = (e.trims[0][k] - e.trims[0][k - 1]).norm();
      if (seam) len = 0.5 * (len + (e.trims[1][k] - e.trims[1][k - 1]).norm());
      e.at[k] = e.at[k - 1] + len;
    }
    e.length = e.at.back();
    auto target = [&](double t) {
      const Point3 a = ev.evaluate(along(e.trims[0], e.at, t)).position;
      if (!seam) return a;
      return Point3(0.5 * (a + ev.evaluate(along(e.trims[1], e.at, t)).position));
    };
    e.curve = fit_trim_curve(target, e.length, static_cast<int>(e.at.size()) - 1, e.at, degree, curve_tol, rounds);
    const int spans = static_cast<int>(e.curve.knots.size()) - 2 * e.curve.degree - 1;
    const int n = std::max(16, 8 * spans);
    e.gap = 0;
    for (int side = 0; side < (seam ? 2 : 1); ++side) {
      const BSplineSurface3& s = out.faces[static_cast<size_t>(e.faces[static_cast<size_t>(side)])].surface;
      for (int k = 0; k <= n; ++k) {
        const double t = e.length * k / n;
        e.gap = std::max(e.gap, (e.curve.value(t) - s.value(along(e.trims[static_cast<size_t>(side)], e.at, t))).norm());
      }
    }
  });
  out.max_gap = 0;
  for (const RegionEdge& e : out.edges) out.max_gap = std::max(out.max_gap, e.gap);
}

}  // namespace tbs::detail
