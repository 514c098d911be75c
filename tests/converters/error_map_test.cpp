#include <tbs/error_map.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/fit.h>

#include "random_spline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace tbs {
namespace {

Spline holed_spline(uint64_t seed) {
  test::GridOptions o;
  o.nx = o.ny = 6;
  o.hole = true;
  return test::random_spline(3, o, seed);
}

// Points at known signed offsets r_i along the normal from F(u_i).
struct Synthetic {
  std::vector<Point2> uv;
  std::vector<Point3> points;
  std::vector<double> offset;
};

Synthetic offset_points(const Spline& s, size_t count, uint64_t seed) {
  const Evaluator ev(s);
  Synthetic out;
  out.uv = test::random_domain_points(s.domain(), count, seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> r(-1e-3, 1e-3);
  for (const auto& u : out.uv) {
    const double o = r(rng);
    out.offset.push_back(o);
    out.points.push_back(ev.value(u) + o * ev.normal(u));
  }
  return out;
}

TEST(ErrorMap, PointErrorsAreTheKnownOffsets) {
  const Spline s = holed_spline(50);
  const Synthetic syn = offset_points(s, 5000, 1);
  const PointErrors e = point_errors(s, syn.points, syn.uv);
  ASSERT_EQ(e.outside, 0u);
  std::vector<double> abs;
  for (size_t i = 0; i < syn.uv.size(); ++i) {
    ASSERT_NEAR(e.distance[i], std::fabs(syn.offset[i]), 1e-12);
    ASSERT_NEAR(e.signed_distance[i], syn.offset[i], 1e-12);
    abs.push_back(std::fabs(syn.offset[i]));
  }
  std::sort(abs.begin(), abs.end());
  double sum2 = 0;
  for (double a : abs) sum2 += a * a;
  EXPECT_NEAR(e.stats.max, abs.back(), 1e-12);
  EXPECT_NEAR(e.stats.rms, std::sqrt(sum2 / abs.size()), 1e-12);
  EXPECT_NEAR(e.stats.p50, abs[abs.size() / 2 - 1], 1e-12);  // nearest rank: ceil(0.5 N)
  EXPECT_NEAR(e.stats.p99, abs[static_cast<size_t>(std::ceil(0.99 * abs.size())) - 1], 1e-12);
  EXPECT_NEAR(e.stats.min_signed, *std::min_element(syn.offset.begin(), syn.offset.end()), 1e-12);
  EXPECT_NEAR(e.stats.max_signed, *std::max_element(syn.offset.begin(), syn.offset.end()), 1e-12);
}

TEST(ErrorMap, MapStatisticsEqualThePointStatistics) {
  const Spline s = holed_spline(51);
  const Synthetic syn = offset_points(s, 20000, 2);
  const PointErrors e = point_errors(s, syn.points, syn.uv);
  const ErrorMap m = make_error_map(s, syn.uv, e, {.width = 64});
  ASSERT_EQ(m.width, 64);
  ASSERT_EQ(m.height, 64);  // the domain is square
  double max = 0, sum2 = 0;
  size_t count = 0;
  int measured = 0, interpolated = 0, outside = 0;
  for (size_t p = 0; p < m.mask.size(); ++p) {
    switch (m.mask[p]) {
      case PixelKind::Measured:
        ++measured;
        max = std::max(max, double(m.error[p]));
        sum2 += double(m.rms[p]) * m.rms[p] * m.count[p];
        count += m.count[p];
        EXPECT_LE(std::fabs(m.signed_error[p]), m.error[p] * (1 + 1e-6));
        break;
      case PixelKind::Interpolated:
        ++interpolated;
        EXPECT_GE(m.triangle[p], 0);
        EXPECT_EQ(m.count[p], 0u);
        break;
      case PixelKind::Outside:
        ++outside;
        EXPECT_EQ(m.triangle[p], -1);
        break;
    }
  }
  EXPECT_EQ(count, syn.uv.size());
  EXPECT_NEAR(max, e.stats.max, 1e-7 * e.stats.max);  // stored as float
  EXPECT_NEAR(std::sqrt(sum2 / count), e.stats.rms, 1e-6 * e.stats.rms);
  EXPECT_EQ(m.stats.max, e.stats.max);
  EXPECT_EQ(m.stats.rms, e.stats.rms);
  // The hole (the middle 2 x 2 of 6 x 6 cells) is outside: about 1/9 of the pixels.
  EXPECT_GT(outside, 64 * 64 / 12);
  EXPECT_LT(outside, 64 * 64 / 7);
  EXPECT_GT(measured, 64 * 64 / 2);
  // Geometry image: the surface at pixel centres.
  const Evaluator ev(s);
  for (int y = 0; y < m.height; y += 7)
    for (int x = 0; x < m.width; x += 5) {
      const size_t p = static_cast<size_t>(y) * m.width + x;
      const Point2 c(m.domain.min.x() + (x + 0.5) * (m.domain.max.x() - m.domain.min.x()) / m.width,
                     m.domain.max.y() - (y + 0.5) * (m.domain.max.y() - m.domain.min.y()) / m.height);
      if (m.triangle[p] < 0) {
        EXPECT_LT(ev.locate(c), 0);
        continue;
      }
      const Point3 f = ev.value(c);
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(m.position[3 * p + k], f[k], 1e-6 * (1 + std::fabs(f[k])));
    }
}

TEST(ErrorMap, SparsePointsLeaveInterpolatedPixels) {
  const Spline s = holed_spline(52);
  const Synthetic syn = offset_points(s, 200, 3);
  const PointErrors e = point_errors(s, syn.points, syn.uv);
  const ErrorMap m = make_error_map(s, syn.uv, e, {.width = 100, .height = 50});
  int interpolated = 0;
  for (size_t p = 0; p < m.mask.size(); ++p) {
    if (m.mask[p] != PixelKind::Interpolated) continue;
    ++interpolated;
    EXPECT_LE(m.error[p], e.stats.max * (1 + 1e-6));  // a mean of neighbours stays in range
  }
  EXPECT_GT(interpolated, 4000);
}

TEST(ErrorMap, AFitsResidualsAreWhatTheMapShows) {
  // A synthetic scan with known noise, fitted; the error measure of the map is the fitter's.
  Scan scan;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0, 2e-4);
  for (int j = 0; j < 120; ++j)
    for (int i = 0; i < 120; ++i) {
      const double u = i / 119.0, v = j / 119.0;
      scan.uv.emplace_back(u, v);
      scan.positions.emplace_back(u, v, 0.1 * std::sin(3 * u) * std::cos(2 * v) + noise(rng));
    }
  FitOptions fo;
  fo.tolerance = 2e-3;
  const FitResult r = fit(scan, fo);
  const PointErrors e = point_errors(r.spline, scan.positions, r.uv);
  ASSERT_EQ(e.distance.size(), r.error.size());
  for (size_t i = 0; i < r.error.size(); ++i) ASSERT_NEAR(e.distance[i], r.error[i], 1e-12);
  EXPECT_NEAR(e.stats.max, r.report.max_error_abs, 1e-12);
  EXPECT_NEAR(e.stats.rms, r.report.rms_error_abs, 1e-12);
  // The noise is about 2e-4, so the residual RMS is close to it.
  EXPECT_GT(e.stats.rms, 1e-4);
  EXPECT_LT(e.stats.rms, 3e-4);
  const ErrorMap m = make_error_map(r.spline, r.uv, e, {.width = 40});
  double max = 0;
  for (size_t p = 0; p < m.mask.size(); ++p)
    if (m.mask[p] == PixelKind::Measured) max = std::max(max, double(m.error[p]));
  EXPECT_NEAR(max, e.stats.max, 1e-7 * e.stats.max);
}

TEST(ErrorMap, ClosestPointDistanceIgnoresSlidingAlongTheSurface) {
  // A height field (a scan-like surface; random control points make folded ones).
  Spline s = holed_spline(54);
  for (int t = 0; t < s.domain().triangle_count(); ++t)
    for (int i = 0; i < beta_count(3); ++i) {
      const Point2 b = s.blossom_point(t, beta_at(3, i));
      s.control_points()[s.control_point_index(t, i)] =
          Point3(b.x(), b.y(), 0.2 * std::sin(3 * b.x()) * std::cos(2 * b.y()));
    }
  const Evaluator ev(s);
  // Points on the surface, but paired with a parameter a little off: the parameter measure
  // sees the slide, the closest-point measure does not. Points off along the normal: both see
  // the offset.
  std::vector<Point2> uv, moved;
  std::vector<Point3> on, off;
  for (const Point2& u : test::random_domain_points(s.domain(), 400, 9)) {
    const Point2 w = u + Point2(0.004, -0.003);
    if (ev.locate(w) < 0 || ev.locate(u + Point2(0.02, -0.02)) < 0 || ev.locate(u - Point2(0.02, -0.02)) < 0) continue;
    uv.push_back(u);
    moved.push_back(w);
    on.push_back(ev.value(u));
    off.push_back(ev.value(u) + 2e-3 * ev.normal(u));
  }
  ASSERT_GT(uv.size(), 200u);
  const PointErrors param = point_errors(s, on, moved);
  const PointErrors closest = point_errors(s, on, moved, {.measure = ErrorMeasure::Closest});
  EXPECT_GT(param.stats.rms, 1e-3);
  EXPECT_LT(closest.stats.max, 1e-9);
  for (size_t i = 0; i < uv.size(); ++i) ASSERT_LE(closest.distance[i], param.distance[i]);
  const PointErrors normal = point_errors(s, off, uv, {.measure = ErrorMeasure::Closest});
  for (size_t i = 0; i < uv.size(); ++i) {
    // The foot of a normal offset is the point itself (a local minimum of the distance).
    ASSERT_NEAR(normal.distance[i], 2e-3, 1e-9);
    ASSERT_NEAR(normal.signed_distance[i], 2e-3, 1e-9);
  }
}

TEST(ErrorMap, ErrorAtReadsThePixelOrItsNearestMeasuredNeighbour) {
  const Spline s = holed_spline(54);
  const Synthetic syn = offset_points(s, 3000, 5);
  const PointErrors e = point_errors(s, syn.points, syn.uv);
  const ErrorMap m = make_error_map(s, syn.uv, e, {.width = 48});
  // At a point's own parameter the map holds the largest error of its pixel: at least its own.
  for (size_t i = 0; i < syn.uv.size(); ++i) {
    const float v = error_at(m, syn.uv[i]);
    ASSERT_TRUE(std::isfinite(v));
    ASSERT_GE(v, static_cast<float>(e.distance[i]));
    ASSERT_LE(v, static_cast<float>(e.stats.max));
  }
  // Every domain vertex, boundary and hole corners included, finds a value nearby.
  for (const Point2& p : s.domain().vertices()) EXPECT_TRUE(std::isfinite(error_at(m, p))) << p.transpose();
  // Far outside the rectangle it clamps to the border pixels.
  const Box2 b = s.domain().bounding_box();
  EXPECT_TRUE(std::isfinite(error_at(m, b.max + Point2(10, 10))));
  // Without any pixel holding a value there is nothing to read.
  ErrorMap empty = m;
  std::fill(empty.mask.begin(), empty.mask.end(), PixelKind::Outside);
  EXPECT_TRUE(std::isnan(error_at(empty, syn.uv[0])));
  EXPECT_TRUE(std::isnan(error_at(ErrorMap{}, syn.uv[0])));
}

TEST(ErrorMap, HeatColourRunsFromBlueToRed) {
  const auto lo = heat_colour(0.0), hi = heat_colour(1.0);
  EXPECT_GT(lo[2], 200);
  EXPECT_LT(lo[0], 50);
  EXPECT_GT(hi[0], 200);
  EXPECT_LT(hi[2], 50);
  EXPECT_EQ(heat_colour(-3.0), lo);
  EXPECT_EQ(heat_colour(7.0), hi);
  EXPECT_EQ(heat_colour(std::nan("")), lo);
  // Blue never rises along the scale; the upper quarter (yellow to red) is mostly red.
  for (int i = 1; i <= 100; ++i) EXPECT_LE(heat_colour(0.01 * i)[2], heat_colour(0.01 * (i - 1))[2]) << i;
  for (double t : {0.75, 0.9, 1.0}) EXPECT_GT(heat_colour(t)[0], 200) << t;
}

TEST(ErrorMap, RejectsBadSizes) {
  const Spline s = holed_spline(53);
  const Synthetic syn = offset_points(s, 10, 4);
  const PointErrors e = point_errors(s, syn.points, syn.uv);
  EXPECT_THROW(make_error_map(s, syn.uv, e, {.width = 0}), InvalidInput);
  EXPECT_THROW(make_error_map(s, syn.uv, e, {.width = 20000}), InvalidInput);
  EXPECT_THROW(point_errors(s, syn.points, std::span(syn.uv).first(5)), InvalidInput);
}

}  // namespace
}  // namespace tbs
