#include <tbs/error_map.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>

#include <Eigen/LU>

#include "side_eval.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

namespace tbs {

ErrorStats error_stats(std::span<const double> distance, std::span<const double> signed_distance) {
  ErrorStats st;
  std::vector<double> d;
  d.reserve(distance.size());
  double sum = 0, sum2 = 0;
  for (double x : distance)
    if (std::isfinite(x)) {
      d.push_back(x);
      sum += x;
      sum2 += x * x;
    }
  st.count = d.size();
  if (d.empty()) return st;
  std::sort(d.begin(), d.end());
  st.max = d.back();
  st.mean = sum / d.size();
  st.rms = std::sqrt(sum2 / d.size());
  auto rank = [&](double p) {
    const size_t k = static_cast<size_t>(std::ceil(p * d.size()));
    return d[std::clamp<size_t>(k, 1, d.size()) - 1];
  };
  st.p50 = rank(0.5);
  st.p90 = rank(0.9);
  st.p95 = rank(0.95);
  st.p99 = rank(0.99);
  bool first = true;
  for (double x : signed_distance)
    if (std::isfinite(x)) {
      st.min_signed = first ? x : std::min(st.min_signed, x);
      st.max_signed = first ? x : std::max(st.max_signed, x);
      first = false;
    }
  return st;
}

namespace {

// Gauss-Newton steps toward the closest surface point from the parameter u, staying in the
// domain; a step is taken only if it brings the surface closer.
Point2 closest_parameter(const Evaluator& ev, const Point3& p, Point2 u, double scale) {
  SurfacePoint f = ev.evaluate(u);
  double best = (p - f.position).squaredNorm();
  for (int iter = 0; iter < 20; ++iter) {
    const Vector3 r = p - f.position;
    Eigen::Matrix2d jtj;
    jtj << f.du.dot(f.du), f.du.dot(f.dv), f.du.dot(f.dv), f.dv.dot(f.dv);
    const Eigen::Vector2d jtr(f.du.dot(r), f.dv.dot(r));
    if (std::fabs(jtj.determinant()) <= 1e-300) break;
    Eigen::Vector2d step = jtj.inverse() * jtr;
    bool moved = false;
    for (int half = 0; half < 30; ++half, step *= 0.5) {
      const Point2 v = u + step;
      if (ev.locate(v) < 0) continue;
      const SurfacePoint g = ev.evaluate(v);
      const double d = (p - g.position).squaredNorm();
      if (d < best) {
        best = d;
        u = v;
        f = g;
        moved = true;
        break;
      }
    }
    if (!moved || step.norm() <= 1e-13 * scale) break;
  }
  return u;
}

}  // namespace

PointErrors point_errors(const Spline& s, std::span<const Point3> points, std::span<const Point2> uv,
                         const PointErrorOptions& o) {
  if (points.size() != uv.size())
    throw InvalidInput("point_errors: " + std::to_string(points.size()) + " points but " +
                       std::to_string(uv.size()) + " parameters");
  const Evaluator ev(s);
  PointErrors out;
  out.measure = o.measure;
  const size_t n = points.size();
  out.foot.assign(uv.begin(), uv.end());
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  if (o.measure == ErrorMeasure::Closest) {
    const Box2 box = s.domain().bounding_box();
    const double scale = std::max((box.max - box.min).norm(), 1e-300);
    arena.execute([&] {
      tbb::parallel_for(size_t(0), n, [&](size_t i) {
        if (ev.locate(uv[i]) >= 0) out.foot[i] = closest_parameter(ev, points[i], uv[i], scale);
      });
    });
  }
  std::vector<Point3> f(n);
  std::vector<Vector3> du(n), dv(n);
  std::vector<uint8_t> inside(n);
  out.outside = ev.evaluate_batch(out.foot, f, du, dv, inside, o.threads);
  out.distance.resize(n);
  out.signed_distance.resize(n);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (size_t i = 0; i < n; ++i) {
    if (!inside[i]) {
      out.distance[i] = out.signed_distance[i] = nan;
      continue;
    }
    const Vector3 r = points[i] - f[i];
    Vector3 nrm = du[i].cross(dv[i]);
    const double len = nrm.norm();
    out.distance[i] = r.norm();
    out.signed_distance[i] = len > 0 ? r.dot(nrm / len) : 0.0;
  }
  out.stats = error_stats(out.distance, out.signed_distance);
  return out;
}

ErrorMap make_error_map(const Spline& s, std::span<const Point2> uv, const PointErrors& e,
                        const ErrorMapOptions& o) {
  if (uv.size() != e.distance.size())
    throw InvalidInput("make_error_map: " + std::to_string(uv.size()) + " parameters but " +
                       std::to_string(e.distance.size()) + " errors");
  const Box2 box = s.domain().bounding_box();
  const double w = box.max.x() - box.min.x(), h = box.max.y() - box.min.y();
  int width = o.width, height = o.height;
  if (height == 0 && width > 0)
    height = std::max(1, static_cast<int>(std::lround(width * (h / std::max(w, 1e-300)))));
  if (width < 1 || width > 16384 || height < 1 || height > 16384)
    throw InvalidInput("error map size " + std::to_string(width) + " x " + std::to_string(height) +
                       " is out of range (1 to 16384 pixels a side)");
  ErrorMap m;
  m.width = width;
  m.height = height;
  m.domain = box;
  const size_t np = static_cast<size_t>(width) * height;
  m.mask.assign(np, PixelKind::Outside);
  m.error.assign(np, 0.f);
  m.signed_error.assign(np, 0.f);
  m.rms.assign(np, 0.f);
  m.count.assign(np, 0);
  m.position.assign(3 * np, 0.f);
  m.normal.assign(3 * np, 0.f);
  m.triangle.assign(np, -1);
  m.stats = e.stats;
  const double sx = width / std::max(w, 1e-300), sy = height / std::max(h, 1e-300);
  auto pixel_of = [&](const Point2& u) -> long {
    const long x = std::clamp(static_cast<long>(std::floor((u.x() - box.min.x()) * sx)), 0L, long(width) - 1);
    const long y = std::clamp(static_cast<long>(std::floor((box.max.y() - u.y()) * sy)), 0L, long(height) - 1);
    return y * width + x;
  };

  // Surface at pixel centres.
  const Evaluator ev(s);
  std::vector<Point2> centres(np);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      centres[static_cast<size_t>(y) * width + x] =
          Point2(box.min.x() + (x + 0.5) / sx, box.max.y() - (y + 0.5) / sy);
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(size_t(0), np, [&](size_t i) {
      const int t = ev.locate(centres[i]);
      if (t < 0) return;
      const SurfacePoint p = ev.evaluate(centres[i]);
      const Vector3 n = detail::unit_normal(p);
      m.triangle[i] = t;
      for (int k = 0; k < 3; ++k) {
        m.position[3 * i + k] = static_cast<float>(p.position[k]);
        m.normal[3 * i + k] = static_cast<float>(n[k]);
      }
    });
  });

  // Points into pixels: largest error, signed error of largest magnitude, RMS.
  std::vector<double> sum2(np, 0.0), emax(np, 0.0), smax(np, 0.0);
  for (size_t i = 0; i < uv.size(); ++i) {
    if (!std::isfinite(e.distance[i])) continue;
    const long p = pixel_of(uv[i]);
    if (m.count[p] == 0 || e.distance[i] > emax[p]) emax[p] = e.distance[i];
    if (m.count[p] == 0 || std::fabs(e.signed_distance[i]) > std::fabs(smax[p])) smax[p] = e.signed_distance[i];
    sum2[p] += e.distance[i] * e.distance[i];
    ++m.count[p];
  }
  std::deque<long> queue;
  for (size_t p = 0; p < np; ++p) {
    if (m.count[p] > 0) {
      // A point near the boundary may fall in a pixel whose centre is outside: it is still
      // measured.
      m.mask[p] = PixelKind::Measured;
      m.error[p] = static_cast<float>(emax[p]);
      m.signed_error[p] = static_cast<float>(smax[p]);
      m.rms[p] = static_cast<float>(std::sqrt(sum2[p] / m.count[p]));
      queue.push_back(static_cast<long>(p));
    }
  }
  // Empty pixels inside the domain: the mean of their already known 4-neighbours, filled
  // outward from the measured ones (breadth first, so nearer data counts first).
  std::vector<char> known(np, 0);
  for (long p : queue) known[p] = 1;
  while (!queue.empty()) {
    const long p = queue.front();
    queue.pop_front();
    const int x = static_cast<int>(p % width), y = static_cast<int>(p / width);
    const int nx[4] = {x - 1, x + 1, x, x}, ny[4] = {y, y, y - 1, y + 1};
    for (int k = 0; k < 4; ++k) {
      if (nx[k] < 0 || nx[k] >= width || ny[k] < 0 || ny[k] >= height) continue;
      const long q = static_cast<long>(ny[k]) * width + nx[k];
      if (known[q] || m.triangle[q] < 0) continue;
      double se = 0, ss = 0, sr = 0;
      int c = 0;
      const int qx = nx[k], qy = ny[k];
      const int mx[4] = {qx - 1, qx + 1, qx, qx}, my[4] = {qy, qy, qy - 1, qy + 1};
      for (int j = 0; j < 4; ++j) {
        if (mx[j] < 0 || mx[j] >= width || my[j] < 0 || my[j] >= height) continue;
        const long r = static_cast<long>(my[j]) * width + mx[j];
        if (!known[r]) continue;
        se += m.error[r];
        ss += m.signed_error[r];
        sr += m.rms[r];
        ++c;
      }
      m.error[q] = static_cast<float>(se / c);
      m.signed_error[q] = static_cast<float>(ss / c);
      m.rms[q] = static_cast<float>(sr / c);
      m.mask[q] = PixelKind::Interpolated;
      known[q] = 1;
      queue.push_back(q);
    }
  }
  return m;
}

float error_at(const ErrorMap& m, const Point2& u) {
  if (m.width < 1 || m.height < 1) return std::numeric_limits<float>::quiet_NaN();
  const double w = m.domain.max.x() - m.domain.min.x(), h = m.domain.max.y() - m.domain.min.y();
  const double fx = (u.x() - m.domain.min.x()) * (m.width / std::max(w, 1e-300));
  const double fy = (m.domain.max.y() - u.y()) * (m.height / std::max(h, 1e-300));
  const long x0 = std::clamp(static_cast<long>(std::floor(fx)), 0L, long(m.width) - 1);
  const long y0 = std::clamp(static_cast<long>(std::floor(fy)), 0L, long(m.height) - 1);
  // The nearest pixel with a value, by the distance from u to the pixel centre.
  constexpr int kReach = 3;
  float best = std::numeric_limits<float>::quiet_NaN();
  double best_d2 = std::numeric_limits<double>::infinity();
  for (long y = std::max(0L, y0 - kReach); y <= std::min(long(m.height) - 1, y0 + kReach); ++y)
    for (long x = std::max(0L, x0 - kReach); x <= std::min(long(m.width) - 1, x0 + kReach); ++x) {
      const size_t p = static_cast<size_t>(y) * m.width + x;
      if (m.mask[p] == PixelKind::Outside) continue;
      const double d2 = (x == x0 && y == y0) ? -1.0 : (x + 0.5 - fx) * (x + 0.5 - fx) + (y + 0.5 - fy) * (y + 0.5 - fy);
      if (d2 < best_d2) best_d2 = d2, best = m.error[p];
    }
  return best;
}

std::array<uint8_t, 3> heat_colour(double t) {
  t = std::isnan(t) ? 0.0 : std::clamp(t, 0.0, 1.0);
  const double stops[5][3] = {{0.1, 0.2, 0.9}, {0.0, 0.8, 0.9}, {0.1, 0.8, 0.2}, {0.95, 0.85, 0.1}, {0.9, 0.1, 0.1}};
  const double f = t * 4;
  const int i = std::min(static_cast<int>(f), 3);
  const double s = f - i;
  std::array<uint8_t, 3> c{};
  for (int k = 0; k < 3; ++k)
    c[k] = static_cast<uint8_t>(std::lround(255 * ((1 - s) * stops[i][k] + s * stops[i + 1][k])));
  return c;
}

}  // namespace tbs
