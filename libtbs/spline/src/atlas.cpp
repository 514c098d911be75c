// Atlases (atlas.h): the charts of a domain, the structure of its seams, and how well the two
// sides of every seam agree on the fitted surface.

#include <tbb/parallel_for.h>
#include <tbs/atlas.h>
#include <tbs/domain.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/spline.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>

#include "thread_arena.h"

namespace tbs {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string point_text(const Point2& p) {
  char buf[80];
  std::snprintf(buf, sizeof buf, "(%.9g, %.9g)", p.x(), p.y());
  return buf;
}

double angle_between(const Vector3& a, const Vector3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / kPi;
}

}  // namespace

Charts domain_charts(const Domain& d) {
  const int T = d.triangle_count();
  std::vector<int> parent(static_cast<size_t>(T));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int e = 0; e < d.edge_count(); ++e) {
    const auto t = d.edge_triangles(e);
    if (t[1] < 0) continue;
    const int a = find(t[0]), b = find(t[1]);
    // The smaller triangle index is the root, so that each chart is named by its first one.
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  Charts c;
  c.of_triangle.assign(static_cast<size_t>(T), -1);
  std::vector<int> number(static_cast<size_t>(T), -1);
  for (int t = 0; t < T; ++t) {
    const int r = find(t);
    if (number[r] < 0) number[r] = c.count++;
    c.of_triangle[t] = number[r];
  }
  return c;
}

void check_atlas_structure(const Atlas& atlas, const std::string& name) {
  if (atlas.genus < 0)
    throw InvalidInput(name + ": atlas.genus: " + std::to_string(atlas.genus) + " is negative");
  for (size_t s = 0; s < atlas.seams.size(); ++s) {
    const Seam& seam = atlas.seams[s];
    const std::string where = name + ": atlas.seams[" + std::to_string(s) + "]";
    if (seam.a.size() < 2)
      throw InvalidInput(where + ".a: a seam side needs at least 2 points, got " +
                         std::to_string(seam.a.size()));
    if (seam.b.size() != seam.a.size())
      throw InvalidInput(where + ".b: " + std::to_string(seam.b.size()) +
                         " points, but side a has " + std::to_string(seam.a.size()) +
                         "; the sides are glued point for point");
    for (int side = 0; side < 2; ++side) {
      const auto& line = side == 0 ? seam.a : seam.b;
      for (size_t i = 0; i < line.size(); ++i)
        if (!line[i].allFinite() || line[i].cwiseAbs().maxCoeff() > 1e30)
          throw InvalidInput(where + (side == 0 ? ".a[" : ".b[") + std::to_string(i) +
                             "]: not a finite point of at most 1e30 in magnitude");
    }
  }
  for (size_t b = 0; b < atlas.borders.size(); ++b) {
    const auto& line = atlas.borders[b];
    const std::string where = name + ": atlas.borders[" + std::to_string(b) + "]";
    if (line.size() < 2)
      throw InvalidInput(where + ": a border needs at least 2 points, got " +
                         std::to_string(line.size()));
    for (size_t i = 0; i < line.size(); ++i)
      if (!line[i].allFinite() || line[i].cwiseAbs().maxCoeff() > 1e30)
        throw InvalidInput(where + "[" + std::to_string(i) +
                           "]: not a finite point of at most 1e30 in magnitude");
  }
}

std::vector<std::vector<Point2>> chart_outlines(const Atlas& atlas) {
  // Pieces with their chart on the left: seam sides a, seam sides b reversed, borders.
  std::vector<std::vector<Point2>> pieces;
  for (const Seam& s : atlas.seams) {
    pieces.push_back(s.a);
    pieces.emplace_back(s.b.rbegin(), s.b.rend());
  }
  for (const auto& b : atlas.borders) pieces.push_back(b);
  std::vector<std::vector<Point2>> loops;
  // Closed pieces are loops of their own; the others are joined at equal end points, each
  // end to the piece that starts there (first in order).
  auto key = [](const Point2& p) { return std::make_pair(p.x(), p.y()); };
  std::multimap<std::pair<double, double>, size_t> starting;
  std::vector<char> used(pieces.size(), 0);
  for (size_t i = 0; i < pieces.size(); ++i) {
    if (pieces[i].size() < 2)
      throw InvalidInput("chart_outlines: a piece of outline has fewer than 2 points");
    if (pieces[i].front() == pieces[i].back()) {
      loops.emplace_back(pieces[i].begin(), pieces[i].end() - 1);
      used[i] = 1;
    } else {
      starting.emplace(key(pieces[i].front()), i);
    }
  }
  for (size_t i = 0; i < pieces.size(); ++i) {
    if (used[i]) continue;
    std::vector<Point2> loop;
    size_t at = i;
    for (size_t guard = 0; guard <= pieces.size(); ++guard) {
      used[at] = 1;
      loop.insert(loop.end(), pieces[at].begin(), pieces[at].end() - 1);
      const Point2& end = pieces[at].back();
      if (end == loop.front()) break;
      size_t next = pieces.size();
      auto [lo, hi] = starting.equal_range(key(end));
      for (auto it = lo; it != hi; ++it)
        if (!used[it->second]) {
          next = it->second;
          break;
        }
      if (next == pieces.size())
        throw InvalidInput("chart_outlines: the outline stops at " + point_text(end) +
                           ": no seam side or border goes on from there");
      at = next;
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

bool inside_outlines(const std::vector<std::vector<Point2>>& loops, const Point2& p) {
  bool inside = false;
  for (const auto& loop : loops)
    for (size_t i = 0, j = loop.size() - 1; i < loop.size(); j = i++) {
      const Point2 &a = loop[i], &b = loop[j];
      if ((a.y() > p.y()) != (b.y() > p.y()) &&
          p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
        inside = !inside;
    }
  return inside;
}

OutlineIndex::OutlineIndex(const std::vector<std::vector<Point2>>& loops) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& loop : loops)
    for (size_t i = 0; i < loop.size(); ++i) {
      segments_.push_back({loop[i], loop[(i + 1) % loop.size()]});
      lo = std::min(lo, loop[i].y());
      hi = std::max(hi, loop[i].y());
    }
  if (segments_.empty()) return;
  const size_t R = std::clamp<size_t>(segments_.size() / 4, 1, 4096);
  y0_ = lo;
  dy_ = hi > lo ? (hi - lo) / static_cast<double>(R) : 1.0;
  rows_.resize(R);
  for (size_t k = 0; k < segments_.size(); ++k) {
    const double a = std::min(segments_[k][0].y(), segments_[k][1].y());
    const double b = std::max(segments_[k][0].y(), segments_[k][1].y());
    const size_t r0 =
        static_cast<size_t>(std::clamp((a - y0_) / dy_, 0.0, static_cast<double>(R - 1)));
    const size_t r1 =
        static_cast<size_t>(std::clamp((b - y0_) / dy_, 0.0, static_cast<double>(R - 1)));
    for (size_t r = r0; r <= r1; ++r) rows_[r].push_back(static_cast<int>(k));
  }
}

bool OutlineIndex::inside(const Point2& p) const {
  if (rows_.empty() || !(p.y() >= y0_) || !(p.y() <= y0_ + dy_ * static_cast<double>(rows_.size())))
    return false;
  const size_t r = static_cast<size_t>(
      std::clamp((p.y() - y0_) / dy_, 0.0, static_cast<double>(rows_.size() - 1)));
  bool in = false;
  for (int k : rows_[r]) {
    const Point2 &a = segments_[static_cast<size_t>(k)][0],
                 &b = segments_[static_cast<size_t>(k)][1];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
      in = !in;
  }
  return in;
}

SeamCheck check_seams(const Spline& spline, const Evaluator& eval, const Atlas& atlas,
                      int samples_per_seam, int threads) {
  if (samples_per_seam < 1)
    throw InvalidInput("check_seams: samples per seam must be at least 1, not " +
                       std::to_string(samples_per_seam));
  check_atlas_structure(atlas, "check_seams");
  const Charts charts = domain_charts(spline.domain());
  SeamCheck out;
  const size_t S = atlas.seams.size();
  out.seam_gap.assign(S, 0.0);
  out.seam_angle.assign(S, 0.0);
  std::vector<double> min_angle(S, 180.0);
  std::vector<size_t> outside(S, 0);
  detail::with_threads(threads, [&] {
    tbb::parallel_for(size_t{0}, S, [&](size_t s) {
      const Seam& seam = atlas.seams[s];
      const size_t segments = seam.a.size() - 1;
      // The chart of each side: that of its first sample inside the domain.
      int chart[2] = {-1, -1};
      for (int k = 0; k < samples_per_seam; ++k) {
        // Evenly in the polyline's own parameter: segment index plus fraction.
        const double x = (k + 0.5) / samples_per_seam * static_cast<double>(segments);
        const size_t i = std::min(static_cast<size_t>(x), segments - 1);
        const double f = x - static_cast<double>(i);
        SurfacePoint p[2];
        bool in = true;
        for (int side = 0; side < 2 && in; ++side) {
          const auto& line = side == 0 ? seam.a : seam.b;
          const Point2 u = (1 - f) * line[i] + f * line[i + 1];
          const int t = eval.locate(u);
          const int c = t < 0 ? -1 : charts.of_triangle[static_cast<size_t>(t)];
          if (c >= 0 && chart[side] < 0) chart[side] = c;
          if (c < 0 || c != chart[side]) {
            in = false;
            break;
          }
          p[side] = eval.evaluate(u);
        }
        if (!in) {
          ++outside[s];
          continue;
        }
        out.seam_gap[s] = std::max(out.seam_gap[s], (p[0].position - p[1].position).norm());
        const Vector3 n0 = p[0].du.cross(p[0].dv), n1 = p[1].du.cross(p[1].dv);
        if (n0.norm() > 0 && n1.norm() > 0) {
          const double a = angle_between(n0, n1);
          out.seam_angle[s] = std::max(out.seam_angle[s], a);
          min_angle[s] = std::min(min_angle[s], a);
        }
      }
    });
  });
  for (size_t s = 0; s < S; ++s) out.outside += outside[s];
  bool any_sharp = false;
  out.min_crease = 180;
  for (size_t s = 0; s < S; ++s) {
    out.samples += static_cast<size_t>(samples_per_seam);
    out.max_gap = std::max(out.max_gap, out.seam_gap[s]);
    if (atlas.seams[s].sharp) {
      any_sharp = true;
      out.min_crease = std::min(out.min_crease, min_angle[s]);
      out.max_crease = std::max(out.max_crease, out.seam_angle[s]);
    } else {
      out.max_normal_jump = std::max(out.max_normal_jump, out.seam_angle[s]);
    }
  }
  if (!any_sharp) out.min_crease = 0;
  return out;
}

}  // namespace tbs
