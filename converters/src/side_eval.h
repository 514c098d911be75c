#pragma once
// Evaluation on a chosen side of a parameter point, shared by the converters.

#include <tbs/evaluator.h>

namespace tbs::detail {

// F and its partial derivatives at u, on the piece that contains u + eps (toward - u), i.e.
// on the side of u where `toward` lies (toward must not equal u). `second` breaks ties when
// u + eps (toward - u) lies on a knot line; it must not be collinear with u and toward.
// If rounding put u just outside the domain, u is moved toward `toward` by a relative 1e-12
// and evaluated there; `used` receives the parameter actually evaluated.
SurfacePoint evaluate_toward(const Evaluator& ev, const Point2& u, const Point2& toward,
                             const Point2& second, Point2* used = nullptr);

// The unit normal of a surface point, zero where F_u x F_v vanishes.
inline Vector3 unit_normal(const SurfacePoint& p) {
  const Vector3 c = p.du.cross(p.dv);
  const double len = c.norm();
  return len > 0 ? Vector3(c / len) : Vector3::Zero();
}

}  // namespace tbs::detail
