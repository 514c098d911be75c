#pragma once
// A uniform grid over axis-aligned boxes: the spatial index behind point location and
// basis-support lookup. Each cell lists the boxes that overlap it, so a point query returns
// every box that may contain the point (and a few that do not).

#include <tbs/types.h>

#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

namespace tbs::detail {

class BoxGrid {
 public:
  BoxGrid() = default;

  // Builds a grid of about `target_cells` cells over the union of the boxes.
  void build(const std::vector<Box2>& boxes, size_t target_cells) {
    extent_ = Box2{};
    for (const auto& b : boxes)
      if (!b.empty()) {
        extent_.extend(b.min);
        extent_.extend(b.max);
      }
    nx_ = ny_ = 1;
    if (extent_.empty()) {
      start_.assign(2, 0);
      items_.clear();
      cells_.assign(boxes.size(), Cells{});
      return;
    }
    const Point2 ext = extent_.max - extent_.min;
    const double w = std::max(ext.x(), 1e-300), h = std::max(ext.y(), 1e-300);
    const double cells = static_cast<double>(std::max<size_t>(target_cells, 1));
    const double cell = std::sqrt(w * h / cells);
    nx_ = cells_across(std::ceil(w / std::max(cell, 1e-300)));
    ny_ = cells_across(std::ceil(h / std::max(cell, 1e-300)));
    sx_ = static_cast<double>(nx_) / w;
    sy_ = static_cast<double>(ny_) / h;

    std::vector<int> count(static_cast<size_t>(nx_ * ny_) + 1, 0);
    auto each_cell = [&](const Box2& b, auto&& f) {
      const long x0 = cx(b.min.x()), x1 = cx(b.max.x());
      const long y0 = cy(b.min.y()), y1 = cy(b.max.y());
      for (long y = y0; y <= y1; ++y)
        for (long x = x0; x <= x1; ++x) f(static_cast<size_t>(y * nx_ + x));
    };
    cells_.assign(boxes.size(), Cells{});
    for (size_t i = 0; i < boxes.size(); ++i)
      if (!boxes[i].empty()) {
        const Box2& b = boxes[i];
        cells_[i] = {cx(b.min.x()), cx(b.max.x()), cy(b.min.y()), cy(b.max.y())};
        each_cell(b, [&](size_t c) { ++count[c + 1]; });
      }
    for (size_t c = 1; c < count.size(); ++c) count[c] += count[c - 1];
    start_ = count;
    items_.assign(static_cast<size_t>(count.back()), -1);
    for (int i = 0; i < static_cast<int>(boxes.size()); ++i)
      if (!boxes[i].empty()) each_cell(boxes[i], [&](size_t c) { items_[count[c]++] = i; });
  }

  // Whether box `id` may grow or shrink to b without a new build: b lies inside the grid's
  // extent and meets no cell that the build did not list `id` in. A grid whose cells list a box
  // in more cells than it meets answers at() with the same boxes in the same order (by id)
  // among those that contain the point, which is all its users look at.
  bool covers(int id, const Box2& b) const {
    if (b.empty() || static_cast<size_t>(id) >= cells_.size() || cells_[id].x0 < 0) return false;
    if (!(b.min.x() >= extent_.min.x() && b.max.x() <= extent_.max.x() && b.min.y() >= extent_.min.y() &&
          b.max.y() <= extent_.max.y()))
      return false;
    const Cells& c = cells_[id];
    return cx(b.min.x()) >= c.x0 && cx(b.max.x()) <= c.x1 && cy(b.min.y()) >= c.y0 && cy(b.max.y()) <= c.y1;
  }

  // Boxes whose cell contains p (empty if p is outside the grid).
  std::span<const int> at(const Point2& p) const {
    if (!(p.x() >= extent_.min.x() && p.x() <= extent_.max.x() && p.y() >= extent_.min.y() &&
          p.y() <= extent_.max.y()))
      return {};
    const size_t c = static_cast<size_t>(cy(p.y()) * nx_ + cx(p.x()));
    return {items_.data() + start_[c], items_.data() + start_[c + 1]};
  }

  // Number of distinct values tile_key() returns.
  size_t tile_key_count() const {
    const long tx = (nx_ + kTile - 1) / kTile, ty = (ny_ + kTile - 1) / kTile;
    return static_cast<size_t>(tx * ty * kTile * kTile) + 1;
  }

  // A key that orders points by cell, cells in tiles of kTile x kTile (row by row inside a
  // tile, tiles row by row), so that points with nearby keys share the boxes of nearby
  // cells. Points outside the grid get the last key, tile_key_count() - 1.
  size_t tile_key(const Point2& p) const {
    if (!(p.x() >= extent_.min.x() && p.x() <= extent_.max.x() && p.y() >= extent_.min.y() &&
          p.y() <= extent_.max.y()))
      return tile_key_count() - 1;
    const long x = cx(p.x()), y = cy(p.y());
    const long tx = (nx_ + kTile - 1) / kTile;
    const long tile = (y / kTile) * tx + x / kTile;
    return static_cast<size_t>(tile * kTile * kTile + (y % kTile) * kTile + x % kTile);
  }

  // Calls f(id) for every box whose cells meet b; an id may be reported more than once.
  template <class F>
  void query(const Box2& b, F&& f) const {
    if (extent_.empty() || b.max.x() < extent_.min.x() || b.min.x() > extent_.max.x() ||
        b.max.y() < extent_.min.y() || b.min.y() > extent_.max.y())
      return;
    const long x0 = cx(b.min.x()), x1 = cx(b.max.x());
    const long y0 = cy(b.min.y()), y1 = cy(b.max.y());
    for (long y = y0; y <= y1; ++y)
      for (long x = x0; x <= x1; ++x) {
        const size_t c = static_cast<size_t>(y * nx_ + x);
        for (int i = start_[c]; i < start_[c + 1]; ++i) f(items_[i]);
      }
  }

 private:
  static constexpr long kTile = 8;

  long cx(double x) const { return index_in((x - extent_.min.x()) * sx_, nx_); }
  long cy(double y) const { return index_in((y - extent_.min.y()) * sy_, ny_); }
  // Both clamp in floating point first: converting a value beyond the range of long (boxes
  // reaching 1e68, or 1e154 times wider than high, from far knots) is undefined behaviour
  // (found by fuzzing .tbs files).
  static long index_in(double f, long n) {
    if (!(f > 0)) return 0;
    if (f >= static_cast<double>(n - 1)) return n - 1;
    return static_cast<long>(f);
  }
  static long cells_across(double f) {
    if (!(f >= 1)) return 1;
    if (f >= 4096) return 4096;
    return static_cast<long>(f);
  }

  // The cells a box was listed in (x0 < 0: none, an empty box).
  struct Cells {
    long x0 = -1, x1 = -1, y0 = -1, y1 = -1;
  };

  Box2 extent_;
  std::vector<Cells> cells_;
  long nx_ = 1, ny_ = 1;
  double sx_ = 1, sy_ = 1;
  std::vector<int> start_;
  std::vector<int> items_;
};

}  // namespace tbs::detail
