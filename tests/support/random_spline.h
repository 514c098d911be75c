#pragma once
// Test fixtures: random valid splines on perturbed grid domains, built in code.

#include <tbs/domain.h>
#include <tbs/evaluator.h>
#include <tbs/spline.h>

#include <Eigen/Core>

#include <cstdint>
#include <random>
#include <vector>

namespace tbs::test {

struct GridOptions {
  int nx = 4, ny = 4;
  double jitter = 0.25;        // interior vertices move by up to this fraction of a cell
  bool hole = false;           // remove the cells of the middle (needs nx, ny >= 4)
  int feature_column = -1;     // vertical feature line along this grid column (interior)
  bool feature_kink = false;   // make the feature line a zig-zag instead of straight
};

// A triangulated grid over [0,1]^2 with dyadic coordinates (multiples of 2^-24), so that
// midpoints and quarter points of segments between vertices or knots are exact.
Domain grid_domain(const GridOptions& o, uint64_t seed);

// Random sub-knots satisfying the knot conditions: inside Traas's circle at a random angle
// and distance, outside the domain for boundary vertices, on the feature edge for feature
// servers; dyadic coordinates. Aborts the test if the result fails check_knot_conditions().
std::vector<Point2> random_knots(const Domain& d, int degree, uint64_t seed);

// A spline with random knots and random control points in [-1,1]^3.
Spline random_spline(int degree, const GridOptions& o, uint64_t seed);

// Uniform random points in the domain's triangles.
std::vector<Point2> random_domain_points(const Domain& d, size_t count, uint64_t seed);

// Points exactly on knot lines (midpoints and quarter points of segments between knots of a
// triangle's vertices), exactly on domain edges (interior and boundary) and the domain
// vertices and knots themselves; only those inside the domain.
std::vector<Point2> special_points(const Spline& s, const Evaluator& ev, size_t max_count);

// Central differences of F(u) when knot t_{v,l} moves along +x and +y by h: the generic
// fallback the analytic knot derivative is tested against.
Eigen::Matrix<double, 3, 2> knot_derivative_fd(const Spline& s, const Point2& u, int v, int l,
                                               double h);

// Rounds to a multiple of 2^-24.
inline double dyadic(double x) { return std::ldexp(std::round(std::ldexp(x, 24)), -24); }
inline Point2 dyadic(const Point2& p) { return {dyadic(p.x()), dyadic(p.y())}; }

}  // namespace tbs::test
