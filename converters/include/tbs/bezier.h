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
/// Throws nothing but std::bad_alloc.
Point3 bezier_value(std::span<const Point3> net, int m, const Bary& b);

/// Value and the derivatives along the barycentric directions e1 - e0 and e2 - e0 (moving
/// from corner 0 toward corner 1, resp. corner 2, per unit of barycentric coordinate).
/// For a patch over a parameter triangle (a, b, c) these are the directional derivatives
/// along b - a and c - a. Throws nothing but std::bad_alloc. \pre as bezier_value().
void bezier_derivatives(std::span<const Point3> net, int m, const Bary& b, Point3& value,
                        Vector3& d01, Vector3& d02);

/// The Bernstein basis values B_beta(b), |beta| = m, in beta order.
/// Throws nothing but std::bad_alloc. \pre out.size() == beta_count(m).
void bernstein_triangle(int m, const Bary& b, std::span<double> out);

/// Value of a Bezier curve at t in [0, 1] (de Casteljau).
/// Throws nothing but std::bad_alloc. \pre cps not empty.
Point3 bezier_curve_value(std::span<const Point3> cps, double t);

/// The control points of the same curve restricted to [t0, t1] and reparameterised to
/// [0, 1]; t0 > t1 reverses it. Throws nothing but std::bad_alloc. \pre cps not empty.
std::vector<Point3> bezier_curve_restrict(std::span<const Point3> cps, double t0, double t1);

/// The Bernstein basis values B_k(t), k = 0..m. Throws nothing. \pre out.size() == m + 1.
void bernstein_curve(int m, double t, std::span<double> out);

/// The control points of the boundary curve of a net on the side opposite corner k, running
/// from corner k+1 to corner k+2 (mod 3). Throws nothing but std::bad_alloc.
std::vector<Point3> bezier_side(std::span<const Point3> net, int m, int k);

/// Positions in the net of the side opposite corner k, from corner k+1 to corner k+2.
/// Throws nothing but std::bad_alloc.
std::vector<int> bezier_side_indices(int m, int k);

/// The tensor-product Bezier patch of bidegree (m, m) that equals the triangular patch `net`
/// composed with the bilinear map (s, t) -> (1-s)(1-t) b00 + s(1-t) b10 + (1-s)t b01 + st b11
/// of barycentric points: exact, since each barycentric coordinate is bilinear in (s, t).
/// Control points are row-major, index i + (m+1) j for the i-th along s and j-th along t.
/// Throws nothing but std::bad_alloc. \pre as bezier_value().
std::vector<Point3> bezier_bilinear_compose(std::span<const Point3> net, int m, const Bary& b00,
                                            const Bary& b10, const Bary& b01, const Bary& b11);

/// The three quad patches that tile a triangular patch without degenerate edges: quad k has
/// corner k at (0,0), the midpoint of the side toward corner k+1 at (1,0), the centroid at
/// (1,1) and the midpoint of the side toward corner k+2 at (0,1); each is oriented like the
/// triangle. Throws nothing but std::bad_alloc. \pre as bezier_value().
std::array<std::vector<Point3>, 3> bezier_triangle_to_quads(std::span<const Point3> net, int m);

/// One quad patch with the edge s = 0 collapsed to corner 0: (s, t) -> barycentric
/// (1-s, s(1-t), st). Throws nothing but std::bad_alloc. \pre as bezier_value().
std::vector<Point3> bezier_triangle_to_collapsed_quad(std::span<const Point3> net, int m);

/// Value of a tensor-product Bezier patch (layout as above) at (s, t).
/// Throws nothing but std::bad_alloc. \pre cps.size() == (m + 1)^2, m >= 0.
Point3 bezier_tensor_value(std::span<const Point3> cps, int m, double s, double t);

}  // namespace tbs
