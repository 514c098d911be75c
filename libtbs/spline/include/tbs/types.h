#pragma once
/// \file
/// Basic geometric types used throughout tbs.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>

namespace tbs {

using Point2 = Eigen::Vector2d;   ///< A parameter point (u, v).
using Vector2 = Eigen::Vector2d;  ///< A direction in the parameter plane.
using Point3 = Eigen::Vector3d;   ///< A point in model space.
using Vector3 = Eigen::Vector3d;  ///< A direction in model space.

/// An axis-aligned box in the parameter plane.
struct Box2 {
  Point2 min{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Point2 max{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  void extend(const Point2& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  bool empty() const { return !(min.x() <= max.x() && min.y() <= max.y()); }
  /// Closed containment test.
  bool contains(const Point2& p) const {
    return p.x() >= min.x() && p.x() <= max.x() && p.y() >= min.y() && p.y() <= max.y();
  }
};

/// An axis-aligned box in model space.
struct Box3 {
  Point3 min{Point3::Constant(std::numeric_limits<double>::infinity())};
  Point3 max{Point3::Constant(-std::numeric_limits<double>::infinity())};
  void extend(const Point3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  bool empty() const { return !(min.array() <= max.array()).all(); }
};

/// Multi-index beta = (b0, b1, b2) of a Bezier-like domain point, |beta| = b0 + b1 + b2.
using Beta = std::array<int, 3>;

/// Number of multi-indices with |beta| = m.
constexpr int beta_count(int m) { return (m + 1) * (m + 2) / 2; }

/// Position of beta in the canonical order: b0 descending from m to 0, then b1 descending
/// from m - b0 to 0 (b2 = m - b0 - b1). For m = 2: (2,0,0) (1,1,0) (1,0,1) (0,2,0) (0,1,1) (0,0,2).
constexpr int beta_index(const Beta& b) {
  const int m = b[0] + b[1] + b[2];
  return (m - b[0]) * (m - b[0] + 1) / 2 + (m - b[0] - b[1]);
}

/// The beta at position `index` of the canonical order for |beta| = m.
constexpr Beta beta_at(int m, int index) {
  int b0 = m;
  int start = 0;
  while (start + (m - b0 + 1) <= index) {
    start += m - b0 + 1;
    --b0;
  }
  const int b1 = (m - b0) - (index - start);
  return {b0, b1, m - b0 - b1};
}

}  // namespace tbs
