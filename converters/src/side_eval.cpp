#include "side_eval.h"

#include <tbs/errors.h>
#include <tbs/predicates.h>

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

}  // namespace tbs::detail
