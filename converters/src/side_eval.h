#pragma once
// Evaluation on a chosen side of a parameter point, shared by the converters.

#include <tbs/evaluator.h>

#include <array>

namespace tbs::detail {

// F and its partial derivatives at u, on the piece that contains u + eps (toward - u), i.e.
// on the side of u where `toward` lies (toward must not equal u). `second` breaks ties when
// u + eps (toward - u) lies on a knot line; it must not be collinear with u and toward.
// If rounding put u just outside the domain, u is moved toward `toward` by a relative 1e-12
// and evaluated there; `used` receives the parameter actually evaluated.
SurfacePoint evaluate_toward(const Evaluator& ev, const Point2& u, const Point2& toward,
                             const Point2& second, Point2* used = nullptr);

// F at a point u of the triangle `tri` (closed), on the side of its interior: toward its
// centroid, ties broken toward the corner farthest from that line. Within a barycentric 1e-5
// of an edge, the derivatives are those at the point 1e-5 inside on the way to the centroid
// (see side_eval.cpp); the position is always F(u).
SurfacePoint evaluate_in_triangle(const Evaluator& ev, const std::array<Point2, 3>& tri, const Point2& u);

// The model size the relative tolerances refer to: the diagonal of the control points'
// bounding box (1 for an empty spline).
double model_size(const Spline& s);

// The unit normal of a surface point, zero where F_u x F_v vanishes.
inline Vector3 unit_normal(const SurfacePoint& p) {
  const Vector3 c = p.du.cross(p.dv);
  const double len = c.norm();
  return len > 0 ? Vector3(c / len) : Vector3::Zero();
}

}  // namespace tbs::detail
