// The exact orientation predicate behind the half-open rule (predicates.h), through CGAL.

#include <tbs/predicates.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

namespace tbs::detail {

int orientation_exact(const Point2& a, const Point2& b, const Point2& c) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  const auto o = CGAL::orientation(K::Point_2(a.x(), a.y()), K::Point_2(b.x(), b.y()),
                                   K::Point_2(c.x(), c.y()));
  return o == CGAL::LEFT_TURN ? 1 : (o == CGAL::RIGHT_TURN ? -1 : 0);
}

}  // namespace tbs::detail
