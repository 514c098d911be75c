#include "side_eval.h"

#include <tbs/errors.h>
#include <tbs/predicates.h>

#include <algorithm>
#include <cmath>

namespace tbs::detail {

namespace {
// See evaluate_in_triangle(): the derivatives' point moves by about 1e-5 of the triangle's
// size, past a strip of rounding width (about 1e-7 of it for float coordinates).
constexpr double kDerivativesInside = 1e-5;
}  // namespace

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
  SurfacePoint p = evaluate_toward(ev, u, c, second);
  // Derivatives near an edge come from a point at least kDerivativesInside (barycentric)
  // inside: a knot line can run within rounding of an edge without lying on it (the sub-knots
  // of a crease vertex lie on one of its two feature edges; where the crease chain bends by
  // rounding, they miss the other one by about 1e-8), and the derivatives then change across a
  // strip of that width. The position is continuous across it and is taken at u.
  const double area = det3(tri[0], tri[1], tri[2]);
  if (area == 0) return p;
  double low = 1;
  for (int k = 0; k < 3; ++k) low = std::min(low, det3(u, tri[(k + 1) % 3], tri[(k + 2) % 3]) / area);
  if (low >= kDerivativesInside) return p;
  const double s = (kDerivativesInside - low) / (1.0 / 3 - low);
  const SurfacePoint q = evaluate_toward(ev, u + s * (c - u), c, second);
  p.du = q.du;
  p.dv = q.dv;
  return p;
}

double model_size(const Spline& s) {
  Box3 box;
  for (const Point3& c : s.control_points()) box.extend(c);
  return box.empty() ? 1.0 : std::max((box.max - box.min).norm(), 1e-300);
}

}  // namespace tbs::detail
