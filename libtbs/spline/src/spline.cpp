// tbs::Spline (spline.h): degree, domain, knots and the shared control points, with the
// control-point map and the blossom points of each triangle.

#include <tbs/errors.h>
#include <tbs/spline.h>
#include <tbs/tolerances.h>

#include <string>

namespace tbs {
namespace {

std::string beta_str(const Beta& b) {
  return "(" + std::to_string(b[0]) + "," + std::to_string(b[1]) + "," + std::to_string(b[2]) + ")";
}

// Canonical domain point index of (t, beta), numbered as in canonical_control_point_map().
int domain_point(const Domain& d, int n, int t, const Beta& b) {
  const auto& tri = d.triangle(t);
  for (int j = 0; j < 3; ++j)
    if (b[j] == n) return tri[j];
  for (int k = 0; k < 3; ++k) {
    if (b[k] != 0) continue;
    // Edge opposite corner k, between corners k+1 and k+2.
    const int a = tri[(k + 1) % 3], c = tri[(k + 2) % 3];
    const int wa = b[(k + 1) % 3], wc = b[(k + 2) % 3];
    const int on_hi = a > c ? wa : wc;  // weight on the larger vertex index: 1..n-1
    const int e = d.triangle_edge(t, k);
    return d.vertex_count() + e * (n - 1) + (on_hi - 1);
  }
  // Interior: betas with all entries >= 1, i.e. beta - (1,1,1) with |.| = n - 3.
  const int inner = beta_index(Beta{b[0] - 1, b[1] - 1, b[2] - 1});
  return d.vertex_count() + d.edge_count() * (n - 1) + t * ((n - 1) * (n - 2) / 2) + inner;
}

}  // namespace

int control_point_count(const Domain& d, int n) {
  return d.vertex_count() + (n - 1) * d.edge_count() + (n - 1) * (n - 2) / 2 * d.triangle_count();
}

std::vector<int> canonical_control_point_map(const Domain& d, int n) {
  const int nb = beta_count(n);
  std::vector<int> map(static_cast<size_t>(d.triangle_count()) * nb);
  for (int t = 0; t < d.triangle_count(); ++t)
    for (int i = 0; i < nb; ++i) map[static_cast<size_t>(t) * nb + i] = domain_point(d, n, t, beta_at(n, i));
  return map;
}

Spline::Spline(int degree, Domain domain, std::vector<Point2> knots,
               std::vector<Point3> control_points, std::vector<int> control_point_map)
    : degree_(degree),
      domain_(std::move(domain)),
      knots_(std::move(knots)),
      control_points_(std::move(control_points)),
      map_(std::move(control_point_map)) {
  const int n = degree_;
  if (n < 1 || n > tol::kMaxDegree)
    throw InvalidInput("degree " + std::to_string(n) + " is not supported (1 to " +
                       std::to_string(tol::kMaxDegree) + ")");
  const size_t nv = domain_.vertex_count();
  if (knots_.size() != nv * (n + 1))
    throw InvalidInput("expected " + std::to_string(nv * (n + 1)) + " knots (" +
                       std::to_string(nv) + " vertices x " + std::to_string(n + 1) + "), got " +
                       std::to_string(knots_.size()));
  for (size_t i = 0; i < nv; ++i) {
    for (int k = 0; k <= n; ++k)
      if (!knots_[i * (n + 1) + k].allFinite())
        throw InvalidInput("knot t_{" + std::to_string(i) + "," + std::to_string(k) +
                           "} is not finite");
    if (knots_[i * (n + 1)] != domain_.vertex(static_cast<int>(i)))
      throw InvalidInput("knot t_{" + std::to_string(i) + ",0} differs from domain vertex " +
                         std::to_string(i) + "; the primary knot is the vertex");
  }
  const int expected = tbs::control_point_count(domain_, n);
  if (static_cast<int>(control_points_.size()) != expected)
    throw InvalidInput("expected " + std::to_string(expected) + " control points (V + (n-1)E + " +
                       "(n-1)(n-2)/2 F for V=" + std::to_string(nv) +
                       ", E=" + std::to_string(domain_.edge_count()) +
                       ", F=" + std::to_string(domain_.triangle_count()) + ", n=" +
                       std::to_string(n) + "), got " + std::to_string(control_points_.size()));
  for (size_t i = 0; i < control_points_.size(); ++i)
    if (!control_points_[i].allFinite())
      throw InvalidInput("control point " + std::to_string(i) + " is not finite");

  const int nb = beta_count(n);
  if (map_.size() != static_cast<size_t>(domain_.triangle_count()) * nb)
    throw InvalidInput("control point map: expected " + std::to_string(domain_.triangle_count()) +
                       " rows of " + std::to_string(nb) + " indices");
  // The map must be a bijection between domain points and control points.
  std::vector<int> dp_to_cp(expected, -1), cp_to_dp(expected, -1);
  for (int t = 0; t < domain_.triangle_count(); ++t)
    for (int i = 0; i < nb; ++i) {
      const Beta b = beta_at(n, i);
      const int cp = map_[static_cast<size_t>(t) * nb + i];
      const std::string where = "control point map: triangle " + std::to_string(t) + ", beta " +
                                beta_str(b);
      if (cp < 0 || cp >= expected)
        throw InvalidInput(where + ": index " + std::to_string(cp) + " out of range [0, " +
                           std::to_string(expected) + ")");
      const int dp = domain_point(domain_, n, t, b);
      if (dp_to_cp[dp] < 0 && cp_to_dp[cp] < 0) {
        dp_to_cp[dp] = cp;
        cp_to_dp[cp] = dp;
      } else if (dp_to_cp[dp] != cp) {
        throw InvalidInput(where + ": index " + std::to_string(cp) +
                           (dp_to_cp[dp] >= 0
                                ? " disagrees with the neighbouring triangle, which uses " +
                                      std::to_string(dp_to_cp[dp]) + " for the same domain point"
                                : " is already used by a different domain point") +
                           " (shared control points: vertex and edge points are shared)");
      }
    }
}

Spline Spline::with_canonical_map(int degree, Domain domain, std::vector<Point2> knots) {
  if (degree < 1 || degree > tol::kMaxDegree)
    throw InvalidInput("degree " + std::to_string(degree) + " is not supported (1 to " +
                       std::to_string(tol::kMaxDegree) + ")");
  auto map = canonical_control_point_map(domain, degree);
  std::vector<Point3> cps(tbs::control_point_count(domain, degree), Point3::Zero());
  return Spline(degree, std::move(domain), std::move(knots), std::move(cps), std::move(map));
}

void Spline::set_knot(int vertex, int level, const Point2& p) {
  if (!p.allFinite()) throw InvalidInput("knot position is not finite");
  if (level == 0) domain_.move_vertex(vertex, p);
  knots_[vertex * (degree_ + 1) + level] = p;
}

Point2 Spline::blossom_point(int triangle, const Beta& beta) const {
  Point2 s = Point2::Zero();
  const auto& tri = domain_.triangle(triangle);
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < beta[j]; ++k) s += knot(tri[j], k);
  return s / degree_;
}

}  // namespace tbs
