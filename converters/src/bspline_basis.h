#pragma once
// B-spline basis functions of clamped knot vectors, for the region faces.

#include <span>
#include <vector>

namespace tbs::detail {

inline constexpr int kMaxBasisDegree = 9;

// The degree + 1 basis functions that are non-zero on a span, and their first and second
// derivatives: entry j belongs to function s - degree + j.
struct Basis {
  double value[kMaxBasisDegree + 1];
  double d1[kMaxBasisDegree + 1];
  double d2[kMaxBasisDegree + 1];
};

// The span s with knots[s] <= t < knots[s + 1] (the last non-empty span for t at the end),
// p <= s < number of basis functions. \pre knots clamped, non-decreasing.
int find_span(std::span<const double> knots, int p, double t);

// The non-zero basis functions of degree p on span s at t, and `derivatives` (0 to 2) of
// their derivatives.
void basis_functions(std::span<const double> knots, int p, int s, double t, int derivatives, Basis& b);

// The clamped knot vector of degree p with the given breakpoints (ascending, at least two).
std::vector<double> clamped_knots(int p, std::span<const double> breaks);

}  // namespace tbs::detail
