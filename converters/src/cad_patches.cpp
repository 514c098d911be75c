#include <tbs/bezier.h>
#include <tbs/cad_patches.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/predicates.h>

#include "side_eval.h"

#include <Eigen/Cholesky>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace tbs {

namespace {

// Patch corners are dyadic barycentric coordinates of their domain triangle: integers that
// sum to kOne, so that 1-to-4 splits are exact and corners are compared exactly.
constexpr int kBits = 24;
constexpr int64_t kOne = int64_t(1) << kBits;
using IBary = std::array<int64_t, 3>;
// Normals are compared where sin(angle between F_u and F_v) is at least this.
constexpr double kRegular = 1e-2;
// Splitting aims below the tolerance, so that points between the check samples stay within
// it: patches and curves at half of it, and curves that give their positions to the corners
// of smaller patches (T-junctions) at a quarter, since those patches inherit that error.
constexpr double kPatchMargin = 0.5;
constexpr double kJunctionMargin = 0.25;
// Normals vary slowly between the dense check samples: a smaller margin does.
constexpr double kNormalMargin = 0.75;
// Two splits that leave the normal deviation above this fraction of the grandparent's have
// not helped: the spline's normal turns faster there than any patch can follow (a crease that
// ends inside the surface, a fold). Such a patch is not split again for its normals alone.
// (One split is not enough to tell: a child can inherit its parent's boundary curves.) Patches
// split fewer than kNormalFreeLevels times are not checked: coarse patches converge unevenly.
constexpr double kNormalStall = 0.75;
constexpr int kNormalFreeLevels = 4;

// A patch corner, named the same way from every triangle that has it: a domain vertex
// (kind 0), a point on a domain edge at position b from its lower vertex (kind 1), or a point
// inside triangle a (kind 2).
struct VKey {
  int kind = 0, a = 0;
  int64_t b = 0, c = 0;
  auto operator<=>(const VKey&) const = default;
};

// A line that patch sides lie on: a domain edge (kind 0, a = edge) or the line where the
// barycentric coordinate `axis` of triangle a equals c (kind 1). Positions along it are
// integers as well.
struct LKey {
  int kind = 0, a = 0, axis = 0;
  int64_t c = 0;
  auto operator<=>(const LKey&) const = default;
};

struct Leaf {
  int triangle = -1, level = 0;
  std::array<IBary, 3> corner{};
  std::array<VKey, 3> key{};
  std::array<Point2, 3> param{};
  bool sampled = false;
  std::vector<Point3> fit_value, check_value;
  std::vector<Vector3> check_normal;
  // The last fit, reused while the boundary stays the same.
  bool fitted = false;
  std::vector<Point3> net;
  double position_dev = 0, normal_dev = 0;
  double parent_normal_dev = std::numeric_limits<double>::infinity();
  double grandparent_normal_dev = std::numeric_limits<double>::infinity();
};

struct Side {
  int leaf = -1, k = 0;
  LKey line;
  int64_t sa = 0, sb = 0;  // positions at corner k+1 and corner k+2
  int master = -1;
  int64_t lo() const { return std::min(sa, sb); }
  int64_t hi() const { return std::max(sa, sb); }
};

struct CurveSamples {
  std::vector<Point3> fit, check;
  // The last fit, reused while the end positions stay the same.
  bool fitted = false;
  Point3 p0, p1;
  std::vector<Point3> cps;
  double dev = 0;
};

struct Master {
  LKey line;
  int64_t lo = 0, hi = 0;
  VKey vlo, vhi;
  int rep = -1;  // triangle the samples are evaluated in
  int level = 0;
  std::vector<std::pair<int64_t, VKey>> inner;  // breakpoints strictly inside
  std::vector<Point3> cps;
  double dev = 0;
};

std::vector<Bary> lattice(int deg) {
  std::vector<Bary> out;
  for (int i = 0; i < beta_count(deg); ++i) {
    const Beta g = beta_at(deg, i);
    out.emplace_back(Bary(g[0], g[1], g[2]) / deg);
  }
  return out;
}

double angle_deg(const Vector3& a, const Vector3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

class Builder {
 public:
  Builder(const Spline& s, const CadPatchOptions& o)
      : s_(s), d_(s.domain()), ev_(s), m_(o.degree), o_(o) {
    const int fit_deg = m_ + 2, check_deg = 2 * m_ + 1;
    fit_bary_ = lattice(fit_deg);
    check_bary_ = lattice(check_deg);
    // Patch interiors: least squares with the boundary fixed.
    for (int i = 0; i < beta_count(m_); ++i) {
      const Beta g = beta_at(m_, i);
      (g[0] > 0 && g[1] > 0 && g[2] > 0 ? inner_ : outer_).push_back(i);
    }
    const int nf = static_cast<int>(fit_bary_.size());
    std::vector<double> b(beta_count(m_));
    Eigen::MatrixXd bi(nf, inner_.size());
    fit_outer_.resize(nf, outer_.size());
    for (int p = 0; p < nf; ++p) {
      bernstein_triangle(m_, fit_bary_[p], b);
      for (size_t q = 0; q < inner_.size(); ++q) bi(p, q) = b[inner_[q]];
      for (size_t q = 0; q < outer_.size(); ++q) fit_outer_(p, q) = b[outer_[q]];
    }
    if (!inner_.empty()) fit_ls_ = (bi.transpose() * bi).ldlt().solve(bi.transpose());
    // Curves: least squares for the inner control points, the ends fixed.
    for (int i = 0; i <= m_ + 2; ++i) curve_fit_t_.push_back(static_cast<double>(i) / (m_ + 2));
    for (int i = 0; i < 2 * m_ + 2; ++i) curve_check_t_.push_back((i + 0.5) / (2 * m_ + 2));
    const int nc = static_cast<int>(curve_fit_t_.size());
    std::vector<double> bc(m_ + 1);
    Eigen::MatrixXd ci(nc, std::max(m_ - 1, 0));
    curve_ends_.resize(nc, 2);
    for (int p = 0; p < nc; ++p) {
      bernstein_curve(m_, curve_fit_t_[p], bc);
      for (int q = 1; q < m_; ++q) ci(p, q - 1) = bc[q];
      curve_ends_(p, 0) = bc[0];
      curve_ends_(p, 1) = bc[m_];
    }
    if (m_ >= 2) curve_ls_ = (ci.transpose() * ci).ldlt().solve(ci.transpose());
  }

  CadPatches run();

 private:
  Point2 param(const VKey& k) const {
    if (k.kind == 0) return d_.vertex(k.a);
    if (k.kind == 1) {
      const auto& e = d_.edges()[k.a];
      const double t = static_cast<double>(k.b) / kOne;
      return d_.vertex(e[0]) + t * (d_.vertex(e[1]) - d_.vertex(e[0]));
    }
    const auto& tri = d_.triangle(k.a);
    const double l0 = static_cast<double>(k.b) / kOne, l1 = static_cast<double>(k.c) / kOne;
    return l0 * d_.vertex(tri[0]) + l1 * d_.vertex(tri[1]) + (1 - l0 - l1) * d_.vertex(tri[2]);
  }

  VKey key(int t, const IBary& l) const {
    const auto& tri = d_.triangle(t);
    for (int k = 0; k < 3; ++k)
      if (l[k] == kOne) return {0, tri[k], 0, 0};
    for (int k = 0; k < 3; ++k)
      if (l[k] == 0) {
        const int e = d_.triangle_edge(t, k);
        const int hi = tri[(k + 1) % 3] > tri[(k + 2) % 3] ? (k + 1) % 3 : (k + 2) % 3;
        return {1, e, l[hi], 0};
      }
    return {2, t, l[0], l[1]};
  }

  Side side(int leaf, int k) const {
    const Leaf& f = leaves_[leaf];
    const IBary &a = f.corner[(k + 1) % 3], &b = f.corner[(k + 2) % 3];
    Side sd;
    sd.leaf = leaf;
    sd.k = k;
    int q = 0;
    while (a[q] != b[q]) ++q;
    if (a[q] == 0) {
      const auto& tri = d_.triangle(f.triangle);
      const int hi = tri[(q + 1) % 3] > tri[(q + 2) % 3] ? (q + 1) % 3 : (q + 2) % 3;
      sd.line = {0, d_.triangle_edge(f.triangle, q), 0, 0};
      sd.sa = a[hi];
      sd.sb = b[hi];
    } else {
      sd.line = {1, f.triangle, q, a[q]};
      sd.sa = a[(q + 1) % 3];
      sd.sb = b[(q + 1) % 3];
    }
    return sd;
  }

  // F at u on the side of the triangle's interior.
  SurfacePoint eval_in(const std::array<Point2, 3>& tri, const Point2& u) const {
    return detail::evaluate_in_triangle(ev_, tri, u);
  }
  std::array<Point2, 3> domain_corners(int t) const {
    const auto& tri = d_.triangle(t);
    return {d_.vertex(tri[0]), d_.vertex(tri[1]), d_.vertex(tri[2])};
  }

  void make_leaf(int t, int level, const std::array<IBary, 3>& c,
                 double parent_normal_dev = std::numeric_limits<double>::infinity(),
                 double grandparent_normal_dev = std::numeric_limits<double>::infinity()) {
    Leaf f;
    f.triangle = t;
    f.level = level;
    f.parent_normal_dev = parent_normal_dev;
    f.grandparent_normal_dev = grandparent_normal_dev;
    f.corner = c;
    for (int j = 0; j < 3; ++j) {
      f.key[j] = key(t, c[j]);
      f.param[j] = param(f.key[j]);
    }
    leaves_.push_back(std::move(f));
  }

  void sample(Leaf& f) const {
    auto at = [&](const Bary& b) { return Point2(b[0] * f.param[0] + b[1] * f.param[1] + b[2] * f.param[2]); };
    for (const Bary& b : fit_bary_) f.fit_value.push_back(eval_in(f.param, at(b)).position);
    for (const Bary& b : check_bary_) {
      const SurfacePoint p = eval_in(f.param, at(b));
      f.check_value.push_back(p.position);
      // Where the tangents are nearly parallel (the surface almost folds) the normal is not
      // defined well enough to compare; such samples are left out of the angle check.
      const Vector3 c = p.du.cross(p.dv);
      const bool regular = c.norm() >= kRegular * p.du.norm() * p.dv.norm();
      f.check_normal.push_back(regular ? detail::unit_normal(p) : Vector3::Zero());
    }
    f.sampled = true;
  }

  CurveSamples sample_curve(const Master& mc) const {
    const Point2 a = param(mc.vlo), b = param(mc.vhi);
    const auto tri = domain_corners(mc.rep);
    CurveSamples cs;
    for (double t : curve_fit_t_) cs.fit.push_back(eval_in(tri, a + t * (b - a)).position);
    for (double t : curve_check_t_) cs.check.push_back(eval_in(tri, a + t * (b - a)).position);
    return cs;
  }

  void fit_curve(Master& mc, const CurveSamples& cs, const Point3& p0, const Point3& p1) const {
    mc.cps.assign(m_ + 1, Point3::Zero());
    mc.cps.front() = p0;
    mc.cps.back() = p1;
    if (m_ >= 2) {
      const int nc = static_cast<int>(curve_fit_t_.size());
      Eigen::MatrixXd f(nc, 3);
      for (int p = 0; p < nc; ++p)
        f.row(p) = (cs.fit[p] - curve_ends_(p, 0) * p0 - curve_ends_(p, 1) * p1).transpose();
      const Eigen::MatrixXd c = curve_ls_ * f;
      for (int q = 1; q < m_; ++q) mc.cps[q] = c.row(q - 1).transpose();
    }
    mc.dev = 0;
    for (size_t p = 0; p < curve_fit_t_.size(); ++p)
      mc.dev = std::max(mc.dev, (bezier_curve_value(mc.cps, curve_fit_t_[p]) - cs.fit[p]).norm());
    for (size_t p = 0; p < curve_check_t_.size(); ++p)
      mc.dev = std::max(mc.dev, (bezier_curve_value(mc.cps, curve_check_t_[p]) - cs.check[p]).norm());
  }

  // Fills the interior of a net whose boundary is set, and measures the leaf's deviations.
  void fit_patch(Leaf& f, std::span<Point3> net) const {
    if (!inner_.empty()) {
      const int nf = static_cast<int>(fit_bary_.size());
      Eigen::MatrixXd known(outer_.size(), 3), v(nf, 3);
      for (size_t q = 0; q < outer_.size(); ++q) known.row(q) = net[outer_[q]].transpose();
      for (int p = 0; p < nf; ++p) v.row(p) = f.fit_value[p].transpose();
      const Eigen::MatrixXd c = fit_ls_ * (v - fit_outer_ * known);
      for (size_t q = 0; q < inner_.size(); ++q) net[inner_[q]] = c.row(q).transpose();
    }
    f.position_dev = f.normal_dev = 0;
    for (size_t p = 0; p < fit_bary_.size(); ++p)
      f.position_dev = std::max(f.position_dev, (bezier_value(net, m_, fit_bary_[p]) - f.fit_value[p]).norm());
    for (size_t p = 0; p < check_bary_.size(); ++p) {
      Point3 v;
      Vector3 d1, d2;
      bezier_derivatives(net, m_, check_bary_[p], v, d1, d2);
      f.position_dev = std::max(f.position_dev, (v - f.check_value[p]).norm());
      const Vector3 n = d1.cross(d2);
      if (n.norm() > 0 && f.check_normal[p].norm() > 0)
        f.normal_dev = std::max(f.normal_dev, angle_deg(n, f.check_normal[p]));
    }
  }

  const Spline& s_;
  const Domain& d_;
  const Evaluator ev_;
  const int m_;
  const CadPatchOptions& o_;
  std::vector<Bary> fit_bary_, check_bary_;
  std::vector<int> inner_, outer_;
  Eigen::MatrixXd fit_ls_, fit_outer_;
  std::vector<double> curve_fit_t_, curve_check_t_;
  Eigen::MatrixXd curve_ls_, curve_ends_;

  std::vector<Leaf> leaves_;
  std::map<VKey, Point3> vertex_value_;
  std::map<std::tuple<LKey, int64_t, int64_t>, CurveSamples> curve_samples_;
};

CadPatches Builder::run() {
  const int nt = d_.triangle_count();
  for (int t = 0; t < nt; ++t) make_leaf(t, 0, {IBary{kOne, 0, 0}, IBary{0, kOne, 0}, IBary{0, 0, kOne}});
  const double tol = o_.tolerance_abs > 0 ? o_.tolerance_abs : o_.tolerance * detail::model_size(s_);
  const double angle_tol = o_.angle_tolerance;
  tbb::task_arena arena(o_.threads > 0 ? o_.threads : tbb::task_arena::automatic);
  const int nb = beta_count(m_);

  CadPatches out;
  out.degree = m_;
  out.tolerance = tol;
  out.angle_tolerance = angle_tol;
  std::vector<Side> sides;
  std::vector<Master> masters;
  std::vector<Point3> nets;
  std::map<VKey, Point3> pos;
  std::map<std::tuple<LKey, int64_t, int64_t>, int> edge_of;  // elementary interval -> edge
  std::vector<std::array<VKey, 2>> edge_keys;                 // the ends of each edge
  for (int round = 0;; ++round) {
    out.rounds = round;
    const int nl = static_cast<int>(leaves_.size());
    arena.execute([&] {
      tbb::parallel_for(0, nl, [&](int i) {
        if (!leaves_[i].sampled) sample(leaves_[i]);
      });
    });
    // Sides by line, then the masters: the intervals no other interval contains.
    sides.clear();
    std::map<LKey, std::vector<int>> by_line;
    for (int i = 0; i < nl; ++i)
      for (int k = 0; k < 3; ++k) {
        by_line[side(i, k).line].push_back(static_cast<int>(sides.size()));
        sides.push_back(side(i, k));
      }
    masters.clear();
    std::map<std::tuple<LKey, int64_t>, VKey> point_key;  // (line, position) -> vertex
    for (const Side& sd : sides) {
      const Leaf& f = leaves_[sd.leaf];
      point_key[{sd.line, sd.sa}] = f.key[(sd.k + 1) % 3];
      point_key[{sd.line, sd.sb}] = f.key[(sd.k + 2) % 3];
    }
    for (auto& [line, ids] : by_line) {
      std::sort(ids.begin(), ids.end(), [&](int a, int b) {
        return std::pair(sides[a].lo(), -sides[a].hi()) < std::pair(sides[b].lo(), -sides[b].hi());
      });
      std::vector<int64_t> breaks;
      for (int id : ids) breaks.push_back(sides[id].lo()), breaks.push_back(sides[id].hi());
      std::sort(breaks.begin(), breaks.end());
      breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
      int cur = -1;
      for (int id : ids) {
        Side& sd = sides[id];
        if (cur >= 0 && sd.lo() >= masters[cur].lo && sd.hi() <= masters[cur].hi) {
          sd.master = cur;
          continue;
        }
        Master mc;
        mc.line = line;
        mc.lo = sd.lo();
        mc.hi = sd.hi();
        mc.vlo = point_key.at({line, mc.lo});
        mc.vhi = point_key.at({line, mc.hi});
        mc.rep = line.kind == 0 ? d_.edge_triangles(line.a)[0] : line.a;
        if (line.kind == 0 && d_.edge_triangles(line.a)[1] >= 0)
          mc.rep = std::min(mc.rep, d_.edge_triangles(line.a)[1]);
        mc.level = kBits - static_cast<int>(std::lround(std::log2(static_cast<double>(mc.hi - mc.lo))));
        for (auto it = std::upper_bound(breaks.begin(), breaks.end(), mc.lo);
             it != breaks.end() && *it < mc.hi; ++it)
          mc.inner.emplace_back(*it, point_key.at({line, *it}));
        cur = static_cast<int>(masters.size());
        masters.push_back(std::move(mc));
        sd.master = cur;
      }
    }
    // Samples for new curves and values at new vertices.
    std::vector<int> fresh;
    for (int i = 0; i < static_cast<int>(masters.size()); ++i)
      if (!curve_samples_.count({masters[i].line, masters[i].lo, masters[i].hi})) fresh.push_back(i);
    std::vector<CurveSamples> fresh_samples(fresh.size());
    arena.execute([&] {
      tbb::parallel_for(0, static_cast<int>(fresh.size()),
                        [&](int i) { fresh_samples[i] = sample_curve(masters[fresh[i]]); });
    });
    for (size_t i = 0; i < fresh.size(); ++i) {
      const Master& mc = masters[fresh[i]];
      curve_samples_[{mc.line, mc.lo, mc.hi}] = std::move(fresh_samples[i]);
    }
    std::vector<std::pair<VKey, int>> new_keys;  // key, a triangle that has it
    for (const Leaf& f : leaves_)
      for (int j = 0; j < 3; ++j)
        if (!vertex_value_.count(f.key[j])) {
          vertex_value_[f.key[j]] = Point3::Zero();
          new_keys.emplace_back(f.key[j], f.triangle);
        }
    std::vector<Point3> new_values(new_keys.size());
    arena.execute([&] {
      tbb::parallel_for(0, static_cast<int>(new_keys.size()), [&](int i) {
        // The lowest triangle around the point is the same whichever leaf found it first.
        const VKey& k = new_keys[i].first;
        int t = new_keys[i].second;
        if (k.kind == 0) t = *std::min_element(d_.vertex_triangles(k.a).begin(), d_.vertex_triangles(k.a).end());
        if (k.kind == 1) {
          const auto tt = d_.edge_triangles(k.a);
          t = tt[1] >= 0 ? std::min(tt[0], tt[1]) : tt[0];
        }
        new_values[i] = eval_in(domain_corners(t), param(k)).position;
      });
    });
    for (size_t i = 0; i < new_keys.size(); ++i) vertex_value_[new_keys[i].first] = new_values[i];

    // Curves, coarsest first: a point inside a longer curve takes its position from it.
    pos = vertex_value_;
    std::vector<int> order(masters.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return masters[a].level < masters[b].level; });
    for (size_t g0 = 0; g0 < order.size();) {
      size_t g1 = g0;
      while (g1 < order.size() && masters[order[g1]].level == masters[order[g0]].level) ++g1;
      arena.execute([&] {
        tbb::parallel_for(g0, g1, [&](size_t i) {
          Master& mc = masters[order[i]];
          const CurveSamples& cs = curve_samples_.at({mc.line, mc.lo, mc.hi});
          const Point3 &p0 = pos.at(mc.vlo), &p1 = pos.at(mc.vhi);
          if (cs.fitted && cs.p0 == p0 && cs.p1 == p1) {
            mc.cps = cs.cps;
            mc.dev = cs.dev;
          } else {
            fit_curve(mc, cs, p0, p1);
          }
        });
      });
      for (size_t i = g0; i < g1; ++i) {
        const Master& mc = masters[order[i]];
        CurveSamples& cs = curve_samples_.at({mc.line, mc.lo, mc.hi});
        cs.fitted = true;
        cs.p0 = pos.at(mc.vlo);
        cs.p1 = pos.at(mc.vhi);
        cs.cps = mc.cps;
        cs.dev = mc.dev;
        for (const auto& [s, k] : mc.inner)
          pos[k] = bezier_curve_value(mc.cps, static_cast<double>(s - mc.lo) / static_cast<double>(mc.hi - mc.lo));
      }
      g0 = g1;
    }

    // Elementary edges (between consecutive breakpoints) and patch boundaries.
    out.edges.clear();
    edge_of.clear();
    edge_keys.clear();
    out.boundaries.assign(nl, {});
    for (const Side& sd : sides) {
      const Master& mc = masters[sd.master];
      std::vector<int64_t> pts{sd.lo()};
      for (const auto& [s, k] : mc.inner)
        if (s > sd.lo() && s < sd.hi()) pts.push_back(s);
      pts.push_back(sd.hi());
      std::vector<CadEdgeUse> uses;
      for (size_t i = 0; i + 1 < pts.size(); ++i) {
        const auto id = std::tuple(mc.line, pts[i], pts[i + 1]);
        auto it = edge_of.find(id);
        if (it == edge_of.end()) {
          CadEdge e;
          const VKey a = point_key.at({mc.line, pts[i]}), b = point_key.at({mc.line, pts[i + 1]});
          if (pts[i] == mc.lo && pts[i + 1] == mc.hi) {
            e.control_points = mc.cps;
          } else {
            const double w = static_cast<double>(mc.hi - mc.lo);
            e.control_points = bezier_curve_restrict(mc.cps, static_cast<double>(pts[i] - mc.lo) / w,
                                                     static_cast<double>(pts[i + 1] - mc.lo) / w);
          }
          e.control_points.front() = pos.at(a);
          e.control_points.back() = pos.at(b);
          e.domain_edge = mc.line.kind == 0 ? mc.line.a : -1;
          e.feature = e.domain_edge >= 0 && d_.is_feature_edge(e.domain_edge);
          // Vertex indices are filled in at the end; keep the keys meanwhile.
          edge_keys.push_back({a, b});
          it = edge_of.emplace(id, static_cast<int>(out.edges.size())).first;
          out.edges.push_back(std::move(e));
        }
        uses.push_back({it->second, false});
      }
      if (sd.sa > sd.sb) {
        std::reverse(uses.begin(), uses.end());
        for (auto& u : uses) u.reversed = true;
      }
      auto& b = out.boundaries[sd.leaf];
      b.insert(b.end(), uses.begin(), uses.end());
    }
    // Patches: boundary from the edges (or from the master for a side that spans several).
    nets.assign(static_cast<size_t>(nl) * nb, Point3::Zero());
    arena.execute([&] {
      tbb::parallel_for(0, nl, [&](int i) {
        Leaf& f = leaves_[i];
        std::span<Point3> net(nets.data() + static_cast<size_t>(i) * nb, nb);
        for (int k = 0; k < 3; ++k) {
          const Side& sd = sides[3 * i + k];
          const Master& mc = masters[sd.master];
          std::vector<Point3> curve;
          const auto e = edge_of.find({mc.line, sd.lo(), sd.hi()});
          if (e != edge_of.end()) curve = out.edges[e->second].control_points;
          else curve = mc.cps;  // a side with breakpoints is a master itself
          if (sd.sa > sd.sb) std::reverse(curve.begin(), curve.end());
          const auto idx = bezier_side_indices(m_, k);
          for (int j = 0; j <= m_; ++j) net[idx[j]] = curve[j];
        }
        bool same = f.fitted;
        for (size_t q = 0; same && q < outer_.size(); ++q) same = f.net[outer_[q]] == net[outer_[q]];
        if (same) {
          std::copy(f.net.begin(), f.net.end(), net.begin());
        } else {
          fit_patch(f, net);
          f.net.assign(net.begin(), net.end());
          f.fitted = true;
        }
      });
    });

    // Split what is out of tolerance.
    std::vector<char> split(nl, 0);
    // A curve out of tolerance splits the patches whose whole side it is.
    for (const Side& sd : sides) {
      const Master& mc = masters[sd.master];
      const double limit = (mc.inner.empty() ? kPatchMargin : kJunctionMargin) * tol;
      if (mc.dev > limit && sd.lo() == mc.lo && sd.hi() == mc.hi) split[sd.leaf] = 1;
    }
    // A patch out of tolerance splits, and so do the larger patches it takes boundary
    // positions from: once the smaller patch is smaller than the error those give it, only
    // refining them can help (their positions are off by up to the tolerance, which turns
    // into an ever larger normal error on an ever smaller patch).
    std::map<VKey, int> junction_master;  // a corner inside a longer curve -> that curve
    for (int i = 0; i < static_cast<int>(masters.size()); ++i)
      for (const auto& [sv, k] : masters[i].inner) junction_master[k] = i;
    std::vector<char> master_split(masters.size(), 0);
    for (int i = 0; i < nl; ++i) {
      const Leaf& f = leaves_[i];
      const bool normal_bad = f.normal_dev > kNormalMargin * angle_tol / 2 &&
                              (f.level < kNormalFreeLevels || f.normal_dev < kNormalStall * f.grandparent_normal_dev);
      if (f.position_dev <= kPatchMargin * tol && !normal_bad) continue;
      split[i] = 1;
      for (int k = 0; k < 3; ++k) {
        const Side& sd = sides[3 * i + k];
        const Master& mc = masters[sd.master];
        if (sd.lo() != mc.lo || sd.hi() != mc.hi) master_split[sd.master] = 1;
        const auto it = junction_master.find(f.key[k]);
        if (it != junction_master.end()) master_split[it->second] = 1;
      }
    }
    for (const Side& sd : sides) {
      const Master& mc = masters[sd.master];
      if (master_split[sd.master] && sd.lo() == mc.lo && sd.hi() == mc.hi) split[sd.leaf] = 1;
    }
    int splits = 0;
    for (int i = 0; i < nl; ++i)
      if (split[i] && leaves_[i].level < o_.max_level) ++splits;
    // The patch budget: rather a file that misses the tolerance somewhere (and says so) than
    // one too large to write or read. The worst patches (relative to the tolerances) split
    // first, as many as the budget allows.
    if (nl + 3 * static_cast<long>(splits) > o_.max_patches) {
      out.budget_reached = true;
      std::vector<int> want;
      for (int i = 0; i < nl; ++i)
        if (split[i] && leaves_[i].level < o_.max_level) want.push_back(i);
      auto badness = [&](int i) {
        return std::max(leaves_[i].position_dev / tol, leaves_[i].normal_dev / (angle_tol / 2));
      };
      std::stable_sort(want.begin(), want.end(), [&](int a, int b) { return badness(a) > badness(b); });
      const size_t room = static_cast<size_t>(std::max<long>(0, (o_.max_patches - nl) / 3));
      for (size_t k = room; k < want.size(); ++k) split[want[k]] = 0;
      splits = static_cast<int>(std::min(room, want.size()));
    }
    if (splits == 0) {
      out.max_position_deviation = out.max_normal_deviation = 0;
      for (const Master& mc : masters) out.max_position_deviation = std::max(out.max_position_deviation, mc.dev);
      for (const Leaf& f : leaves_) {
        out.max_position_deviation = std::max(out.max_position_deviation, f.position_dev);
        out.max_normal_deviation = std::max(out.max_normal_deviation, f.normal_dev);
      }
      out.within_tolerance =
          out.max_position_deviation <= tol && out.max_normal_deviation <= angle_tol / 2;
      break;
    }
    std::vector<Leaf> old;
    old.swap(leaves_);
    for (int i = 0; i < nl; ++i) {
      Leaf& f = old[i];
      if (!split[i] || f.level >= o_.max_level) {
        leaves_.push_back(std::move(f));
        continue;
      }
      const IBary &a = f.corner[0], &b = f.corner[1], &c = f.corner[2];
      auto mid = [](const IBary& p, const IBary& q) {
        return IBary{(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2};
      };
      const IBary ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      const double nd = f.normal_dev, pd = f.parent_normal_dev;
      make_leaf(f.triangle, f.level + 1, {a, ab, ca}, nd, pd);
      make_leaf(f.triangle, f.level + 1, {ab, b, bc}, nd, pd);
      make_leaf(f.triangle, f.level + 1, {ca, bc, c}, nd, pd);
      make_leaf(f.triangle, f.level + 1, {bc, ca, ab}, nd, pd);
    }
  }

  // Output: vertices numbered in order of first use.
  std::map<VKey, int> vid;
  auto vertex = [&](const VKey& k) {
    const auto [it, added] = vid.try_emplace(k, static_cast<int>(out.vertices.size()));
    if (added) {
      out.vertices.push_back(pos.at(k));
      out.vertex_parameters.push_back(param(k));
    }
    return it->second;
  };
  out.patch_start.assign(1, 0);
  for (int i = 0; i < static_cast<int>(leaves_.size()); ++i) {
    const Leaf& f = leaves_[i];
    CadPatch p;
    p.triangle = f.triangle;
    p.level = f.level;
    for (int j = 0; j < 3; ++j) p.corners[j] = vertex(f.key[j]);
    out.patches.push_back(p);
  }
  for (int t = 0, i = 0; t < nt; ++t) {
    while (i < static_cast<int>(out.patches.size()) && out.patches[i].triangle == t) ++i;
    out.patch_start.push_back(i);
  }
  for (size_t e = 0; e < out.edges.size(); ++e)
    out.edges[e].vertices = {vertex(edge_keys[e][0]), vertex(edge_keys[e][1])};
  out.control_points = std::move(nets);
  return out;
}

}  // namespace

CadPatches make_cad_patches(const Spline& spline, const CadPatchOptions& options) {
  if (spline.domain().triangle_count() == 0) throw InvalidInput("make_cad_patches: the spline has no triangles");
  CadPatchOptions o = options;
  if (o.degree == 0) o.degree = spline.degree() + 2;
  if (o.degree < spline.degree() || o.degree > 15)
    throw InvalidInput("CAD patch degree " + std::to_string(o.degree) + " is out of range: use " +
                       std::to_string(spline.degree()) + " (the spline's degree) to 15");
  if (!(o.tolerance > 0) && !(o.tolerance_abs > 0))
    throw InvalidInput("CAD tolerance must be positive");
  if (!(o.angle_tolerance > 0) || !(o.angle_tolerance < 90))
    throw InvalidInput("angle tolerance must be between 0 and 90 degrees");
  if (o.max_level < 0 || o.max_level > 16)
    throw InvalidInput("max_level must be 0 to 16");
  if (o.max_patches < spline.domain().triangle_count())
    throw InvalidInput("the CAD patch budget (" + std::to_string(o.max_patches) +
                       ") is below the number of domain triangles (" +
                       std::to_string(spline.domain().triangle_count()) + "): raise it");
  Builder b(spline, o);
  return b.run();
}

}  // namespace tbs
