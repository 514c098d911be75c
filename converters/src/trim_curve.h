#pragma once
// The 3D curve of a trim edge of the region faces: a clamped B-spline fitted to the spline
// along the edge.

#include <tbs/cad_regions.h>

#include <functional>
#include <vector>

namespace tbs::detail {

// Fits a clamped B-spline curve of `degree` over t in [0, length] to target(t): through
// target(0) and target(length), least squares in between, starting from `spans` uniform spans
// and bisecting those that miss `tol` (checked at the breaks, the span midpoints, 2 degree + 2
// points inside every span and at `checks`), for at most `rounds` rounds.
// \throw SolverError if a least-squares system cannot be solved.
BSplineCurve3 fit_trim_curve(const std::function<Point3(double)>& target, double length, int spans,
                             const std::vector<double>& checks, int degree, double tol, int rounds);

// Breakpoints: `spans` uniform spans from a to b (b exact).
std::vector<double> uniform_breaks(double a, double b, int spans);
// The span (index into breaks) that holds u; the later one at an inner break.
int span_of(const std::vector<double>& breaks, double u);
// Every break and the midpoint of every span.
std::vector<double> breaks_and_midpoints(const std::vector<double>& breaks);
// (p + 1) points inside every span, at (k + 1/2) / (p + 1).
std::vector<double> inner_points(const std::vector<double>& breaks, int p);

}  // namespace tbs::detail
