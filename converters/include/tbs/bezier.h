#pragma once
/// \file
/// Triangular Bezier patches and Bezier curves: evaluation, derivatives, restriction.
///
/// A triangular net of degree m holds beta_count(m) control points in the canonical beta
/// order of types.h (beta_index); b_j is the power of the barycentric coordinate of corner j.
/// A curve of degree m holds m + 1 control points.

#include <tbs/types.h>

#include <span>
#include <vector>

namespace tbs {

/// Barycentric coordinates (lambda_0, lambda_1, lambda_2) of a point in a patch's triangle.
using Bary = Eigen::Vector3d;

/// Value of a triangular Bezier patch at barycentric coordinates `b` (de Casteljau).
/// \pre net.size() == beta_count(m), m >= 0.
Point3 bezier_value(std::span<const Point3> net, int m, const Bary& b);

/// Value and the derivatives along the barycentric directions e1 - e0 and e2 - e0 (moving
/// from corner 0 toward corner 1, resp. corner 2, per unit of barycentric coordinate).
/// For a patch over a parameter triangle (a, b, c) these are the directional derivatives
/// along b - a and c - a.
void bezier_derivatives(std::span<const Point3> net, int m, const Bary& b, Point3& value,
                        Vector3& d01, Vector3& d02);

/// The Bernstein basis values B_beta(b), |beta| = m, in beta order.
void bernstein_triangle(int m, const Bary& b, std::span<double> out);

/// Value of a Bezier curve at t in [0, 1] (de Casteljau).
Point3 bezier_curve_value(std::span<const Point3> cps, double t);

/// The control points of the same curve restricted to [t0, t1] and reparameterised to
/// [0, 1]; t0 > t1 reverses it.
std::vector<Point3> bezier_curve_restrict(std::span<const Point3> cps, double t0, double t1);

/// The Bernstein basis values B_k(t), k = 0..m.
void bernstein_curve(int m, double t, std::span<double> out);

/// The control points of the boundary curve of a net on the side opposite corner k, running
/// from corner k+1 to corner k+2 (mod 3).
std::vector<Point3> bezier_side(std::span<const Point3> net, int m, int k);

/// Positions in the net of the side opposite corner k, from corner k+1 to corner k+2.
std::vector<int> bezier_side_indices(int m, int k);

}  // namespace tbs
