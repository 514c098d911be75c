#pragma once
/// \file
/// Knot conditions (METHOD.md section 3), the default knot placement and the continuity the
/// knots give across domain edges.

#include <tbs/domain.h>
#include <tbs/types.h>

#include <span>
#include <string>
#include <vector>

namespace tbs {

/// One violated knot condition.
struct KnotIssue {
  /// "finite", "orientation", "common-interior" or "boundary".
  std::string condition;
  int triangle = -1;  ///< The domain triangle concerned, or -1.
  int vertex = -1;    ///< The vertex whose knot cloud is at fault, or -1.
  Beta beta{-1, -1, -1};  ///< For "orientation": the multi-index of the degenerate X_{I,beta}.
  std::string message;    ///< A complete sentence naming all of the above.
};

/// Result of check_knot_conditions().
struct KnotCheck {
  std::vector<KnotIssue> issues;
  bool ok() const { return issues.empty(); }
  /// The first few messages, one per line. Throws nothing but std::bad_alloc.
  std::string summary(size_t max_lines = 5) const;
};

/// Checks the DMS knot conditions for degree n and knots laid out as in Spline::knots():
///  - "finite":          every knot is a finite point;
///  - "orientation":     every X_{I,beta} = [t_{i0,b0}, t_{i1,b1}, t_{i2,b2}], |beta| <= n, is
///                       non-degenerate and counter-clockwise like I;
///  - "common-interior": for every triangle I the interiors of all X_{I,beta} share a point;
///  - "boundary":        for every boundary edge (a, b), the convex hull of the knot clouds of a
///                       and b lies outside the domain's interior (its sub-knots lie strictly
///                       on the outer side of the edge, and no other triangle reaches into it).
/// \pre knots.size() == domain.vertex_count() * (degree + 1).
/// Throws nothing but std::bad_alloc: every violation, a wrong knot count included (as a
/// "finite" issue), is reported in the result.
KnotCheck check_knot_conditions(const Domain& domain, int degree, std::span<const Point2> knots);

/// The same conditions, checked only for the given triangles and their boundary edges: what
/// moving the knots of one vertex can break is confined to the triangles around it.
/// Throws nothing but std::bad_alloc; the triangle indices are not range-checked.
KnotCheck check_knot_conditions(const Domain& domain, int degree, std::span<const Point2> knots,
                                std::span<const int> triangles);

/// For each vertex, the feature line its free sub-knots t_{i,1..n-1} lie on, given as the
/// other endpoint of a feature edge at the vertex, or -1 if its sub-knots are placed freely.
/// Every feature edge is served by at least one endpoint, so n+1 knots on its line give C^0
/// there (METHOD.md section 3); then every other feature vertex serves one of its feature lines
/// too (a boundary vertex only if the ray away from the line's other end leaves the domain).
/// With one server per edge the kink fades toward the other end; with both, the whole edge can
/// carry it (a 60 degree fold is then reproduced to within 2 degrees, fit_test.cpp). A vertex
/// where lines of different directions meet serves only one of them.
/// Throws nothing but std::bad_alloc.
std::vector<int> feature_servers(const Domain& domain);

/// Traas's radius at vertex v: half the smallest height, at v, of the triangles around it.
/// Sub-knots strictly inside this circle keep the knot conditions (paper section 4.3).
/// Throws nothing; v is not range-checked.
double traas_radius(const Domain& domain, int v);

/// Default knots (Traas's scheme): the sub-knots of vertex i lie inside the circle of radius
/// r_i = half the smallest height at t_i, at between tol::kSubKnotMin and tol::kSubKnotMax
/// times r_i, in a fixed pseudo-random pattern (no three collinear in practice, so C^(n-1));
/// boundary vertices' sub-knots lie outside the domain; feature servers' free sub-knots lie on
/// their feature edge. Deterministic. The result passes check_knot_conditions().
/// Throws nothing but std::bad_alloc. \pre 1 <= degree <= tol::kMaxDegree (not checked).
std::vector<Point2> default_knots(const Domain& domain, int degree);

/// A lower bound on the continuity order across every domain edge: C^k with k = n + 1 - mu,
/// where mu is the largest number of knots on the edge's line in any knot set V_{I,beta},
/// |beta| = n, of the triangles at the edge (the last knots t_{i,n} excluded: F does not
/// depend on them). n - 1 where nothing is collinear; 0 for a feature edge with enough knots
/// on it; negative means the surface may be discontinuous there. Indexed by edge.
/// Throws nothing but std::bad_alloc. \pre 1 <= degree <= tol::kMaxDegree and the knot count
/// as for check_knot_conditions() (neither is checked).
std::vector<int> edge_continuity(const Domain& domain, int degree, std::span<const Point2> knots);

}  // namespace tbs
