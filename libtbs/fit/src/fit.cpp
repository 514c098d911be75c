// tbs::fit (fit.h): the paper's Algorithm 1, the refinement loop around the domain, the
// solve and the knot moves, with the options' checks, the memory model, progress and the report.

#include <tbs/atlas.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/fit.h>
#include <tbs/knots.h>
#include <tbs/predicates.h>
#include <tbs/shape_check.h>
#include <tbs/tolerances.h>

#include "fit_domain.h"
#include "fit_knots.h"
#include "fit_solve.h"
#include "thread_arena.h"

#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numeric>

namespace tbs {
namespace {

// The largest |F_u|, |F_v| times the domain's diameter over the model size that a knot pass may
// bring a fit to (issue 19's limit for a fair fit).
constexpr double kMaxStretch = 20;

using Clock = std::chrono::steady_clock;

// Below this many points there are too few neighbours to estimate normals: the fairness term
// is left out.
constexpr size_t kMinPointsForNormals = 20;
constexpr int kNormalNeighbours = 18;  // estimate_normals' k

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

void check_options(const FitOptions& o) {
  auto bad = [](const std::string& what) { throw InvalidInput("fit options: " + what); };
  if (o.degree < 1 || o.degree > tol::kMaxDegree)
    bad("degree " + std::to_string(o.degree) + " is out of range; use 1 to " + std::to_string(tol::kMaxDegree));
  if (!(o.tolerance > 0) || !std::isfinite(o.tolerance))
    bad("tolerance must be a positive number (relative to the model size, e.g. 1e-3)");
  if (!(o.tolerance_abs >= 0) || !std::isfinite(o.tolerance_abs)) bad("tolerance_abs must be >= 0");
  if (o.triangles < 0 || o.triangles > 10'000'000) bad("triangles must be between 0 (automatic) and 10^7");
  if (!(o.fairness >= 0) || !std::isfinite(o.fairness)) bad("fairness must be >= 0");
  if (!(o.bending >= 0) || !std::isfinite(o.bending)) bad("bending must be >= 0");
  if (!(o.smoothness >= 0) || !std::isfinite(o.smoothness)) bad("smoothness must be >= 0");
  if (!(o.feature_angle > 0 && o.feature_angle < 180)) bad("feature angle must be between 0 and 180 degrees");
  if (o.max_control_points < 0) bad("max_control_points must be >= 0");
  if (o.max_iterations < 0) bad("max_iterations must be >= 0");
  if (o.knot_sweeps < 0) bad("knot_sweeps must be >= 0");
  if (o.threads < 0) bad("threads must be >= 0");
}

// Knots for a refined domain: the previous knots of vertices that existed before where they
// still satisfy the knot conditions, the default placement elsewhere.
std::vector<Point2> transfer_knots(const Domain& d, int n, const std::vector<int>& ids,
                                   const std::map<int, std::vector<Point2>>& previous) {
  std::vector<Point2> knots = default_knots(d, n);
  const std::vector<Point2> fresh = knots;
  std::vector<char> reverted(d.vertex_count(), 0);
  for (int v = 0; v < d.vertex_count(); ++v) {
    auto it = previous.find(ids[v]);
    if (it == previous.end() || it->second[0] != d.vertex(v)) continue;
    for (int k = 0; k <= n; ++k) knots[static_cast<size_t>(v) * (n + 1) + k] = it->second[k];
  }
  for (int round = 0; round < 8; ++round) {
    const KnotCheck check = check_knot_conditions(d, n, knots);
    if (check.ok()) return knots;
    auto revert = [&](int v) {
      if (v < 0 || reverted[v]) return;
      reverted[v] = 1;
      for (int k = 0; k <= n; ++k)
        knots[static_cast<size_t>(v) * (n + 1) + k] = fresh[static_cast<size_t>(v) * (n + 1) + k];
    };
    for (const auto& issue : check.issues) {
      revert(issue.vertex);
      if (issue.triangle >= 0)
        for (int v : d.triangle(issue.triangle)) revert(v);
    }
  }
  return fresh;
}

struct Errors {
  double max = 0, rms = 0;
};

// The longest edge of the domain triangle at p (infinity outside the domain).
double edge_at(const Spline& spline, const Evaluator& eval, const Point2& p) {
  const Domain& d = spline.domain();
  const int t = eval.locate(p);
  if (t < 0) return std::numeric_limits<double>::infinity();
  double l = 0;
  for (int k = 0; k < 3; ++k) l = std::max(l, (d.vertex(d.triangle(t)[k]) - d.vertex(d.triangle(t)[(k + 1) % 3])).norm());
  return l;
}

// The window of the seams' smoothing, in seam edges of the mesh either side (align_seams).
constexpr double kSeamSmoothing = 0;

// Seams are sampled at this fraction of the longest edge of the domain triangles they cross
// (the smaller of the two sides'): the spline is piecewise polynomial on cells of its knot
// lines, several across a triangle, and the ties must hold between the samples too.
constexpr double kSeamSpacing = 1.0 / 24;

// Weight of a smooth seam's derivative tie against its gap tie. At the gap's weight (1) the
// derivative rows held the folds they met in place: the egg's noisy cloud (tests/closed) ended
// with 547 folds and did not converge, and converges at 0.1 with 0 folds; meshes of closed parts
// and libcgal-demo's closed meshes fit as well or better at 0.1 (fewer folds on blob-closed and
// tripod, none more), their normals across the seams within a degree (docs/benchmarks.md).
constexpr double kSlopeTie = 0.1;

// The seams aligned with the fitted surfaces of their two sides: each seam is resampled at
// kSeamSpacing, and each pair of glued inner points (a, b) moved, each in its own chart, to
// where its surface reaches the midpoint of F(a) and F(b) (Gauss-Newton steps in the
// parameters; the seam's end points, which other seams and borders share, stay). Two charts
// fitted apart meet within the tolerance, but not at the same parameters of their seam
// sides: tied there, one side would have to slide over the other within a band narrower than
// its points, and folds. Tied where they already meet, they join with little strain. J of each
// point: the derivative of the map from b's chart to a's that the two surfaces give, for the
// tangent ties.
struct AlignedSeams {
  Atlas atlas;
  std::vector<std::vector<Eigen::Matrix2d>> J;  // per seam, per point
};

// Gauss-Newton steps in u, inside the domain, toward where F reaches `target` (the point of
// the surface nearest to it). fp is F at u, and at the result on return.
void move_toward(const Evaluator& eval, const Point3& target, Point2& u, SurfacePoint& fp) {
  for (int it = 0; it < 4; ++it) {
    Eigen::Matrix<double, 3, 2> D;
    D << fp.du, fp.dv;
    const Eigen::Matrix2d N = D.transpose() * D;
    if (!(std::abs(N.determinant()) > 0)) return;
    const Vector2 step = N.ldlt().solve(D.transpose() * (target - fp.position));
    if (!step.allFinite()) return;
    const Point2 next = u + step;
    if (eval.locate(next) < 0) return;
    u = next;
    fp = eval.evaluate(u);
    if (step.norm() < 1e-12 * (1 + u.norm())) return;
  }
}

// The point `target`, or the point at distance `reach` from `from` toward it if it is farther:
// alignment corrects what fits within the tolerance disagree on; where two sides are farther
// apart, the fit is still coarse there, and the ties, not the seams, have to bring them
// together.
Point3 toward(const Point3& from, const Point3& target, double reach) {
  const Vector3 d = target - from;
  const double l = d.norm();
  return l > reach && l > 0 ? Point3(from + d * (reach / l)) : target;
}

// J with D_b = D_a J, least squares (the map from b's chart to a's, to first order).
Eigen::Matrix2d transition(const SurfacePoint& fa, const SurfacePoint& fb) {
  Eigen::Matrix<double, 3, 2> Da, Db;
  Da << fa.du, fa.dv;
  Db << fb.du, fb.dv;
  const Eigen::Matrix2d N = Da.transpose() * Da;
  Eigen::Matrix2d J = std::abs(N.determinant()) > 0 ? Eigen::Matrix2d(N.ldlt().solve(Da.transpose() * Db))
                                                    : Eigen::Matrix2d::Identity();
  if (!J.allFinite()) J.setIdentity();
  return J;
}

AlignedSeams align_seams(const Atlas& atlas, const Spline& spline, const Evaluator& eval, double reach) {
  AlignedSeams out;
  out.atlas = atlas;
  out.atlas.seams.clear();
  // The seams' end points first: where seams end, one point of the surface has a copy in each
  // chart around it (a junction), shared by every seam and border that ends there. The copies
  // glued by the seams (by their exact parameters) form one group; each copy moves toward the
  // mean of the group's surface points, and every end at it moves with it.
  auto key = [](const Point2& p) { return std::make_pair(p.x(), p.y()); };
  std::map<std::pair<double, double>, int> copy_of;
  std::vector<Point2> copies;
  auto copy_index = [&](const Point2& p) {
    auto [it, added] = copy_of.emplace(key(p), static_cast<int>(copies.size()));
    if (added) copies.push_back(p);
    return it->second;
  };
  std::vector<std::array<int, 2>> glued;
  for (const Seam& seam : atlas.seams) {
    glued.push_back({copy_index(seam.a.front()), copy_index(seam.b.front())});
    glued.push_back({copy_index(seam.a.back()), copy_index(seam.b.back())});
  }
  std::vector<int> group(copies.size());
  std::iota(group.begin(), group.end(), 0);
  auto find = [&](int x) {
    while (group[static_cast<size_t>(x)] != x) x = group[static_cast<size_t>(x)] = group[static_cast<size_t>(group[static_cast<size_t>(x)])];
    return x;
  };
  for (const auto& g : glued) group[static_cast<size_t>(find(g[0]))] = find(g[1]);
  std::vector<SurfacePoint> at(copies.size());
  std::vector<char> inside(copies.size(), 0);
  std::map<int, std::pair<Point3, int>> mean;
  for (size_t c = 0; c < copies.size(); ++c) {
    if (eval.locate(copies[c]) < 0) continue;
    inside[c] = 1;
    at[c] = eval.evaluate(copies[c]);
    auto& m = mean[find(static_cast<int>(c))];
    if (m.second == 0) m.first = Point3::Zero();
    m.first += at[c].position;
    ++m.second;
  }
  std::vector<Point2> moved = copies;
  for (size_t c = 0; c < copies.size(); ++c) {
    if (!inside[c]) continue;
    const auto& m = mean[find(static_cast<int>(c))];
    move_toward(eval, toward(at[c].position, m.first / m.second, reach), moved[c], at[c]);
  }
  auto end_point = [&](const Point2& p) { return moved[static_cast<size_t>(copy_of.at(key(p)))]; };
  for (auto& border : out.atlas.borders) {
    if (auto it = copy_of.find(key(border.front())); it != copy_of.end()) border.front() = moved[static_cast<size_t>(it->second)];
    if (auto it = copy_of.find(key(border.back())); it != copy_of.end()) border.back() = moved[static_cast<size_t>(it->second)];
  }

  for (const Seam& seam : atlas.seams) {
    // Resampled: (a, b) pairs, each with its surface points.
    struct Pair {
      Point2 a, b;
      bool fixed = false;  // an end point (moved above with its junction), or outside
      SurfacePoint fa, fb;
    };
    std::vector<Pair> pairs;
    const size_t P = seam.a.size();
    double segments = 0;
    for (size_t i = 0; i + 1 < P; ++i) segments += (seam.a[i + 1] - seam.a[i]).norm();
    for (size_t i = 0; i + 1 < P; ++i) {
      const Vector2 da = seam.a[i + 1] - seam.a[i], db = seam.b[i + 1] - seam.b[i];
      const double len = std::max(da.norm(), db.norm());
      const double h = std::min({edge_at(spline, eval, seam.a[i]), edge_at(spline, eval, seam.b[i]),
                                 edge_at(spline, eval, seam.a[i + 1]), edge_at(spline, eval, seam.b[i + 1])});
      const int m = std::isfinite(h) && len > 0 ? std::clamp(static_cast<int>(std::ceil(len / (kSeamSpacing * h))), 1, 4096) : 1;
      for (int k = 0; k < m || (k == m && i + 2 == P); ++k) {
        const double f = static_cast<double>(k) / m;
        const bool first = i == 0 && k == 0, last = i + 2 == P && k == m;
        Pair q;
        q.a = first ? end_point(seam.a.front()) : last ? end_point(seam.a.back()) : Point2(seam.a[i] + f * da);
        q.b = first ? end_point(seam.b.front()) : last ? end_point(seam.b.back()) : Point2(seam.b[i] + f * db);
        q.fixed = first || last || eval.locate(q.a) < 0 || eval.locate(q.b) < 0;
        if (eval.locate(q.a) >= 0 && eval.locate(q.b) >= 0) q.fa = eval.evaluate(q.a), q.fb = eval.evaluate(q.b);
        pairs.push_back(q);
      }
    }
    // The curve where the two sides meet, smoothed along its length over about two of the
    // mesh's seam edges: a seam cut along a noisy mesh zigzags from edge to edge, and two
    // smooth surfaces cannot follow the same zigzag; both sides move onto the smoothed curve
    // (by at most `reach` plus the zigzag's size).
    const size_t Q = pairs.size();
    std::vector<Point3> mid(Q);
    std::vector<double> arc(Q, 0.0);
    for (size_t k = 0; k < Q; ++k) {
      mid[k] = 0.5 * (pairs[k].fa.position + pairs[k].fb.position);
      if (k > 0) arc[k] = arc[k - 1] + (mid[k] - mid[k - 1]).norm();
    }
    const double window = P > 1 ? kSeamSmoothing * segments / static_cast<double>(P - 1) : 0.0;
    const double wiggle = reach + window;
    std::vector<Point3> smooth = mid;
    if (window > 0)
      for (size_t k = 0, lo = 0, hi = 0; k < Q; ++k) {
        if (pairs[k].fixed) continue;
        while (arc[lo] < arc[k] - window) ++lo;
        while (hi + 1 < Q && arc[hi + 1] <= arc[k] + window) ++hi;
        Point3 sum = Point3::Zero();
        double weight = 0;
        for (size_t j = lo; j <= hi; ++j) {
          const double w = 1 - std::abs(arc[j] - arc[k]) / (window * 1.0001);
          sum += w * mid[j];
          weight += w;
        }
        if (weight > 0) smooth[k] = sum / weight;
      }
    Seam s;
    s.sharp = seam.sharp;
    std::vector<Eigen::Matrix2d> Js;
    for (size_t k = 0; k < Q; ++k) {
      Pair& q = pairs[k];
      if (!q.fixed) {
        move_toward(eval, toward(q.fa.position, smooth[k], wiggle), q.a, q.fa);
        move_toward(eval, toward(q.fb.position, smooth[k], wiggle), q.b, q.fb);
      }
      s.a.push_back(q.a);
      s.b.push_back(q.b);
      Js.push_back(eval.locate(q.a) >= 0 && eval.locate(q.b) >= 0 ? transition(q.fa, q.fb) : Eigen::Matrix2d::Identity());
    }
    out.atlas.seams.push_back(std::move(s));
    out.J.push_back(std::move(Js));
  }
  return out;
}

// The ties of the seams (METHOD.md section 10, fit_solve.h): at every point of the (aligned)
// seams and between them every kSeamSpacing of the longest edge of the domain triangles met; a
// gap term everywhere, and on smooth seams a tie of the derivatives across the seam: along the
// normal of the seam's direction in b's chart (its direction over about half a domain edge, so
// that the mesh's zigzags do not turn it), and along J times that in a's chart, with the J of
// the segment's first point (or, before any alignment, the similarity that takes segment b
// onto segment a: the charts' flattenings are conformal, their transition one to first order).
std::vector<detail::SeamTie> seam_ties(const Atlas& atlas, const std::vector<std::vector<Eigen::Matrix2d>>& Js,
                                       const Spline& spline, const Evaluator& eval) {
  std::vector<detail::SeamTie> ties;
  for (size_t si = 0; si < atlas.seams.size(); ++si) {
    const Seam& seam = atlas.seams[si];
    const size_t P = seam.a.size();
    // Arc length of side b at each point, for the smoothed direction.
    std::vector<double> arc(P, 0.0);
    for (size_t i = 1; i < P; ++i) arc[i] = arc[i - 1] + (seam.b[i] - seam.b[i - 1]).norm();
    auto direction_b = [&](size_t i, double f, double h) {
      // The chord of side b over +- h / 4 of arc length around the point.
      const double here = arc[i] + f * (i + 1 < P ? arc[i + 1] - arc[i] : 0.0);
      auto point_at = [&](double s) {
        s = std::clamp(s, 0.0, arc.back());
        const size_t k = std::min<size_t>(static_cast<size_t>(std::upper_bound(arc.begin(), arc.end(), s) - arc.begin()), P - 1);
        const size_t j = k == 0 ? 0 : k - 1;
        const double len = arc[k] - arc[j];
        const double g = len > 0 ? (s - arc[j]) / len : 0.0;
        return Point2(seam.b[j] + g * (seam.b[k] - seam.b[j]));
      };
      const double r = std::isfinite(h) ? 0.25 * h : 0.0;
      Vector2 t = point_at(here + r) - point_at(here - r);
      if (!(t.norm() > 0)) t = seam.b[std::min(i + 1, P - 1)] - seam.b[i];
      return t.norm() > 0 ? Vector2(t.normalized()) : Vector2(1, 0);
    };
    for (size_t i = 0; i + 1 < P; ++i) {
      const Vector2 da = seam.a[i + 1] - seam.a[i], db = seam.b[i + 1] - seam.b[i];
      Eigen::Matrix2d J = Eigen::Matrix2d::Identity();
      if (const double nb = db.squaredNorm(); nb > 0) {
        // da / db as complex numbers.
        const double re = (da.x() * db.x() + da.y() * db.y()) / nb, im = (da.y() * db.x() - da.x() * db.y()) / nb;
        J << re, -im, im, re;
      }
      // The transition measured on the two surfaces, where it keeps the orientation the two
      // flattenings give the seam: where one side has folded over near the seam (an
      // extrapolation beyond a cloud's last points can), the measured J mirrors, and tying the
      // derivatives with it would hold the fold in place.
      if (si < Js.size() && i < Js[si].size() && Js[si][i].determinant() > 0) J = Js[si][i];
      const double len = std::max(da.norm(), db.norm());
      for (double f = 0;;) {
        const Point2 a = seam.a[i] + f * da, b = seam.b[i] + f * db;
        const double h = std::min(edge_at(spline, eval, a), edge_at(spline, eval, b));
        detail::SeamTie t;
        t.a = a;
        t.b = b;
        t.c0 = 1;
        t.c1 = seam.sharp || !std::isfinite(h) ? 0.0 : kSlopeTie;
        const Vector2 tb = direction_b(i, f, h);
        t.cross_b = Vector2(tb.y(), -tb.x());
        t.cross_a = J * t.cross_b;
        ties.push_back(t);
        if (f >= 1) break;
        const double step = std::isfinite(h) && len > 0 ? kSeamSpacing * h / len : 1.0;
        f = std::min(1.0, f + std::max(step, 1e-3));
        // The segment's end is the next one's start; the seam's last point is its own.
        if (f >= 1 && i + 2 != P) break;
      }
    }
  }
  return ties;
}

}  // namespace

std::string FitReport::to_json(bool with_times) const {
  nlohmann::ordered_json j;
  j["points"] = points;
  j["points_excluded"] = points_excluded;
  j["guide_points"] = guide_points;
  j["degree"] = degree;
  j["domain_triangles"] = domain_triangles;
  j["domain_vertices"] = domain_vertices;
  j["feature_edges"] = feature_edges;
  j["holes"] = holes;
  j["control_points"] = control_points;
  j["max_error"] = max_error;
  j["rms_error"] = rms_error;
  j["max_error_abs"] = max_error_abs;
  j["rms_error_abs"] = rms_error_abs;
  j["tolerance"] = tolerance;
  j["tolerance_abs"] = tolerance_abs;
  j["scale"] = scale;
  j["fairness"] = fairness;
  j["bending"] = bending;
  j["smoothness"] = smoothness;
  j["converged"] = converged;
  j["stop_reason"] = stop_reason;
  j["iterations"] = iterations;
  j["normals_estimated"] = normals_estimated;
  j["folds"] = folds;
  j["max_stretch"] = max_stretch;
  j["charts"] = charts;
  j["seams"] = seams;
  j["closed"] = closed;
  j["genus"] = genus;
  j["seam_gap"] = seam_gap;
  j["seam_gap_abs"] = seam_gap_abs;
  j["seam_normal_jump"] = seam_normal_jump;
  j["seam_crease_min"] = seam_crease_min;
  j["seam_crease_max"] = seam_crease_max;
  j["seam_samples_outside"] = seam_samples_outside;
  if (with_times) {
    j["memory_estimate"] = memory_estimate;
    j["seconds"] = seconds;
    nlohmann::ordered_json st = nlohmann::ordered_json::object();
    for (const auto& [k, v] : stage_seconds) st[k] = v;
    j["stage_seconds"] = st;
    const SolveStages& ss = solve_stages;
    j["solve_stages"] = {{"solves", ss.solves},         {"pattern", ss.pattern},
                         {"basis_rows", ss.basis_rows}, {"assembly", ss.assembly},
                         {"analysis", ss.analysis},     {"factorization", ss.factorization},
                         {"solve", ss.solve},           {"cg_iterations", ss.cg_iterations},
                         {"unknowns", ss.unknowns},     {"nonzeros", ss.nonzeros}};
  }
  nlohmann::ordered_json r = nlohmann::ordered_json::array();
  for (const auto& x : rounds)
    r.push_back({{"domain_triangles", x.triangles},
                 {"control_points", x.control_points},
                 {"max_error", x.max_error},
                 {"rms_error", x.rms_error}});
  j["rounds"] = r;
  return j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

namespace {

// The memory model of estimate_fit_memory(): bytes = base + points * p + control points * c
// b^1.75, b = beta_count(n) (basis functions per triangle; the per-triangle systems, the
// evaluator's graph and the sparse factor grow with it), fitted to the peak resident sets of
// `tbs fit` on synthetic scans of 100k to 1M points at degrees 2 to 5 with 1,195 to 101,398
// control points (bench/memory_bench.sh and bench/solve_profile.sh, docs/benchmarks.md
// "Memory", 2026-12-05, after the split solve): at or above every row, by at most 37 %,
// before the safety factor. The kept basis rows (fit_solve.h) came later with their own term;
// with them every row is still below the estimate (the night's table there).
constexpr double kMemoryBase = 40e6;
constexpr double kMemoryPerPoint = 420;
constexpr double kMemoryPerControlPoint = 290;  // times b^1.75
constexpr double kMemorySafety = 1.25;

// Weight of a guide point (Scan::guide) against a measured one, in every term of the fit.
constexpr double kGuideWeight = 0.1;

std::string format_bytes(double bytes) {
  char s[32];
  if (bytes >= 1 << 30)
    std::snprintf(s, sizeof s, "%.1f GiB", bytes / (1 << 30));
  else
    std::snprintf(s, sizeof s, "%.0f MiB", std::max(1.0, bytes / (1 << 20)));
  return s;
}

}  // namespace

size_t estimate_fit_memory(size_t points, int degree, size_t control_points) {
  const double b = beta_count(std::clamp(degree, 1, tol::kMaxDegree));
  // The basis rows a solve keeps between its passes (fit_solve.h).
  const double rows = static_cast<double>(detail::row_cache_budget(points, degree));
  const double bytes = kMemoryBase + static_cast<double>(points) * kMemoryPerPoint + rows +
                       static_cast<double>(control_points) * kMemoryPerControlPoint * std::pow(b, 1.75);
  return static_cast<size_t>(std::min(bytes * kMemorySafety, 1e19));
}

size_t initial_control_points(size_t points, const FitOptions& options) {
  const double triangles = options.triangles > 0 ? options.triangles
                                                 : std::clamp(static_cast<double>(points / 200), 32.0, 4000.0);
  // A disk-like triangulation has about F/2 vertices and 3F/2 edges for F triangles; a control
  // point per vertex, n - 1 per edge and (n - 1)(n - 2)/2 inside each triangle.
  const double n = std::clamp(options.degree, 1, tol::kMaxDegree);
  return static_cast<size_t>(triangles * (0.5 + 1.5 * (n - 1) + (n - 1) * (n - 2) / 2) + 0.5);
}

void check_fit_memory(const std::string& name, size_t points, const FitOptions& options) {
  if (options.max_memory == 0) return;
  const size_t need = estimate_fit_memory(points, options.degree, initial_control_points(points, options));
  if (need <= options.max_memory) return;
  throw InvalidInput(name + ": fitting " + std::to_string(points) + " points at degree " +
                     std::to_string(options.degree) + " needs about " + format_bytes(need) +
                     " of memory, more than the limit of " + format_bytes(options.max_memory) + " (" +
                     options.max_memory_name + "); fit a decimated or cropped scan" +
                     (options.degree > 2 ? ", use a lower degree" : "") + ", or raise " +
                     options.max_memory_name + " if the machine has that much memory free");
}

namespace {

// The most control points a fit of `points` points at degree n can have within `max_memory`
// (0 = no limit: the largest size_t).
size_t affordable_control_points(size_t points, int degree, size_t max_memory) {
  if (max_memory == 0) return std::numeric_limits<size_t>::max();
  const size_t fixed = estimate_fit_memory(points, degree, 0);
  if (fixed >= max_memory) return 0;
  const size_t per = estimate_fit_memory(points, degree, 1'000'000) - fixed;  // per million
  return static_cast<size_t>(static_cast<double>(max_memory - fixed) / static_cast<double>(per) * 1e6);
}

}  // namespace

namespace {
FitResult fit_scan(const Scan& scan, const FitOptions& opt);
}

FitResult fit(const Scan& scan, const FitOptions& opt) {
  try {
    return fit_scan(scan, opt);
  } catch (const SolverError& e) {
    // Solver messages name no input; messages start with the scan's name.
    throw SolverError((scan.source.empty() ? std::string("<scan>") : scan.source) + ": " + e.what());
  }
}

namespace {

FitResult fit_scan(const Scan& scan, const FitOptions& opt) {
  const auto t_start = Clock::now();
  check_options(opt);
  const std::string name = scan.source.empty() ? "<scan>" : scan.source;
  const size_t N = scan.positions.size();
  check_fit_memory(name, N, opt);
  if (!scan.has_uv())
    throw InvalidInput(name + ": this input has no parameters (u, v); compute them with "
                       "parameterize_scan() (the tbs command does so), or give a PLY with u v (or s t, "
                       "texture_u texture_v) properties, an OBJ with vt, or an .xyz with 5 or 8 columns");
  if (scan.uv.size() != N) throw InvalidInput(name + ": " + std::to_string(scan.uv.size()) +
                                              " parameters for " + std::to_string(N) + " points");
  if (scan.has_normals() && scan.normals.size() != N)
    throw InvalidInput(name + ": " + std::to_string(scan.normals.size()) + " normals for " +
                       std::to_string(N) + " points");
  if (N < 3) throw InvalidInput(name + ": a fit needs at least 3 points, got " + std::to_string(N));
  if (!scan.guide.empty() && scan.guide.size() != N)
    throw InvalidInput(name + ": " + std::to_string(scan.guide.size()) + " guide flags for " + std::to_string(N) +
                       " points");
  // Guides (Scan::guide) enter the fit with kGuideWeight and are not measured.
  auto guide = [&](size_t i) { return !scan.guide.empty() && scan.guide[i] != 0; };
  std::vector<double> weight;
  if (!scan.guide.empty()) {
    weight.resize(N);
    for (size_t i = 0; i < N; ++i) weight[i] = guide(i) ? kGuideWeight : 1.0;
  }
  for (size_t i = 0; i < N; ++i) {
    if (!scan.positions[i].allFinite() || !scan.uv[i].allFinite() ||
        (scan.has_normals() && !scan.normals[i].allFinite()))
      throw InvalidInput(name + ": point " + std::to_string(i) +
                         " has a non-finite coordinate, parameter or normal");
    if (scan.positions[i].cwiseAbs().maxCoeff() > 1e30 || scan.uv[i].cwiseAbs().maxCoeff() > 1e30)
      throw InvalidInput(name + ": point " + std::to_string(i) +
                         " has a coordinate or parameter larger than 1e30 in magnitude");
    if (scan.has_normals() && std::abs(scan.normals[i].norm() - 1) > 1e-6)
      throw InvalidInput(name + ": normal " + std::to_string(i) + " has length " +
                         std::to_string(scan.normals[i].norm()) + "; normals must be unit vectors");
  }
  for (const auto& t : scan.triangles)
    for (int v : t)
      if (v < 0 || static_cast<size_t>(v) >= N)
        throw InvalidInput(name + ": a triangle refers to point " + std::to_string(v) + " of " +
                           std::to_string(N));

  FitResult res;
  FitReport& rep = res.report;
  rep.guide_points = static_cast<size_t>(std::count_if(scan.guide.begin(), scan.guide.end(), [](std::uint8_t g) { return g != 0; }));
  std::map<std::string, double> stage;
  auto progress = [&](const std::string& st, const std::string& msg, double f) {
    if (opt.stop.stop_requested()) throw Cancelled(name + ": the fit was cancelled (" + st + ")");
    if (opt.progress) opt.progress({st, msg, f});
  };
  const int n = opt.degree;
  rep.points = N;
  rep.degree = n;
  rep.fairness = opt.fairness;
  rep.bending = opt.bending;
  rep.smoothness = opt.smoothness;

  // The box (and so the relative tolerance) of the measured points: guides do not change it.
  if (rep.guide_points == N) throw InvalidInput(name + ": every point is a guide; a fit needs measured points");
  Box3 box;
  for (size_t i = 0; i < N; ++i)
    if (!guide(i)) box.extend(scan.positions[i]);
  const Vector3 ext = box.max - box.min;
  rep.scale = ext.maxCoeff();
  if (!(rep.scale > 0)) throw InvalidInput(name + ": all points are identical");
  rep.tolerance_abs = opt.tolerance_abs > 0 ? opt.tolerance_abs : opt.tolerance * rep.scale;
  rep.tolerance = rep.tolerance_abs / rep.scale;

  // Normals for the fairness term.
  std::vector<Vector3> normals;
  {
    const auto t0 = Clock::now();
    if (scan.has_normals()) {
      normals = scan.normals;
    } else if (opt.fairness > 0 && N >= kMinPointsForNormals) {
      progress("normals", "estimating normals of " + std::to_string(N) + " points", 0);
      try {
        const auto report = [&](double f) {
          char text[96];
          std::snprintf(text, sizeof text, "estimating normals: %.0f %% of %zu points", 100 * f, N);
          progress("normals", text, f);
        };
        // Inside an arena of opt.threads: the estimate is a plain TBB loop.
        detail::with_threads(opt.threads, [&] {
          normals = estimate_normals(scan.positions, scan.uv, scan.triangles, kNormalNeighbours, report);
        });
      } catch (const InvalidInput& e) {
        throw InvalidInput(name + ": cannot estimate normals (" + e.what() +
                           "); give normals in the input, or turn the fairness term off (--fairness 0)");
      }
      rep.normals_estimated = true;
    } else {
      normals.assign(N, Vector3::Zero());
    }
    stage["normals"] += seconds_since(t0);
  }

  // Initial domain.
  const int target = opt.triangles > 0 ? opt.triangles
                                       : std::clamp(static_cast<int>(N / 200), 32, 4000);
  progress("domain", "building the domain (about " + std::to_string(target) + " triangles)", 0);
  auto t0 = Clock::now();
  detail::DomainInput din{scan.uv, scan.positions, scan.triangles, target, opt.features, opt.feature_angle,
                          !scan.atlas.empty()};

  std::unique_ptr<detail::FitDomain> fdom_ptr;
  try {
    // Inside an arena of opt.threads: parts of the build are plain TBB loops.
    detail::with_threads(opt.threads, [&] { fdom_ptr = std::make_unique<detail::FitDomain>(din); });
  } catch (const InvalidInput& e) {
    throw InvalidInput(name + ": " + e.what());
  }
  detail::FitDomain& fdom = *fdom_ptr;
  stage["domain"] += seconds_since(t0);
  std::vector<detail::SeamTie> ties;
  AlignedSeams seams{scan.atlas, {}};

  // The fairness term of a point is weighted by the squared longest edge of its domain
  // triangle: (h n.F_u)^2 is a length, like the distance term, so the weight is dimensionless
  // and does not grow stronger as refinement shrinks the triangles.
  const double lambda = opt.fairness;
  std::vector<double> fair(N, 0.0);
  std::vector<double> bend, jerk;
  const size_t budget_cp = opt.max_control_points > 0 ? static_cast<size_t>(opt.max_control_points)
                                                      : std::max<size_t>(N, 16);
  const size_t memory_cp = affordable_control_points(N, n, opt.max_memory);
  const size_t max_cp = std::min(budget_cp, memory_cp);

  std::vector<Point2> uv(scan.uv.begin(), scan.uv.end());
  std::vector<int> located(N, -1);
  std::vector<int> order, start;
  std::vector<Point2> knots = default_knots(fdom.domain(), n);
  std::vector<Point3> positions(N);
  std::vector<double> err(N, 0.0);
  std::vector<Point3> previous_cp;
  detail::SolveTimes solve_times;
  detail::KeptRows kept_rows;  // basis rows one solve leaves to the next (the knot search's re-solves)

  for (int iter = 0;; ++iter) {
    Spline spline = Spline::with_canonical_map(n, fdom.domain(), knots);
    if (!previous_cp.empty() && previous_cp.size() == static_cast<size_t>(spline.control_point_count()))
      spline.control_points() = previous_cp;
    Evaluator eval(spline);
    ties.clear();

    // Locate the points where the evaluator (and `tbs eval`) will: the domain builder keeps
    // every point of the region inside the domain; one it could not is left out and counted.
    t0 = Clock::now();
    // Each point's domain triangle (-1: excluded or outside), in parallel in an arena of
    // opt.threads (each point writes its own entry).
    auto locate_all = [&] {
      detail::with_threads(opt.threads, [&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, N, 4096), [&](const tbb::blocked_range<size_t>& r) {
          for (size_t i = r.begin(); i != r.end(); ++i) located[i] = fdom.excluded()[i] ? -1 : eval.locate(uv[i]);
        });
      });
    };
    locate_all();
    size_t used = 0;
    size_t measured = 0;
    for (size_t i = 0; i < N; ++i) used += located[i] >= 0, measured += located[i] >= 0 && !guide(i);
    if (measured == 0) throw InvalidInput(name + ": no point lies in the fitting domain");
    rep.points_excluded = N - used;
    stage["domain"] += seconds_since(t0);

    auto make_points = [&] {
      const Domain& d = spline.domain();
      detail::group_by_triangle(located, d.triangle_count(), order, start);
      // Estimated normals average the two sides of a crease: no fairness next to features.
      std::vector<char> at_feature(d.vertex_count(), 0);
      if (rep.normals_estimated)
        for (const auto& e : d.feature_edges()) at_feature[e[0]] = at_feature[e[1]] = 1;
      // Squared longest edge and area of each triangle, for both terms' weights.
      const int T = d.triangle_count();
      std::vector<double> longest2(T), area(T);
      for (int t = 0; t < T; ++t) {
        const auto& tri = d.triangle(t);
        for (int k = 0; k < 3; ++k)
          longest2[t] = std::max(longest2[t], (d.vertex(tri[k]) - d.vertex(tri[(k + 1) % 3])).squaredNorm());
        const Vector2 e1 = d.vertex(tri[1]) - d.vertex(tri[0]), e2 = d.vertex(tri[2]) - d.vertex(tri[0]);
        area[t] = 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
      }
      for (size_t i = 0; i < N; ++i) {
        if (located[i] < 0) continue;
        const auto& t = d.triangle(located[i]);
        fair[i] = at_feature[t[0]] || at_feature[t[1]] || at_feature[t[2]] ? 0.0 : longest2[located[i]];
      }
      // Bending and smoothness: weights density * h^4 and density * h^6 per triangle (so that
      // h^2 |F_uu| and h^3 |F_uuu| compare with the point distances as lengths), with the
      // density of the points in use over the whole domain, so that triangles with few points
      // are held by them. Where a triangle has more points than control points of its own
      // (beta_count), the points decide its shape and the terms would only bias it: there the
      // weights drop by (beta_count / points)^2.
      bend.assign(opt.bending > 0 ? T : 0, 0.0);
      jerk.assign(opt.smoothness > 0 ? T : 0, 0.0);
      if (opt.bending > 0 || opt.smoothness > 0) {
        const double total_area = std::accumulate(area.begin(), area.end(), 0.0);
        // Points counted with their weights (guides).
        std::vector<double> mass(T, 0.0);
        for (int t = 0; t < T; ++t)
          for (int q = start[t]; q < start[t + 1]; ++q) mass[t] += weight.empty() ? 1.0 : weight[order[q]];
        const double total_mass = std::accumulate(mass.begin(), mass.end(), 0.0);
        const double density = total_area > 0 ? total_mass / total_area : 0.0;
        const double own = beta_count(n);
        for (int t = 0; t < T; ++t) {
          const double here = mass[t];
          const double w = density * (here > own ? (own / here) * (own / here) : 1.0);
          const double h4 = longest2[t] * longest2[t];
          if (!bend.empty()) bend[t] = opt.bending * w * h4;
          if (!jerk.empty()) jerk[t] = opt.smoothness * w * h4 * longest2[t];
        }
      }
      return detail::FitPoints{scan.positions, normals, uv, located, order, start, fair, bend, jerk, weight, ties};
    };
    auto solve = [&] {
      const auto ts = Clock::now();
      progress("solve", "round " + std::to_string(iter + 1) + ": solving " +
                            std::to_string(spline.control_point_count()) + " control points",
               0);
      spline.control_points() =
          detail::solve_control_points(spline, eval, make_points(), lambda, opt.threads, &solve_times,
                                       detail::Solver::Split, detail::row_cache_budget(N, n), &kept_rows);
      stage["solve"] += seconds_since(ts);
    };
    if (!seams.atlas.empty()) {
      // The first round: the charts fitted apart, their seams aligned where the surfaces meet,
      // then tied (align_seams).
      solve();
      progress("solve", "aligning " + std::to_string(seams.atlas.seams.size()) + " seams with the fitted surfaces", 0);
      seams = align_seams(scan.atlas, spline, eval, std::numeric_limits<double>::infinity());
    }
    ties = seam_ties(seams.atlas, seams.J, spline, eval);
    solve();

    // Errors per point.
    auto measure = [&] {
      progress("error", "round " + std::to_string(iter + 1) + ": measuring the error at " + std::to_string(N) +
                            " points",
               0);
      const auto ts = Clock::now();
      std::vector<uint8_t> inside(N);
      eval.evaluate_batch(uv, positions, {}, {}, inside, opt.threads);
      double sum = 0, mx = 0;
      size_t cnt = 0;
      for (size_t i = 0; i < N; ++i) {
        if (located[i] < 0) {
          err[i] = std::numeric_limits<double>::quiet_NaN();
          continue;
        }
        err[i] = (scan.positions[i] - positions[i]).norm();
        if (guide(i)) continue;
        sum += err[i] * err[i];
        mx = std::max(mx, err[i]);
        ++cnt;
      }
      stage["error"] += seconds_since(ts);
      return Errors{mx, std::sqrt(sum / std::max<size_t>(cnt, 1))};
    };
    Errors e = measure();

    // Free knots: OptimizeKnot on the vertices of triangles with large errors, then re-solve.
    if (opt.knot_sweeps > 0 && e.max > rep.tolerance_abs) {
      const Domain& d = spline.domain();
      // The knot search judges moves by the local points alone; the smoothness terms of the
      // global solve do not enter it. A pass after which the surface folds in more triangles
      // than before, or stretches beyond kMaxStretch and by more than 10 %, is undone.
      ShapeCheck shape = check_shape(spline, eval, 8, opt.threads, rep.tolerance_abs, seams.atlas);
      for (int sweep = 0; sweep < opt.knot_sweeps; ++sweep) {
        const auto ts = Clock::now();
        std::vector<double> tri_err(d.triangle_count(), 0.0);
        for (size_t i = 0; i < N; ++i)
          if (located[i] >= 0 && !guide(i)) tri_err[located[i]] = std::max(tri_err[located[i]], err[i]);
        std::vector<char> want(d.vertex_count(), 0);
        for (int t = 0; t < d.triangle_count(); ++t)
          if (tri_err[t] > rep.tolerance_abs)
            for (int v : d.triangle(t)) want[v] = 1;
        std::vector<int> verts;
        for (int v = 0; v < d.vertex_count(); ++v)
          if (want[v]) verts.push_back(v);
        progress("knots", "round " + std::to_string(iter + 1) + ": optimizing the knots of " +
                              std::to_string(verts.size()) + " vertices",
                 0);
        const auto pts = make_points();
        const std::vector<Point2> saved_knots = spline.knots();
        const std::vector<Point3> saved_cp = spline.control_points();
        const std::vector<double> saved_err = err;
        const Errors saved_e = e;
        std::vector<int> moved_primary;  // in the order the moves were made
        const auto st = detail::optimize_knots(spline, eval, located, pts, lambda, verts,
                                               [&](int v, const Point2& p) {
                                                 moved_primary.push_back(v);
                                                 fdom.move_vertex(fdom.ids()[v], p);
                                               },
                                               opt.threads);
        stage["knots"] += seconds_since(ts);
        {
          char msg[160];
          std::snprintf(msg, sizeof msg, "round %d: knots of %d vertices tried, %d moved, local energy %.2f %% lower",
                        iter + 1, st.vertices, st.moved,
                        st.energy_before > 0 ? 100 * (st.energy_before - st.energy_after) / st.energy_before : 0.0);
          progress("knots", msg, 1);
        }
        if (st.moved == 0) break;
        solve();
        e = measure();
        const ShapeCheck after = check_shape(spline, eval, 8, opt.threads, rep.tolerance_abs, seams.atlas);
        if (after.folded_triangles.size() > shape.folded_triangles.size() ||
            after.max_stretch > std::max(1.1 * shape.max_stretch, kMaxStretch)) {
          // Undo: sub-knots first, then the primary knots in reverse order (each step back is
          // the reverse of a valid move), the domain with them.
          const int stride = n + 1;
          std::vector<int> changed;
          for (int v = 0; v < d.vertex_count(); ++v) {
            bool any = false;
            for (int k = 1; k <= n; ++k)
              if (spline.knot(v, k) != saved_knots[static_cast<size_t>(v) * stride + k]) {
                spline.set_knot(v, k, saved_knots[static_cast<size_t>(v) * stride + k]);
                any = true;
              }
            if (any || spline.knot(v, 0) != saved_knots[static_cast<size_t>(v) * stride]) changed.push_back(v);
          }
          for (auto it = moved_primary.rbegin(); it != moved_primary.rend(); ++it) {
            const Point2& p = saved_knots[static_cast<size_t>(*it) * stride];
            spline.set_knot(*it, 0, p);
            fdom.move_vertex(fdom.ids()[*it], p);
          }
          for (int v : changed) eval.update_knots(v);
          locate_all();
          spline.control_points() = saved_cp;
          err = saved_err;
          e = saved_e;
          char msg[200];
          std::snprintf(msg, sizeof msg, "round %d: knot moves undone: the surface would fold in %zu triangles "
                        "(%zu before) and stretch to %.3g (%.3g before)", iter + 1, after.folded_triangles.size(),
                        shape.folded_triangles.size(), after.max_stretch, shape.max_stretch);
          progress("knots", msg, 1);
          break;
        }
        shape = after;
        // The energy stalls: another pass would gain less than 1 %.
        if (st.energy_before - st.energy_after < 0.01 * st.energy_before) break;
      }
    }

    rep.rounds.push_back({spline.domain().triangle_count(), spline.control_point_count(),
                          e.max / rep.scale, e.rms / rep.scale});
    // Progress toward the tolerance, on a log scale from the first round's error.
    const double e0 = rep.rounds.front().max_error * rep.scale;
    const double frac = e.max <= rep.tolerance_abs ? 1.0
                        : e0 <= rep.tolerance_abs || e.max >= e0
                            ? 0.0
                            : std::log(e0 / e.max) / std::log(e0 / rep.tolerance_abs);
    char msg[160];
    std::snprintf(msg, sizeof msg, "round %d: %d triangles, %d control points, max error %.3g (target %.3g)",
                  iter + 1, spline.domain().triangle_count(), spline.control_point_count(),
                  e.max / rep.scale, rep.tolerance);
    progress("refine", msg, frac);
    rep.iterations = iter + 1;
    auto finish = [&](bool converged, const std::string& why) {
      rep.converged = converged;
      rep.stop_reason = why;
      rep.max_error_abs = e.max;
      rep.rms_error_abs = e.rms;
      rep.max_error = e.max / rep.scale;
      rep.rms_error = e.rms / rep.scale;
      rep.domain_triangles = spline.domain().triangle_count();
      rep.domain_vertices = spline.domain().vertex_count();
      rep.feature_edges = static_cast<int>(spline.domain().feature_edges().size());
      rep.holes = static_cast<int>(spline.domain().boundary_loops().size()) - 1;
      rep.control_points = spline.control_point_count();
      rep.memory_estimate = estimate_fit_memory(N, n, static_cast<size_t>(rep.control_points));
      const ShapeCheck shape = check_shape(spline, eval, 8, opt.threads, rep.tolerance_abs, seams.atlas);
      rep.folds = static_cast<int>(shape.folded_triangles.size());
      rep.max_stretch = shape.max_stretch;
      rep.charts = domain_charts(spline.domain()).count;
      rep.seams = static_cast<int>(scan.atlas.seams.size());
      rep.closed = scan.atlas.closed;
      rep.genus = scan.atlas.genus;
      if (!scan.atlas.empty()) {
        const SeamCheck check = check_seams(spline, eval, seams.atlas, 1000, opt.threads);
        rep.seam_gap_abs = check.max_gap;
        rep.seam_gap = check.max_gap / rep.scale;
        rep.seam_normal_jump = check.max_normal_jump;
        rep.seam_crease_min = check.min_crease;
        rep.seam_crease_max = check.max_crease;
        rep.seam_samples_outside = check.outside;
      }
      res.atlas = seams.atlas;
      res.spline = std::move(spline);
    };
    if (e.max <= rep.tolerance_abs) {
      finish(true, "tolerance reached");
      break;
    }
    if (iter >= opt.max_iterations) {
      finish(false, "iteration limit (" + std::to_string(opt.max_iterations) + ") reached");
      break;
    }

    // Refinement: split the triangles with large errors, worst first, within the budget.
    const Domain& d = spline.domain();
    std::vector<double> tri_err(d.triangle_count(), 0.0);
    for (size_t i = 0; i < N; ++i)
      if (located[i] >= 0 && !guide(i)) tri_err[located[i]] = std::max(tri_err[located[i]], err[i]);
    std::vector<int> bad;
    for (int t = 0; t < d.triangle_count(); ++t)
      if (tri_err[t] > rep.tolerance_abs) bad.push_back(t);
    std::stable_sort(bad.begin(), bad.end(), [&](int a, int b) { return tri_err[a] > tri_err[b]; });
    const size_t per_split = static_cast<size_t>(n) * n;  // 1 vertex, 3 edges, 2 more triangles
    const size_t room = max_cp > static_cast<size_t>(spline.control_point_count())
                            ? (max_cp - spline.control_point_count()) / per_split
                            : 0;
    if (room == 0) {
      if (memory_cp < budget_cp)
        finish(false, "memory limit (" + format_bytes(static_cast<double>(opt.max_memory)) + ", " +
                          opt.max_memory_name + ") reached at " + std::to_string(spline.control_point_count()) +
                          " control points");
      else
        finish(false, "control-point budget (" + std::to_string(max_cp) + ") reached");
      break;
    }
    if (bad.size() > room) bad.resize(room);
    std::sort(bad.begin(), bad.end());
    t0 = Clock::now();
    std::map<int, std::vector<Point2>> prev;
    for (int v = 0; v < d.vertex_count(); ++v) {
      std::vector<Point2> k(n + 1);
      for (int l = 0; l <= n; ++l) k[l] = spline.knot(v, l);
      prev[fdom.ids()[v]] = std::move(k);
    }
    const int before = d.triangle_count();
    fdom.split(bad);
    if (fdom.domain().triangle_count() == before) {
      finish(false, "the triangles with large errors cannot be split further");
      break;
    }
    knots = transfer_knots(fdom.domain(), n, fdom.ids(), prev);
    previous_cp.clear();
    stage["refine"] += seconds_since(t0);
  }

  res.uv = std::move(uv);
  res.error = std::move(err);
  rep.seconds = seconds_since(t_start);
  for (const char* s : {"normals", "domain", "solve", "knots", "refine", "error"})
    rep.stage_seconds.emplace_back(s, stage[s]);
  rep.solve_stages = {solve_times.solves,   solve_times.pattern,       solve_times.basis_rows,
                      solve_times.assembly, solve_times.analysis,      solve_times.factorization,
                      solve_times.solve,    solve_times.cg_iterations, solve_times.unknowns,
                      solve_times.nonzeros};
  return res;
}

}  // namespace

}  // namespace tbs
