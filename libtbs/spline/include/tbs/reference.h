#pragma once
/// \file
/// Plain-recursion evaluation of simplex splines and of the surface: no graph, no
/// precomputation, every triangle visited. Slow and simple on purpose: it is the independent
/// computation the fast Evaluator is tested against, and the baseline of the benchmarks.

#include <tbs/predicates.h>
#include <tbs/spline.h>

#include <span>

namespace tbs::reference {

/// M(u | knots) (METHOD.md section 2) at the perturbed point p (section 7), by the recurrence
/// with a well-conditioned split set. Knots may repeat; a set whose knots are all collinear
/// is a degenerate spline and evaluates to 0. Throws nothing but std::bad_alloc.
/// \pre knots.size() >= 3.
double simplex_spline(std::span<const Point2> knots, const Perturbation& p);

/// D_{dirs[0]} ... D_{dirs[k-1]} M(u | knots): the one-sided derivative of the polynomial
/// piece that contains the perturbed point. Throws as simplex_spline().
double simplex_spline_derivative(std::span<const Point2> knots, std::span<const Vector2> dirs,
                                 const Perturbation& p);

/// The degree-n basis function N_{I,beta}(u) = |d(X_{I,beta})| M(u | V_{I,beta}), |beta| = n,
/// by the definition (n + 3 knots, the last knots t_{i,n} included).
/// Throws nothing but std::bad_alloc; triangle is not range-checked.
double basis_degree_n(const Spline& s, int triangle, const Beta& beta, const Perturbation& p);

/// F(u) by the degree-n definition, summing over every triangle.
/// Throws nothing but std::bad_alloc.
Point3 value_degree_n(const Spline& s, const Perturbation& p);

/// D_{dirs[0]} ... D_{dirs[k-1]} F(u) (F itself for no directions) through the degree n-1
/// form, summing over every triangle. Throws nothing but std::bad_alloc.
Vector3 derivative(const Spline& s, std::span<const Vector2> dirs, const Perturbation& p);

}  // namespace tbs::reference
