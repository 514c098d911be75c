// Knot clouds (knots.h): the knot conditions and their check, Traas's default knots, the
// servers of feature edges and the continuity across domain edges.

#include <tbs/errors.h>
#include <tbs/knots.h>
#include <tbs/predicates.h>
#include <tbs/tolerances.h>

#include "box_grid.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_2.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>

namespace tbs {
namespace {

std::string knot_name(int v, int k) {
  return "t_{" + std::to_string(v) + "," + std::to_string(k) + "}";
}

std::string tri_name(const Domain& d, int t) {
  const auto& v = d.triangle(t);
  return "triangle " + std::to_string(t) + " (vertices " + std::to_string(v[0]) + " " +
         std::to_string(v[1]) + " " + std::to_string(v[2]) + ")";
}

// Clips the convex CCW polygon `poly` by the closed left half-plane of a -> b.
std::vector<Point2> clip(const std::vector<Point2>& poly, const Point2& a, const Point2& b) {
  std::vector<Point2> out;
  const size_t m = poly.size();
  for (size_t i = 0; i < m; ++i) {
    const Point2& p = poly[i];
    const Point2& q = poly[(i + 1) % m];
    const double dp = det3(a, b, p), dq = det3(a, b, q);
    if (dp >= 0) out.push_back(p);
    if ((dp > 0 && dq < 0) || (dp < 0 && dq > 0)) out.push_back(p + (q - p) * (dp / (dp - dq)));
  }
  return out;
}

double polygon_area(const std::vector<Point2>& poly) {
  double a = 0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const Point2& p = poly[i];
    const Point2& q = poly[(i + 1) % poly.size()];
    a += p.x() * q.y() - p.y() * q.x();
  }
  return 0.5 * a;
}

// Interiors of two convex CCW polygons are disjoint iff an edge of one has the other in its
// closed outer half-plane (separating axis theorem, exact predicates).
bool interiors_disjoint(const std::vector<Point2>& p, const std::vector<Point2>& q) {
  auto separates = [](const std::vector<Point2>& a, const std::vector<Point2>& b) {
    for (size_t i = 0; i < a.size(); ++i) {
      const Point2& s = a[i];
      const Point2& e = a[(i + 1) % a.size()];
      bool all_out = true;
      for (const auto& x : b)
        if (orientation(s, e, x) > 0) {
          all_out = false;
          break;
        }
      if (all_out) return true;
    }
    return false;
  };
  return separates(p, q) || separates(q, p);
}

std::vector<Point2> convex_hull(const std::vector<Point2>& pts) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::vector<K::Point_2> in, out;
  for (const auto& p : pts) in.emplace_back(p.x(), p.y());
  CGAL::convex_hull_2(in.begin(), in.end(), std::back_inserter(out));
  std::vector<Point2> h;
  for (const auto& p : out) h.emplace_back(p.x(), p.y());
  return h;
}

struct Checker {
  const Domain& d;
  int n;
  std::span<const Point2> knots;

  Checker(const Domain& dom, int deg, std::span<const Point2> k) : d(dom), n(deg), knots(k) {}

  // The triangles' grid, built on first use: only boundary edges need it, and a check of a
  // few interior triangles (the knot search's, per candidate move) should not pay for it.
  const detail::BoxGrid& tri_grid() const {
    if (!grid_built_) {
      std::vector<Box2> boxes(d.triangle_count());
      for (int t = 0; t < d.triangle_count(); ++t)
        for (int v : d.triangle(t)) boxes[t].extend(d.vertex(v));
      grid_.build(boxes, static_cast<size_t>(d.triangle_count()));
      grid_built_ = true;
    }
    return grid_;
  }

  const Point2& knot(int v, int k) const { return knots[static_cast<size_t>(v) * (n + 1) + k]; }

  // Boundary condition for boundary edge a -> b (domain on its left); appends issues.
  void check_boundary_edge(int a, int b, std::vector<KnotIssue>* issues) const {
    const int t = d.edge_triangles(d.find_edge(a, b))[0];
    bool local_ok = true;
    for (int v : {a, b})
      for (int k = 1; k <= n; ++k)
        if (orientation(d.vertex(a), d.vertex(b), knot(v, k)) >= 0) {
          local_ok = false;
          if (!issues) return;
          issues->push_back({"boundary", t, v, {-1, -1, -1},
                             "boundary condition: knot " + knot_name(v, k) + " of boundary vertex " +
                                 std::to_string(v) + " is not strictly outside boundary edge (" +
                                 std::to_string(a) + ", " + std::to_string(b) +
                                 "); sub-knots of boundary vertices must lie outside the domain"});
        }
    if (!local_ok) return;
    std::vector<Point2> cloud;
    for (int v : {a, b})
      for (int k = 0; k <= n; ++k) cloud.push_back(knot(v, k));
    const auto hull = convex_hull(cloud);
    Box2 hb;
    for (const auto& p : hull) hb.extend(p);
    int bad = -1;
    tri_grid().query(hb, [&](int s) {
      if (bad >= 0 && bad <= s) return;
      const auto& tri = d.triangle(s);
      std::vector<Point2> q{d.vertex(tri[0]), d.vertex(tri[1]), d.vertex(tri[2])};
      if (!interiors_disjoint(hull, q)) bad = s;
    });
    if (bad >= 0 && issues)
      issues->push_back({"boundary", bad, a, {-1, -1, -1},
                         "boundary condition: the hull of the knot clouds of boundary vertices " +
                             std::to_string(a) + " and " + std::to_string(b) + " reaches into " +
                             tri_name(d, bad) + "; move their sub-knots further out or closer"});
  }

  bool boundary_edge_ok(int a, int b) const {
    std::vector<KnotIssue> issues;
    check_boundary_edge(a, b, &issues);
    return issues.empty();
  }

 private:
  mutable detail::BoxGrid grid_;
  mutable bool grid_built_ = false;
};

// splitmix64: a fixed, well-mixed pseudo-random sequence, so placements are reproducible.
double hash01(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  x ^= x >> 31;
  return static_cast<double>(x >> 11) * 0x1.0p-53;
}

// Valid directions for sub-knots of boundary vertex v: strictly right of both boundary edges
// at v. Returns the bisector angle and the half-width of that open wedge.
std::pair<double, double> boundary_wedge(const Domain& d, int v) {
  const Point2 p = d.vertex(v);
  const Vector2 ein = (p - d.vertex(d.boundary_prev(v))).normalized();
  const Vector2 eout = (d.vertex(d.boundary_next(v)) - p).normalized();
  const Vector2 rin(ein.y(), -ein.x()), rout(eout.y(), -eout.x());  // right normals
  const Vector2 bis = rin + rout;
  const double cosang = std::clamp(rin.dot(rout), -1.0, 1.0);
  const double half = 0.5 * (std::numbers::pi - std::acos(cosang));
  return {std::atan2(bis.y(), bis.x()), half};
}


bool strictly_outside_wedge_ok(const Domain& d, int v, const Point2& q) {
  return orientation(d.vertex(d.boundary_prev(v)), d.vertex(v), q) < 0 &&
         orientation(d.vertex(v), d.vertex(d.boundary_next(v)), q) < 0;
}

// The point p + s (q - p) for a fraction near s, chosen so that it lies EXACTLY on the line
// pq whenever a nearby dyadic fraction makes that possible (always for coordinates on a
// dyadic grid). Exact collinearity is what makes a feature edge C^0: nearly collinear knots
// give a smooth surface with a steep, numerically fragile transition instead.
Point2 on_line(const Point2& p, const Point2& q, double s) {
  for (int bits = 3; bits <= 30; ++bits) {
    const double f = std::ldexp(std::round(std::ldexp(s, bits)), -bits);
    if (f <= 0 || std::fabs(f - s) > 0.25 * s) continue;
    const Point2 x = p + f * (q - p);
    if (orientation(p, q, x) == 0 && x != p) return x;
  }
  return p + s * (q - p);
}

}  // namespace

double traas_radius(const Domain& d, int v) {
  double r = std::numeric_limits<double>::infinity();
  for (int t : d.vertex_triangles(v)) {
    const auto& tri = d.triangle(t);
    const int k = tri[0] == v ? 0 : (tri[1] == v ? 1 : 2);
    const Point2& a = d.vertex(tri[(k + 1) % 3]);
    const Point2& b = d.vertex(tri[(k + 2) % 3]);
    const double h = std::fabs(det3(d.vertex(v), a, b)) / (b - a).norm();
    r = std::min(r, 0.5 * h);
  }
  return r;
}

std::string KnotCheck::summary(size_t max_lines) const {
  std::string s;
  for (size_t i = 0; i < issues.size() && i < max_lines; ++i) s += issues[i].message + "\n";
  if (issues.size() > max_lines)
    s += "... and " + std::to_string(issues.size() - max_lines) + " more\n";
  return s;
}

namespace {
// Orientation of every X_{I,beta} and their common interior, for triangle t.
void check_triangle(const Domain& d, int n, const Checker& c, int t, KnotCheck& check) {
    const auto& tri = d.triangle(t);
    bool oriented = true;
    for (int m = 0; m <= n && oriented; ++m)
      for (int i = 0; i < beta_count(m); ++i) {
        const Beta b = beta_at(m, i);
        const int o = orientation(c.knot(tri[0], b[0]), c.knot(tri[1], b[1]), c.knot(tri[2], b[2]));
        if (o > 0) continue;
        oriented = false;
        // Blame the knot with the highest level (the primary knots form a valid triangle).
        int j = 0;
        for (int q = 1; q < 3; ++q)
          if (b[q] > b[j]) j = q;
        check.issues.push_back(
            {"orientation", t, tri[j], b,
             tri_name(d, t) + ": X_{I,beta} for beta (" + std::to_string(b[0]) + "," +
                 std::to_string(b[1]) + "," + std::to_string(b[2]) + ") = [" +
                 knot_name(tri[0], b[0]) + ", " + knot_name(tri[1], b[1]) + ", " +
                 knot_name(tri[2], b[2]) + "] is " + (o == 0 ? "degenerate" : "clockwise") +
                 "; move " + knot_name(tri[j], b[j]) + " closer to vertex " +
                 std::to_string(tri[j])});
        break;
      }
    if (!oriented) return;
    std::vector<Point2> poly{c.knot(tri[0], 0), c.knot(tri[1], 0), c.knot(tri[2], 0)};
    const double area0 = polygon_area(poly);
    for (int m = 1; m <= n && !poly.empty(); ++m)
      for (int i = 0; i < beta_count(m) && !poly.empty(); ++i) {
        const Beta b = beta_at(m, i);
        const Point2& x0 = c.knot(tri[0], b[0]);
        const Point2& x1 = c.knot(tri[1], b[1]);
        const Point2& x2 = c.knot(tri[2], b[2]);
        poly = clip(poly, x0, x1);
        poly = clip(poly, x1, x2);
        poly = clip(poly, x2, x0);
      }
    if (poly.size() < 3 || polygon_area(poly) <= tol::kCommonInteriorRelArea * area0)
      check.issues.push_back({"common-interior", t, -1, {-1, -1, -1},
                              tri_name(d, t) +
                                  ": the triangles X_{I,beta} have no common interior point; "
                                  "keep each sub-knot within half the smallest height of the "
                                  "triangles at its vertex (Traas's scheme)"});
  }

KnotCheck check_finite(const Domain& d, int n, std::span<const Point2> knots) {
  KnotCheck check;
  if (knots.size() != static_cast<size_t>(d.vertex_count()) * (n + 1)) {
    check.issues.push_back({"finite", -1, -1, {-1, -1, -1},
                            "expected " + std::to_string(d.vertex_count() * (n + 1)) +
                                " knots, got " + std::to_string(knots.size())});
    return check;
  }
  for (int v = 0; v < d.vertex_count(); ++v)
    for (int k = 0; k <= n; ++k)
      if (!knots[static_cast<size_t>(v) * (n + 1) + k].allFinite())
        check.issues.push_back({"finite", -1, v, {-1, -1, -1},
                                "knot " + knot_name(v, k) + " is not finite"});
  return check;
}
}  // namespace

KnotCheck check_knot_conditions(const Domain& d, int n, std::span<const Point2> knots) {
  KnotCheck check = check_finite(d, n, knots);
  if (!check.ok()) return check;
  Checker c(d, n, knots);
  for (int t = 0; t < d.triangle_count(); ++t) check_triangle(d, n, c, t, check);
  for (const auto& loop : d.boundary_loops())
    for (size_t i = 0; i < loop.size(); ++i)
      c.check_boundary_edge(loop[i], loop[(i + 1) % loop.size()], &check.issues);
  return check;
}

KnotCheck check_knot_conditions(const Domain& d, int n, std::span<const Point2> knots,
                                std::span<const int> triangles) {
  KnotCheck check = check_finite(d, n, knots);
  if (!check.ok()) return check;
  Checker c(d, n, knots);
  for (int t : triangles) {
    check_triangle(d, n, c, t, check);
    const auto& tri = d.triangle(t);
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k], b = tri[(k + 1) % 3];
      if (d.is_boundary_edge(d.find_edge(a, b))) c.check_boundary_edge(a, b, &check.issues);
    }
  }
  return check;
}

std::vector<int> feature_servers(const Domain& d) {
  const int nv = d.vertex_count();
  std::vector<int> server(nv, -1);
  if (d.feature_edges().empty()) return server;
  std::vector<std::vector<int>> nbr(nv);
  for (const auto& e : d.feature_edges()) {
    nbr[e[0]].push_back(e[1]);
    nbr[e[1]].push_back(e[0]);
  }
  // Does p currently serve the feature edge (p, q)?
  auto serves = [&](int p, int q) {
    return server[p] >= 0 && orientation(d.vertex(p), d.vertex(server[p]), d.vertex(q)) == 0;
  };
  auto eligible = [&](int p, int q) {
    if (server[p] >= 0) return false;
    if (d.is_boundary_vertex(p)) {
      // Its sub-knots would go on the ray away from q, which must leave the domain.
      const Point2 out = d.vertex(p) + (d.vertex(p) - d.vertex(q));
      if (!strictly_outside_wedge_ok(d, p, out)) return false;
    }
    // Serving line pq covers every feature edge (p, r) on that line; r must not serve it too.
    for (int r : nbr[p])
      if (orientation(d.vertex(p), d.vertex(q), d.vertex(r)) == 0 && serves(r, p)) return false;
    return true;
  };

  // Walk chains from their ends (feature degree != 2), then the remaining cycles.
  std::vector<std::array<int, 2>> order;
  std::vector<char> used(d.edge_count(), 0);
  auto walk = [&](int start) {
    for (int first : nbr[start]) {
      int p = start, q = first;
      while (true) {
        const int e = d.find_edge(p, q);
        if (used[e]) break;
        used[e] = 1;
        order.push_back({p, q});
        if (nbr[q].size() != 2) break;
        const int next = nbr[q][0] == p ? nbr[q][1] : nbr[q][0];
        p = q;
        q = next;
      }
    }
  };
  for (int v = 0; v < nv; ++v)
    if (!nbr[v].empty() && nbr[v].size() != 2) walk(v);
  for (int v = 0; v < nv; ++v)
    if (!nbr[v].empty()) walk(v);

  for (const auto& [p, q] : order) {
    if (serves(p, q) || serves(q, p)) continue;
    if (eligible(p, q))
      server[p] = q;
    else if (eligible(q, p))
      server[q] = p;
  }
  // Every other feature vertex puts its sub-knots on one of its feature lines too. One server
  // per edge already makes the edge C^0, but then only the basis functions near the serving
  // end carry the kink: the crease fades toward the other end. With both ends on the line
  // the whole edge can kink (the paper's feature constraint: every feature vertex's sub-knots
  // lie on a feature edge).
  for (const auto& [p, q] : order)
    for (auto [a, b] : {std::pair{p, q}, std::pair{q, p}}) {
      if (server[a] >= 0) continue;
      if (d.is_boundary_vertex(a)) {
        const Point2 out = d.vertex(a) + (d.vertex(a) - d.vertex(b));
        if (!strictly_outside_wedge_ok(d, a, out)) continue;
      }
      server[a] = b;
    }
  return server;
}

std::vector<Point2> default_knots(const Domain& d, int n) {
  const int nv = d.vertex_count();
  std::vector<Point2> knots(static_cast<size_t>(nv) * (n + 1));
  const auto server = feature_servers(d);
  std::vector<double> radius(nv);
  for (int v = 0; v < nv; ++v) radius[v] = traas_radius(d, v);

  auto place = [&](int v, double shrink) {
    const Point2 p = d.vertex(v);
    const double r = radius[v] * shrink;
    knots[static_cast<size_t>(v) * (n + 1)] = p;
    for (int k = 1; k <= n; ++k) {
      const uint64_t seed = static_cast<uint64_t>(v) * 64 + static_cast<uint64_t>(k);
      const double h1 = hash01(2 * seed), h2 = hash01(2 * seed + 1);
      double dist = r * (tol::kSubKnotMin + (tol::kSubKnotMax - tol::kSubKnotMin) * h2);
      double angle;
      if (server[v] >= 0 && k < n) {
        const Point2 q = d.vertex(server[v]);
        const Point2 far = d.is_boundary_vertex(v) ? Point2(2.0 * p - q) : q;
        dist = r * (tol::kSubKnotMin + (tol::kSubKnotMax - tol::kSubKnotMin) * k / n);
        knots[static_cast<size_t>(v) * (n + 1) + k] = on_line(p, far, dist / (far - p).norm());
        continue;
      }
      if (d.is_boundary_vertex(v)) {
        const auto [mid, half] = boundary_wedge(d, v);
        angle = mid + 0.8 * half * (2 * h1 - 1);
      } else {
        angle = 2 * std::numbers::pi * h1;
      }
      knots[static_cast<size_t>(v) * (n + 1) + k] = p + dist * Vector2(std::cos(angle), std::sin(angle));
    }
  };
  for (int v = 0; v < nv; ++v) place(v, 1.0);

  // Boundary vertices: shrink clouds whose hull reaches into a non-adjacent part of the domain
  // (thin gaps, narrow holes) or that rounding pushed onto an edge line.
  Checker c(d, n, knots);
  std::vector<double> shrink(nv, 1.0);
  for (const auto& loop : d.boundary_loops())
    for (size_t i = 0; i < loop.size(); ++i) {
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      for (int iter = 0; iter < 60 && !c.boundary_edge_ok(a, b); ++iter) {
        for (int v : {a, b}) {
          shrink[v] *= 0.5;
          place(v, shrink[v]);
        }
      }
    }
  return knots;
}

std::vector<int> edge_continuity(const Domain& d, int n, std::span<const Point2> knots) {
  auto knot = [&](int v, int k) -> const Point2& { return knots[static_cast<size_t>(v) * (n + 1) + k]; };
  std::vector<int> result(d.edge_count(), n - 1);
  for (int e = 0; e < d.edge_count(); ++e) {
    const Point2& p = d.vertex(d.edges()[e][0]);
    const Point2& q = d.vertex(d.edges()[e][1]);
    for (int t : d.edge_triangles(e)) {
      if (t < 0) continue;
      const auto& tri = d.triangle(t);
      // on[j][l]: knot t_{i_j, l} (l < n) lies on the line pq.
      int on[3][tol::kMaxDegree + 1] = {};
      for (int j = 0; j < 3; ++j)
        for (int l = 0; l < n; ++l) on[j][l] = orientation(p, q, knot(tri[j], l)) == 0;
      int mu = 0;
      for (int i = 0; i < beta_count(n); ++i) {
        const Beta b = beta_at(n, i);
        int count = 0;
        for (int j = 0; j < 3; ++j)
          for (int l = 0; l <= std::min(b[j], n - 1); ++l) count += on[j][l];
        mu = std::max(mu, count);
      }
      // n + 2 collinear knots make single basis functions jump across the line, but not the
      // surface: with both ends of a feature edge serving it, the jumps of the basis functions
      // of the two triangles cancel (continuity_test checks value jumps below 1e-12 for random
      // control points). The bound is therefore never below C^0.
      result[e] = std::min(result[e], std::max(0, std::min(n - 1, n + 1 - mu)));
    }
  }
  return result;
}

}  // namespace tbs
