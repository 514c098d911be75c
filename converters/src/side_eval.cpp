#include "side_eval.h"

#include <tbs/errors.h>
#include <tbs/predicates.h>

#include <algorithm>
#include <cmath>

namespace tbs::detail {

SurfacePoint evaluate_toward(const Evaluator& ev, const Point2& u, const Point2& toward,
                             const Point2& second, Point2* used) {
  if (orientation(u, toward, second) != 0) {
    if (auto r = ev.evaluate(u, Perturbation::toward(u, toward, second))) {
      if (used) *used = u;
      return *r;
    }
  }
  // u is off the domain by rounding (or the directions were degenerate): step inside.
  Point2 v = u;
  for (double f = 1e-12; f < 1e-3; f *= 16) {
    v = u + f * (toward - u);
    if (ev.locate(v) >= 0) {
      if (used) *used = v;
      return ev.evaluate(v);
    }
  }
  if (used) *used = toward;
  return ev.evaluate(toward);
}

SurfacePoint evaluate_in_triangle(const Evaluator& ev, const std::array<Point2, 3>& tri, const Point2& u) {
  const Point2 c = (tri[0] + tri[1] + tri[2]) / 3.0;
  Point2 second = tri[0];
  double best = -1;
  for (const Point2& v : tri) {
    const double a = std::fabs(det3(u, c, v));
    if (a > best) best = a, second = v;
  }
  return evaluate_toward(ev, u, c, second);
}

double model_size(const Spline& s) {
  Box3 box;
  for (const Point3& c : s.control_points()) box.extend(c);
  return box.empty() ? 1.0 : std::max((box.max - box.min).norm(), 1e-300);
}

}  // namespace tbs::detail
