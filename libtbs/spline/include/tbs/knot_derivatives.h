#pragma once
/// \file
/// Derivatives of the surface with respect to its free knots (METHOD.md section 5).
///
/// For a simplex spline of degree m, moving knot t of V along v gives (from the Dirichlet
/// form of M, in which the weight of t doubles the knot):
///   D_{t,v} M(u | V) = -sum_j mu_j(v | W) M(u | V + {t} - {w_j}),  W = {t, a, b} in V,
/// so the first term is -mu_0 M(u | V) and the others are simplex splines with t doubled.
/// With the degree n-1 form F = sum_{I,g} P_{I,g}(u) M(u | V_{I,g}),
/// P_{I,g}(u) = sum_j d(X_{I,g}[j <- u]) c_{I,g+e_j}, the product rule gives D_{t,v} F.

#include <tbs/predicates.h>
#include <tbs/spline.h>

#include <Eigen/Core>

namespace tbs {

/// dF(u)/dt_{vertex,level}: column 0 is the derivative when the knot moves along +u, column 1
/// along +v. level in [0, n-1] (F does not depend on t_{i,n}); level 0 moves the domain
/// vertex. `p` is the perturbation of u (Evaluator::perturbation()).
/// \throw InvalidInput if vertex or level is out of range.
Eigen::Matrix<double, 3, 2> knot_derivative(const Spline& s, const Perturbation& p, int vertex,
                                            int level);

}  // namespace tbs
