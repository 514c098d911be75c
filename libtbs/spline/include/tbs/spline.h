#pragma once
/// \file
/// The triangular B-spline (DMS spline) surface with shared control points (METHOD.md 3-4).

#include <tbs/domain.h>
#include <tbs/types.h>

#include <string>
#include <vector>

namespace tbs {

/// Number of control points of a degree-n spline with shared control points:
/// V + (n-1) E + (n-1)(n-2)/2 F. Throws nothing.
int control_point_count(const Domain& domain, int degree);

/// The canonical (triangle, beta) -> control point map: vertex points first (index = vertex),
/// then n-1 points per edge in edge order (from the smaller vertex index to the larger), then
/// the (n-1)(n-2)/2 interior points of each triangle in beta order. Entry
/// [t * beta_count(n) + beta_index(beta)] is the control point of (t, beta).
/// Throws nothing but std::bad_alloc. \pre 1 <= degree <= tol::kMaxDegree (not checked).
std::vector<int> canonical_control_point_map(const Domain& domain, int degree);

/// A DMS spline F(u) = sum_I sum_{|beta|=n} c_{I,beta} N_{I,beta}(u) over a Domain.
///
/// Knot clouds are stored flat: knot(i, k) = t_{i,k} = knots()[i * (n + 1) + k]; t_{i,0} is
/// always the domain vertex i. Control points are shared as in METHOD.md section 4: the map
/// from (triangle, beta) to a control point index is a bijection between the domain points
/// of the triangulation and the control points.
class Spline {
 public:
  Spline() = default;

  /// Builds a spline and checks its structure (sizes, finiteness, the control point map).
  /// Knot conditions are NOT checked here; see check_knot_conditions().
  /// \param degree             n, 1 <= n <= tol::kMaxDegree.
  /// \param knots              #V * (n+1) knots; knots[i*(n+1)] must equal the vertex i.
  /// \param control_points     control_point_count(domain, n) points.
  /// \param control_point_map  #F * beta_count(n) indices, see canonical_control_point_map().
  /// \throw InvalidInput naming the offending element.
  Spline(int degree, Domain domain, std::vector<Point2> knots, std::vector<Point3> control_points,
         std::vector<int> control_point_map);

  /// A spline with the canonical control point map and all control points at the origin.
  /// \throw InvalidInput if the degree is out of range or the knots do not fit the domain (as
  ///   the constructor).
  static Spline with_canonical_map(int degree, Domain domain, std::vector<Point2> knots);

  int degree() const { return degree_; }
  const Domain& domain() const { return domain_; }

  const std::vector<Point2>& knots() const { return knots_; }
  const Point2& knot(int vertex, int level) const { return knots_[vertex * (degree_ + 1) + level]; }
  int knot_id(int vertex, int level) const { return vertex * (degree_ + 1) + level; }
  /// Moves t_{vertex,level}. Level 0 moves the domain vertex too.
  /// \throw InvalidInput if p is not finite or, for level 0, a triangle around the vertex would
  ///   flip or degenerate (nothing is moved then). vertex and level are not range-checked.
  void set_knot(int vertex, int level, const Point2& p);

  int control_point_count() const { return static_cast<int>(control_points_.size()); }
  const std::vector<Point3>& control_points() const { return control_points_; }
  std::vector<Point3>& control_points() { return control_points_; }

  const std::vector<int>& control_point_map() const { return map_; }
  int control_point_index(int triangle, int beta_idx) const {
    return map_[triangle * beta_count(degree_) + beta_idx];
  }
  int control_point_index(int triangle, const Beta& b) const {
    return control_point_index(triangle, beta_index(b));
  }

  /// The blossom of the identity at (triangle, beta): (1/n) sum_j sum_{k<b_j} t_{i_j,k}.
  /// Control points c = A * blossom + b reproduce the affine map A u + b exactly.
  /// Throws nothing.
  Point2 blossom_point(int triangle, const Beta& beta) const;

 private:
  int degree_ = 0;
  Domain domain_;
  std::vector<Point2> knots_;
  std::vector<Point3> control_points_;
  std::vector<int> map_;
};

}  // namespace tbs
