// The control-point sub-problem (paper section 4.3, fit_solve.h): the points' basis rows, the
// fairness and smoothness terms, assembled into one sparse SPD system and solved by CHOLMOD.

#include "fit_solve.h"
#include "thread_arena.h"

#include <tbs/errors.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

namespace tbs::detail {

void group_by_triangle(std::span<const int> triangle, int triangle_count, std::vector<int>& order,
                       std::vector<int>& start) {
  start.assign(static_cast<size_t>(triangle_count) + 1, 0);
  for (int t : triangle)
    if (t >= 0) ++start[t + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  order.assign(start.back(), 0);
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (size_t i = 0; i < triangle.size(); ++i)
    if (triangle[i] >= 0) order[fill[triangle[i]]++] = static_cast<int>(i);
}

namespace {

// Second and third derivatives of F at interior quadrature points of a domain triangle, as
// sparse rows over the control points, by central differences of the exact first derivatives
// (the evaluator gives F, F_u, F_v). The step, 2 % of the sub-triangle's size, is below the
// distance of the Gauss points from the sub-triangle's edges (a sixth of its heights) for the
// well-shaped triangles the domain builder makes, so the differences stay inside the triangle
// and do not reach across a feature edge.
struct BendSample {
  BasisRow row[5];  // at x, x + d e_u, x - d e_u, x + d e_v, x - d e_v
  double delta = 0;
  double weight = 0;  // quadrature weight times triangle area
};

// The basis rows of one triangle's points, as the pattern pass computed them, for the
// assembly pass: point q's row is entries start[q] .. start[q + 1] - 1 (empty for a point
// the evaluator gives no row: it adds nothing either way). du and dv are kept only when the
// fairness term needs them.
struct RowCache {
  std::vector<int> start, index;
  std::vector<double> value, du, dv;
  bool filled = false;
  // The triangle's smoothness samples (for_bend_samples), when it has them; without the basis
  // values, which the smoothness terms do not use.
  std::vector<BendSample> bend;
  bool bend_filled = false;
  size_t bend_bytes() const {
    size_t b = bend.capacity() * sizeof(BendSample);
    for (const BendSample& s : bend)
      for (const BasisRow& r : s.row)
        b += r.index.capacity() * sizeof(int) + (r.value.capacity() + r.du.capacity() + r.dv.capacity()) * sizeof(double);
    return b;
  }
  size_t bytes() const {
    return start.capacity() * sizeof(int) + index.capacity() * sizeof(int) +
           (value.capacity() + du.capacity() + dv.capacity()) * sizeof(double) + bend_bytes();
  }
  void release() { *this = RowCache(); }
};

// One point's basis row, from the cache or from the evaluator.
struct RowView {
  const int* index;
  const double *value, *du, *dv;
  size_t size;
};

// Local normal equations of the points of one triangle, dense over its control points S.
struct Local {
  std::vector<int> S;
  // Row-major m x m, upper triangle only (entries (a, b >= a); the rest stays 0): the local
  // indices of a basis row increase with its control-point indices, so every pair of a row
  // lands there.
  std::vector<double> G;  // data term
  std::vector<double> F;  // fairness: 6 per entry (xx xy xz yy yz zz), side by side
  std::vector<double> rhs;              // m x 3
  std::vector<double> data_diag;        // m, diagonal of the data term alone
};

// Conjugate gradients on the coupled system stop at this relative residual (the preconditioned
// system is within about the fairness weight of the identity: a few iterations reach it).
constexpr double kCgTolerance = 1e-14;
constexpr int kCgMaxIterations = 200;

// The scalar factorisation applied to x, y and z alike: the 3N vector (x0 y0 z0 x1 ...) as an
// N x 3 matrix, three right-hand sides. The interface Eigen's iterative solvers expect of a
// preconditioner; compute() does nothing, the factor is given.
class ScalarPreconditioner {
 public:
  using Chol = Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower>;
  ScalarPreconditioner() = default;
  explicit ScalarPreconditioner(const Chol& chol) : chol_(&chol) {}
  template <class M>
  ScalarPreconditioner& analyzePattern(const M&) { return *this; }
  template <class M>
  ScalarPreconditioner& factorize(const M&) { return *this; }
  template <class M>
  ScalarPreconditioner& compute(const M&) { return *this; }
  Eigen::ComputationInfo info() const { return Eigen::Success; }
  Eigen::VectorXd solve(const Eigen::Ref<const Eigen::VectorXd>& r) const {
    using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
    const Eigen::Index n = r.size() / 3;
    const Eigen::MatrixXd R = Eigen::Map<const Rows>(r.data(), n, 3);
    const Rows Z = chol_->solve(R);
    return Eigen::Map<const Eigen::VectorXd>(Z.data(), 3 * n);
  }

 private:
  const Chol* chol_ = nullptr;
};

// Sub-triangles per edge of the composite smoothness rule in sparse triangles.
constexpr int kBendLevel = 4;

// Symmetric Gauss rules on a triangle: barycentric points (a, a, 1 - 2a) and their
// permutations, with weights summing to 1. Three points are exact for quadratics: the
// bending integrand of a cubic piece. Degree 4 and up use Dunavant's six points (degree 4).
struct QuadOrbit {
  double a, w;
};
constexpr QuadOrbit kQuad3[] = {{1.0 / 6.0, 1.0 / 3.0}};
constexpr QuadOrbit kQuad6[] = {{0.445948490915965, 0.223381589678011},
                                {0.091576213509771, 0.109951743655322}};

// The composite rule of a domain triangle: `level` x `level` congruent sub-triangles (the
// barycentric lattice of step 1/level, upward and downward ones), the Gauss rule on each. The
// spline is piecewise polynomial inside a domain triangle (the cells of its knot lines), so a
// single rule misses most of the shapes a sparse triangle can take: a swing between the
// rule's points costs nothing. Sub-triangles about as small as the cells see them.
template <class F>
void for_bend_samples(const Evaluator& eval, const Domain& d, int degree, int t, int level, BendSample& s, F&& f) {
  const auto& tri = d.triangle(t);
  const Point2 &a = d.vertex(tri[0]), &b = d.vertex(tri[1]), &c = d.vertex(tri[2]);
  const double area = 0.5 * std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
  const double h = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  const double step = 1.0 / level;
  s.delta = 2e-2 * h * step;
  const Point2 du(s.delta, 0), dv(0, s.delta);
  const std::span<const QuadOrbit> rule = degree <= 3 ? std::span<const QuadOrbit>(kQuad3) : std::span<const QuadOrbit>(kQuad6);
  const double sub_area = area * step * step;
  // Sub-triangle corners in barycentric lattice coordinates (i, j) of (b, c).
  auto at = [&](double i, double j) { return a + (i * step) * (b - a) + (j * step) * (c - a); };
  for (int i = 0; i < level; ++i)
    for (int j = 0; i + j < level; ++j)
      for (int down = 0; down < 2; ++down) {
        if (down && i + j + 2 > level) continue;
        const Point2 p0 = down ? at(i + 1, j + 1) : at(i, j);
        const Point2 p1 = down ? at(i, j + 1) : at(i + 1, j);
        const Point2 p2 = down ? at(i + 1, j) : at(i, j + 1);
        for (const QuadOrbit& q : rule)
          for (int k = 0; k < 3; ++k) {
            const double l1 = 1 - 2 * q.a;
            const Point2 x = (k == 0 ? l1 : q.a) * p0 + (k == 1 ? l1 : q.a) * p1 + (k == 2 ? l1 : q.a) * p2;
            if (!eval.basis_row(x, s.row[0]) || !eval.basis_row(x + du, s.row[1]) || !eval.basis_row(x - du, s.row[2]) ||
                !eval.basis_row(x + dv, s.row[3]) || !eval.basis_row(x - dv, s.row[4]))
              continue;
            s.weight = q.w * sub_area;
            f(s);
          }
      }
}

}  // namespace

struct KeptRows::Data {
  bool fair = false;
  std::vector<std::array<int, 3>> triangles;  // the domain the rows were computed on
  std::vector<Point2> knots;                  // and its knots
  std::vector<int> order, start;              // the points of each triangle
  std::vector<RowCache> cache;                // per triangle
  std::vector<std::vector<int>> point_support;  // per triangle: the control points its points' rows touch

  // Per triangle of the current solve: whether its kept rows are still its rows. They are if
  // the domain is the same, the triangle holds the same points, and no knot moved in a
  // triangle whose box (old and new knots of its vertices, all levels) meets the triangle's
  // box: a point's row depends only on the knots of the triangles whose supports reach it.
  std::vector<char> reusable(const Spline& spline, const FitPoints& pts, bool fair_now) const {
    const Domain& d = spline.domain();
    const int T = d.triangle_count();
    std::vector<char> ok(T, 0);
    if (fair != fair_now || static_cast<int>(triangles.size()) != T || knots.size() != spline.knots().size())
      return ok;
    for (int t = 0; t < T; ++t)
      if (d.triangle(t) != triangles[t]) return ok;
    const int stride = spline.degree() + 1;
    std::vector<Box2> moved;
    std::vector<char> changed(d.vertex_count(), 0);
    for (int v = 0; v < d.vertex_count(); ++v)
      for (int l = 0; l < stride; ++l)
        if (spline.knot(v, l) != knots[static_cast<size_t>(v) * stride + l]) changed[v] = 1;
    for (int v = 0; v < d.vertex_count(); ++v) {
      if (!changed[v]) continue;
      for (int t : d.vertex_triangles(v)) {
        Box2 b;
        for (int w : d.triangle(t))
          for (int l = 0; l < stride; ++l) {
            b.extend(spline.knot(w, l));
            b.extend(knots[static_cast<size_t>(w) * stride + l]);
          }
        moved.push_back(b);
      }
    }
    auto meets = [](const Box2& a, const Box2& b) {
      return a.min.x() <= b.max.x() && b.min.x() <= a.max.x() && a.min.y() <= b.max.y() && b.min.y() <= a.max.y();
    };
    for (int t = 0; t < T; ++t) {
      if (!cache[t].filled) continue;
      const int m = pts.start[t + 1] - pts.start[t];
      if (m != start[t + 1] - start[t] ||
          !std::equal(pts.order.begin() + pts.start[t], pts.order.begin() + pts.start[t + 1], order.begin() + start[t]))
        continue;
      Box2 box;
      for (int w : d.triangle(t)) box.extend(d.vertex(w));
      ok[t] = std::none_of(moved.begin(), moved.end(), [&](const Box2& b) { return meets(b, box); });
    }
    return ok;
  }
};

namespace {

// A seam tie's rows (fit_solve.h) as one local system with unit weight: its support (the
// control points of the rows at a and b, ascending) and the upper triangle of sum w r r^T,
// row-major. Empty where a or b is outside the domain.
void tie_system(const Evaluator& eval, const SeamTie& tie, BasisRow& ra, BasisRow& rb, std::vector<int>& S,
                std::vector<double>* G) {
  S.clear();
  if (!eval.basis_row(tie.a, ra) || !eval.basis_row(tie.b, rb)) return;
  S = ra.index;
  S.insert(S.end(), rb.index.begin(), rb.index.end());
  std::sort(S.begin(), S.end());
  S.erase(std::unique(S.begin(), S.end()), S.end());
  if (!G) return;
  const size_t m = S.size();
  // The two rows over S: the value, and the derivative across the seam.
  std::vector<double> r0(m, 0.0), r1(m, 0.0);
  auto at = [&](int j) { return static_cast<size_t>(std::lower_bound(S.begin(), S.end(), j) - S.begin()); };
  for (size_t k = 0; k < ra.index.size(); ++k) {
    const size_t q = at(ra.index[k]);
    r0[q] += ra.value[k];
    r1[q] -= tie.cross_a.x() * ra.du[k] + tie.cross_a.y() * ra.dv[k];
  }
  for (size_t k = 0; k < rb.index.size(); ++k) {
    const size_t q = at(rb.index[k]);
    r0[q] -= rb.value[k];
    r1[q] += tie.cross_b.x() * rb.du[k] + tie.cross_b.y() * rb.dv[k];
  }
  // Each row scaled to unit length: a tie's strength does not depend on the size of the basis
  // functions' values or derivatives there (the derivative rows are far longer than the value
  // row, and grow as the domain is refined), only on its weight.
  auto unit = [](std::vector<double>& r) {
    double n2 = 0;
    for (double x : r) n2 += x * x;
    return n2 > 0 ? 1 / n2 : 0.0;
  };
  const double w0 = tie.c0 * unit(r0), w1 = tie.c1 * unit(r1);
  G->assign(m * m, 0.0);
  for (size_t a = 0; a < m; ++a)
    for (size_t b = a; b < m; ++b) (*G)[a * m + b] = w0 * r0[a] * r0[b] + w1 * r1[a] * r1[b];
}

}  // namespace

KeptRows::KeptRows() = default;
KeptRows::~KeptRows() = default;

std::vector<Point3> solve_control_points(const Spline& spline, const Evaluator& eval,
                                         const FitPoints& pts, double lambda, int threads,
                                         SolveTimes* times, Solver solver,
                                         size_t row_cache_bytes, KeptRows* kept) {
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  auto t_stage = Clock::now();
  const Domain& d = spline.domain();
  const int T = d.triangle_count();
  const int N = spline.control_point_count();
  const bool fair = lambda > 0;
  // The seam ties take the places T .. T + K - 1 after the triangles in the support sets and
  // the assembly: their systems are summed apart (Gt) and weighted once the data's scale is known.
  const int K = static_cast<int>(pts.ties.size());

  // The control points each triangle's points touch (union of their basis rows), in parallel.
  struct Scratch {
    BasisRow row;
    std::vector<int> where;
    BendSample bend;
    Eigen::MatrixXd A;
    double row_seconds = 0;  // in basis_row for the points
  };
  tbb::enumerable_thread_specific<Scratch> scratch([N] { return Scratch{{}, std::vector<int>(N, -1), {}, {}, 0}; });
  // A point's basis row into sc.row, timed only when the caller asks for the times.
  auto point_row = [&](Scratch& sc, const Point2& uv) {
    if (!times) return eval.basis_row(uv, sc.row);
    const auto t = Clock::now();
    const bool ok = eval.basis_row(uv, sc.row);
    sc.row_seconds += since(t);
    return ok;
  };
  auto bends = [&](int t) {
    return (!pts.bend.empty() && pts.bend[t] > 0) || (!pts.jerk.empty() && pts.jerk[t] > 0);
  };
  auto idle = [&](int t) { return t < T && pts.start[t + 1] == pts.start[t] && !bends(t); };
  // Triangles with fewer points than control points of their own (beta_count) take the
  // composite rule; where the points outnumber them they decide the shape, one rule will do.
  const int own = beta_count(spline.degree());
  auto bend_level = [&](int t) { return pts.start[t + 1] - pts.start[t] >= own ? 1 : kBendLevel; };
  std::vector<std::vector<int>> support(static_cast<size_t>(T) + K), point_support(T);
  // The pattern pass keeps its basis rows (of the points and of the smoothness samples) for
  // the assembly pass, triangle by triangle, while they fit in row_cache_bytes (the rest are
  // computed again); the same rows either way. With `kept`, triangles take the rows of the
  // previous solve where they are still theirs.
  std::vector<RowCache> cache(T);
  // A triangle's smoothness samples: kept ones, or computed (the same rows either way).
  auto bend_samples = [&](Scratch& sc, int t, auto&& f) {
    const RowCache& C = cache[t];
    if (C.bend_filled) {
      for (const BendSample& b : C.bend) f(b);
    } else {
      for_bend_samples(eval, d, spline.degree(), t, bend_level(t), sc.bend, f);
    }
  };
  std::vector<char> reuse(T, 0);
  if (kept && kept->data) reuse = kept->data->reusable(spline, pts, fair);
  size_t reused_bytes = 0;
  for (int t = 0; t < T; ++t)
    if (reuse[t]) {
      cache[t] = std::move(kept->data->cache[t]);
      point_support[t] = std::move(kept->data->point_support[t]);
      reused_bytes += cache[t].bytes();
    }
  if (kept) kept->data.reset();
  if (times) times->kept_triangles += std::count(reuse.begin(), reuse.end(), 1);
  std::atomic<size_t> cached_bytes{reused_bytes};
  with_threads(threads, [&] {
    tbb::parallel_for(0, K, [&](int k) {
      Scratch& sc = scratch.local();
      BasisRow rb;
      tie_system(eval, pts.ties[static_cast<size_t>(k)], sc.row, rb, support[static_cast<size_t>(T + k)], nullptr);
    });
    tbb::parallel_for(0, T, [&](int t) {
      if (idle(t)) return;
      Scratch& sc = scratch.local();
      std::vector<int>& P = point_support[t];
      if (!reuse[t]) {
        RowCache& C = cache[t];
        const bool keep = cached_bytes.load(std::memory_order_relaxed) < row_cache_bytes;
        if (keep) C.start.reserve(static_cast<size_t>(pts.start[t + 1] - pts.start[t]) + 1);
        for (int q = pts.start[t]; q < pts.start[t + 1]; ++q) {
          if (keep) C.start.push_back(static_cast<int>(C.index.size()));
          if (!point_row(sc, pts.uv[pts.order[q]])) continue;
          if (keep) {
            C.index.insert(C.index.end(), sc.row.index.begin(), sc.row.index.end());
            C.value.insert(C.value.end(), sc.row.value.begin(), sc.row.value.end());
            if (fair) {
              C.du.insert(C.du.end(), sc.row.du.begin(), sc.row.du.end());
              C.dv.insert(C.dv.end(), sc.row.dv.begin(), sc.row.dv.end());
            }
          }
          for (int j : sc.row.index)
            if (sc.where[j] < 0) sc.where[j] = 0, P.push_back(j);
        }
        for (int j : P) sc.where[j] = -1;
        std::sort(P.begin(), P.end());
        if (keep) {
          C.start.push_back(static_cast<int>(C.index.size()));
          C.filled = true;
          if (cached_bytes.fetch_add(C.bytes(), std::memory_order_relaxed) + C.bytes() > row_cache_bytes) {
            cached_bytes.fetch_sub(C.bytes(), std::memory_order_relaxed);
            C.release();
          }
        }
      }
      // The support set: the points' control points and those of the smoothness samples.
      std::vector<int>& S = support[t];
      S = P;
      if (bends(t)) {
        for (int j : S) sc.where[j] = 0;
        RowCache& C = cache[t];
        const bool keep = !C.bend_filled && cached_bytes.load(std::memory_order_relaxed) < row_cache_bytes;
        bend_samples(sc, t, [&](const BendSample& b) {
          for (const BasisRow& r : b.row)
            for (int j : r.index)
              if (sc.where[j] < 0) sc.where[j] = 0, S.push_back(j);
          if (keep) {
            BendSample& k = C.bend.emplace_back();
            k.delta = b.delta;
            k.weight = b.weight;
            for (int q = 0; q < 5; ++q)
              k.row[q] = {b.row[q].index, {}, b.row[q].du, b.row[q].dv};
          }
        });
        if (keep) {
          C.bend_filled = true;
          const size_t bytes = C.bend_bytes();
          if (cached_bytes.fetch_add(bytes, std::memory_order_relaxed) + bytes > row_cache_bytes) {
            cached_bytes.fetch_sub(bytes, std::memory_order_relaxed);
            C.bend = std::vector<BendSample>();
            C.bend_filled = false;
          }
        }
        for (int j : S) sc.where[j] = -1;
        std::sort(S.begin(), S.end());
      }
    });
  });
  // Control-net membrane pairs (j < k).
  std::vector<std::pair<int, int>> net;
  {
    const int n = spline.degree();
    const int nb = beta_count(n);
    for (int t = 0; t < T; ++t)
      for (int i = 0; i < nb; ++i) {
        const Beta b = beta_at(n, i);
        for (int a = 0; a < 3; ++a)
          for (int c = 0; c < 3; ++c) {
            if (a == c || b[c] == 0) continue;
            Beta b2 = b;
            ++b2[a];
            --b2[c];
            const int j = spline.control_point_index(t, i), k = spline.control_point_index(t, b2);
            if (j < k) net.emplace_back(j, k);
          }
      }
  }
  // Pattern: row j holds the sorted columns k >= j that a triangle's support set (k after j
  // in it) or a membrane pair joins to j, and j itself. Rows are independent: built in
  // parallel from the triangles and pairs of each control point.
  // Items grouped by control point (a counting sort); each(f) calls f(j, item) for every item.
  auto by_point = [N]<class Item>(Item, auto&& each) {
    std::vector<size_t> start(static_cast<size_t>(N) + 1, 0);
    each([&](int j, const Item&) { ++start[j + 1]; });
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<Item> items(start.back());
    std::vector<size_t> next(start.begin(), start.end() - 1);
    each([&](int j, const Item& item) { items[next[j]++] = item; });
    return std::pair{std::move(start), std::move(items)};
  };
  // (triangle, position of j in its support set) and the membrane partners k > j of each j.
  // (Named members, not structured bindings: clang before 16 cannot capture those.)
  const auto tri_of = by_point(std::pair<int, int>{}, [&](auto&& f) {
    for (int t = 0; t < T + K; ++t)
      for (size_t a = 0; a < support[t].size(); ++a) f(support[t][a], std::pair{t, static_cast<int>(a)});
  });
  const auto net_of = by_point(0, [&](auto&& f) {
    for (auto [j, k] : net) f(j, k);
  });
  const std::vector<size_t>&tri_start = tri_of.first, &net_start = net_of.first;
  const std::vector<std::pair<int, int>>& tri_items = tri_of.second;
  const std::vector<int>& net_items = net_of.second;
  std::vector<std::vector<int>> rows(N);
  with_threads(threads, [&] {
    tbb::parallel_for(0, N, [&](int j) {
      Scratch& sc = scratch.local();
      std::vector<int>& r = rows[j];
      auto add = [&](int k) {
        if (sc.where[k] < 0) sc.where[k] = 0, r.push_back(k);
      };
      add(j);
      for (size_t e = tri_start[j]; e < tri_start[j + 1]; ++e) {
        const auto [t, from] = tri_items[e];
        for (size_t a = static_cast<size_t>(from); a < support[t].size(); ++a) add(support[t][a]);
      }
      for (size_t e = net_start[j]; e < net_start[j + 1]; ++e) add(net_items[e]);
      for (int k : r) sc.where[k] = -1;
      std::sort(r.begin(), r.end());
    });
  });
  std::vector<size_t> row_start(static_cast<size_t>(N) + 1, 0);
  for (int j = 0; j < N; ++j) row_start[j + 1] = row_start[j] + rows[j].size();
  const size_t nnz = row_start[N];
  std::vector<int> cols(nnz);
  for (int j = 0; j < N; ++j) std::copy(rows[j].begin(), rows[j].end(), cols.begin() + static_cast<long>(row_start[j]));
  rows.clear();
  rows.shrink_to_fit();
  if (times) times->pattern += since(t_stage);
  t_stage = Clock::now();
  std::vector<double> G(nnz, 0.0);
  std::vector<double> Gt(K > 0 ? nnz : 0, 0.0);  // the seam ties, unit weight
  std::array<std::vector<double>, 6> F;
  if (fair)
    for (auto& f : F) f.assign(nnz, 0.0);
  std::vector<double> rhs(3 * static_cast<size_t>(N), 0.0);
  std::vector<double> data_diag(N, 0.0);

  // Local systems in parallel, scattered in triangle order (deterministic sums).
  constexpr int kChunk = 128;
  std::vector<Local> locals(kChunk);
  std::vector<size_t> next_item(tri_start.begin(), tri_start.end() - 1);  // per row: its next triangle
  for (int t0 = 0; t0 < T + K; t0 += kChunk) {
    const int t1 = std::min(T + K, t0 + kChunk);
    with_threads(threads, [&] {
      tbb::parallel_for(t0, t1, [&](int t) {
        Local& L = locals[t - t0];
        L.S.clear();
        if (idle(t)) return;
        Scratch& sc = scratch.local();
        if (t >= T) {
          BasisRow rb;
          tie_system(eval, pts.ties[static_cast<size_t>(t - T)], sc.row, rb, L.S, &L.G);
          return;
        }
        L.S = support[t];
        const size_t m = L.S.size();
        for (size_t a = 0; a < m; ++a) sc.where[L.S[a]] = static_cast<int>(a);
        L.G.assign(m * m, 0.0);
        if (fair) L.F.assign(m * m * 6, 0.0);
        L.rhs.assign(m * 3, 0.0);
        L.data_diag.assign(m, 0.0);
        std::vector<int> loc;
        const RowCache& C = cache[t];
        for (int q = pts.start[t]; q < pts.start[t + 1]; ++q) {
          const int i = pts.order[q];
          RowView r;
          if (C.filled) {
            const size_t at = static_cast<size_t>(q - pts.start[t]);
            const size_t b = static_cast<size_t>(C.start[at]);
            r = {C.index.data() + b, C.value.data() + b, fair ? C.du.data() + b : nullptr,
                 fair ? C.dv.data() + b : nullptr, static_cast<size_t>(C.start[at + 1]) - b};
          } else {
            if (!point_row(sc, pts.uv[i])) continue;
            r = {sc.row.index.data(), sc.row.value.data(), sc.row.du.data(), sc.row.dv.data(),
                 sc.row.index.size()};
          }
          const size_t k = r.size;
          loc.resize(k);
          for (size_t a = 0; a < k; ++a) {
            loc[a] = sc.where[r.index[a]];
            if (loc[a] < 0) throw SolverError("internal: basis function outside its support set");
            if (a > 0 && loc[a] <= loc[a - 1]) throw SolverError("internal: basis row not sorted");
          }
          const Point3& p = pts.p[i];
          const double pw = pts.point_weight(i);
          for (size_t a = 0; a < k; ++a) {
            const size_t ra = static_cast<size_t>(loc[a]) * m;
            const double wa = pw * r.value[a];
            for (size_t b = a; b < k; ++b) L.G[ra + loc[b]] += wa * r.value[b];
            L.data_diag[loc[a]] += wa * r.value[a];
            for (int c = 0; c < 3; ++c) L.rhs[3 * loc[a] + c] += wa * p[c];
          }
          if (fair) {
            const Vector3 nv = pts.n[i] * std::sqrt(pts.fair_weight(i));
            const double nn[6] = {nv.x() * nv.x(), nv.x() * nv.y(), nv.x() * nv.z(),
                                  nv.y() * nv.y(), nv.y() * nv.z(), nv.z() * nv.z()};
            for (size_t a = 0; a < k; ++a) {
              const size_t ra = static_cast<size_t>(loc[a]) * m;
              for (size_t b = a; b < k; ++b) {
                const double g = r.du[a] * r.du[b] + r.dv[a] * r.dv[b];
                double* f = &L.F[(ra + loc[b]) * 6];
                for (int c = 0; c < 6; ++c) f[c] += g * nn[c];
              }
            }
          }
        }
        if (bends(t)) {
          // Central differences of the exact first derivatives (rows x, x +- d e_u, x +- d e_v):
          // second derivatives for the thin-plate energy, third ones for the jerk energy.
          const double wb = pts.bend.empty() ? 0.0 : pts.bend[t];
          const double wj = pts.jerk.empty() ? 0.0 : pts.jerk[t];
          // Rows of all samples, each scaled by the square root of its weight, stacked into
          // A; the triangle adds A^T A (a dense product, far faster than row by row).
          const double c[7] = {wb, 2 * wb, wb, wj, 3 * wj, 3 * wj, wj};
          int active = 0;
          for (double ck : c) active += ck > 0;
          Eigen::MatrixXd& A = sc.A;
          A.resize(static_cast<Eigen::Index>(active) * 64, static_cast<Eigen::Index>(m));  // rows zeroed as used
          Eigen::Index rows = 0;
          bend_samples(sc, t, [&](const BendSample& b) {
            if (rows + active > A.rows()) A.conservativeResize(2 * A.rows(), Eigen::NoChange);
            const double f2 = 1.0 / (2 * b.delta), f4 = 1.0 / (4 * b.delta), f3 = 1.0 / (b.delta * b.delta);
            // Derivative k (0 uu, 1 uv, 2 vv, 3 uuu, 4 uuv, 5 uvv, 6 vvv) from the five rows
            // (x, x + d e_u, x - d e_u, x + d e_v, x - d e_v): coefficients of F_u (kU) and of
            // F_v (kV). uu, uuu, uvv come from F_u; vv, uuv, vvv from F_v; uv from both.
            static constexpr double kU[5][7] = {{0, 0, 0, -2, 0, -2, 0}, {1, 0, 0, 1, 0, 0, 0}, {-1, 0, 0, 1, 0, 0, 0},
                                                {0, 1, 0, 0, 0, 1, 0}, {0, -1, 0, 0, 0, 1, 0}};
            static constexpr double kV[5][7] = {{0, 0, 0, 0, -2, 0, -2}, {0, 1, 0, 0, 1, 0, 0}, {0, -1, 0, 0, 1, 0, 0},
                                                {0, 0, 1, 0, 0, 0, 1}, {0, 0, -1, 0, 0, 0, 1}};
            const double f[7] = {f2, f4, f2, f3, f3, f3, f3};
            double scale[7];
            Eigen::Index row_of[7];
            Eigen::Index next = rows;
            for (int k = 0; k < 7; ++k) {
              scale[k] = c[k] > 0 ? f[k] * std::sqrt(c[k] * b.weight) : 0.0;
              row_of[k] = c[k] > 0 ? next++ : -1;
            }
            A.middleRows(rows, next - rows).setZero();
            for (int side = 0; side < 5; ++side) {
              const BasisRow& r = b.row[side];
              for (size_t a = 0; a < r.index.size(); ++a) {
                const int l = sc.where[r.index[a]];
                if (l < 0) throw SolverError("internal: basis function outside its support set");
                const double u = r.du[a], v = r.dv[a];
                for (int k = 0; k < 7; ++k)
                  if (row_of[k] >= 0) A(row_of[k], l) += scale[k] * (kU[side][k] * u + kV[side][k] * v);
              }
            }
            rows = next;
          });
          if (rows > 0) {
            // L.G is row-major m x m; as a column-major map its lower triangle is what the
            // scatter below reads (entries (a, b >= a) of the row-major matrix).
            Eigen::Map<Eigen::MatrixXd> G(L.G.data(), static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
            G.selfadjointView<Eigen::Lower>().rankUpdate(A.topRows(rows).transpose());
          }
        }
        for (size_t a = 0; a < m; ++a) sc.where[L.S[a]] = -1;
      });
    });
    // Row j takes the chunk's triangles that hold control point j in triangle order (its
    // items are sorted by triangle): every entry sums in the same order for any thread count.
    with_threads(threads, [&] {
      tbb::parallel_for(0, N, [&](int j) {
        size_t& e = next_item[static_cast<size_t>(j)];
        for (; e < tri_start[j + 1] && tri_items[e].first < t1; ++e) {
          const Local& L = locals[tri_items[e].first - t0];
          const size_t a = static_cast<size_t>(tri_items[e].second), m = L.S.size();
          if (tri_items[e].first >= T) {
            size_t pos = row_start[j];
            for (size_t b = a; b < m; ++b) {
              while (cols[pos] != L.S[b]) ++pos;
              Gt[pos] += L.G[a * m + b];
            }
            continue;
          }
          for (int c = 0; c < 3; ++c) rhs[3 * static_cast<size_t>(j) + c] += L.rhs[3 * a + c];
          data_diag[j] += L.data_diag[a];
          // Columns L.S[a..] are sorted and a subset of row j's columns: merge walk.
          size_t pos = row_start[j];
          for (size_t b = a; b < m; ++b) {
            while (cols[pos] != L.S[b]) ++pos;
            // The local matrices hold their upper triangle (b >= a).
            G[pos] += L.G[a * m + b];
            if (fair)
              for (int c = 0; c < 6; ++c) F[c][pos] += L.F[(a * m + b) * 6 + c];
          }
        }
      });
    });
  }

  if (kept) {
    // For the next solve: the rows, and what decides whether they still hold.
    auto data = std::make_unique<KeptRows::Data>();
    data->fair = fair;
    data->triangles.resize(T);
    for (int t = 0; t < T; ++t) data->triangles[t] = d.triangle(t);
    data->knots = spline.knots();
    data->order.assign(pts.order.begin(), pts.order.end());
    data->start.assign(pts.start.begin(), pts.start.end());
    data->cache = std::move(cache);
    data->point_support = std::move(point_support);
    kept->data = std::move(data);
  }
  cache = std::vector<RowCache>();  // free before the factorisation

  // Regulariser scale: the mean diagonal of the data term over reached control points (the
  // smoothness terms left out: their scale follows the knot spacing, not the data).
  double diag = 0;
  int reached = 0;
  for (int j = 0; j < N; ++j)
    if (data_diag[j] > 0) diag += data_diag[j], ++reached;
  if (reached == 0) throw SolverError("no data point lies in the domain");
  diag /= reached;
  const double mu = kRegularization * diag;
  auto at = [&](int j, int k) {
    const auto b = cols.begin() + static_cast<long>(row_start[j]);
    const auto e = cols.begin() + static_cast<long>(row_start[j + 1]);
    return row_start[j] + static_cast<size_t>(std::lower_bound(b, e, k) - b);
  };
  for (size_t pos = 0; pos < Gt.size(); ++pos) G[pos] += kTieWeight * diag * Gt[pos];
  for (auto [j, k] : net) {
    G[at(j, j)] += mu;
    G[at(k, k)] += mu;
    G[at(j, k)] -= mu;
  }
  // A tiny pull toward the current control points keeps the system definite in any case.
  const double eps = 1e-6 * mu;
  const auto& c0 = spline.control_points();
  for (int j = 0; j < N; ++j) {
    G[row_start[j]] += eps;
    for (int c = 0; c < 3; ++c) rhs[3 * static_cast<size_t>(j) + c] += eps * c0[j][c];
  }

  // Only the fairness term couples x, y and z (through n n^T); everything else in G acts on
  // each coordinate alike. The split solve factorises the N x N scalar matrix S = G + lambda/2
  // (F_xx + F_yy + F_zz) once and solves the three coordinates with it: exactly when the
  // fairness term is off, else as the preconditioner of conjugate gradients on the coupled
  // system, which S approximates to the fairness weight's order (n n^T lies between 0 and I).
  // The coupled direct solve factorises the 3N x 3N system itself, 9 times the entries and
  // about 27 times the work.
  const int n3 = 3 * N;
  const Eigen::Map<const Eigen::VectorXd> b(rhs.data(), n3);
  using Chol = Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower>;
  auto factorise = [&](Chol& chol, const Eigen::SparseMatrix<double>& S, bool supernodal) {
    auto t = Clock::now();
    chol.setMode(supernodal ? Eigen::CholmodSupernodalLLt : Eigen::CholmodSimplicialLLt);
    chol.analyzePattern(S);
    if (times) times->analysis += since(t);
    t = Clock::now();
    if (chol.info() == Eigen::Success) chol.factorize(S);
    if (times) times->factorization += since(t);
    if (chol.info() != Eigen::Success)
      throw SolverError("the control-point system could not be factorised (" + std::to_string(S.rows()) +
                        " unknowns); the data may be degenerate");
  };
  // The coupled 3N x 3N lower triangle, column-major: column 3j+a holds rows 3k+b for k >= j
  // (b >= a on the diagonal block). Row j's first column is j itself, so column 3j+a has
  // 3 len(j) - a entries; the columns are filled in parallel, in place.
  auto coupled = [&] {
    Eigen::SparseMatrix<double> M(n3, n3);
    int* outer = M.outerIndexPtr();
    outer[0] = 0;
    for (int j = 0; j < N; ++j)
      for (int a = 0; a < 3; ++a)
        outer[3 * j + a + 1] = outer[3 * j + a] + 3 * static_cast<int>(row_start[j + 1] - row_start[j]) - a;
    M.resizeNonZeros(outer[n3]);
    int* inner = M.innerIndexPtr();
    double* values = M.valuePtr();
    static constexpr int kSym[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
    with_threads(threads, [&] {
      tbb::parallel_for(0, N, [&](int j) {
        for (int a = 0; a < 3; ++a) {
          size_t out = static_cast<size_t>(outer[3 * j + a]);
          for (size_t pos = row_start[j]; pos < row_start[j + 1]; ++pos) {
            const int k = cols[pos];
            for (int c = (k == j ? a : 0); c < 3; ++c) {
              double v = (a == c ? G[pos] : 0.0);
              if (fair) v += lambda * F[kSym[a][c]][pos];
              inner[out] = 3 * k + c;
              values[out++] = v;
            }
          }
        }
      });
    });
    return M;
  };
  Eigen::VectorXd x;
  if (solver == Solver::Split) {
    Eigen::SparseMatrix<double> S(N, N);  // filled in place: the pattern, then the values
    for (int j = 0; j <= N; ++j) S.outerIndexPtr()[j] = static_cast<int>(row_start[j]);
    S.resizeNonZeros(static_cast<Eigen::Index>(nnz));
    std::copy(cols.begin(), cols.end(), S.innerIndexPtr());
    for (size_t pos = 0; pos < nnz; ++pos)
      S.valuePtr()[pos] = G[pos] + (fair ? 0.5 * lambda * (F[0][pos] + F[3][pos] + F[5][pos]) : 0.0);
    const Eigen::SparseMatrix<double> M = fair ? coupled() : Eigen::SparseMatrix<double>();
    if (times) {
      times->assembly += since(t_stage);
      times->unknowns = N;
      times->nonzeros = S.nonZeros();
    }
    Chol chol;
    factorise(chol, S, true);
    t_stage = Clock::now();
    const ScalarPreconditioner scalar(chol);
    if (!fair) {
      x = scalar.solve(b);
    } else {
      Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower, ScalarPreconditioner> cg;
      cg.compute(M);
      cg.preconditioner() = scalar;
      cg.setTolerance(kCgTolerance);
      cg.setMaxIterations(kCgMaxIterations);
      x = cg.solve(b);
      if (times) times->cg_iterations += static_cast<int>(cg.iterations());
      if (cg.info() != Eigen::Success || !x.allFinite()) {
        // Not converged (a fairness term far stronger than the rest): the coupled system directly.
        if (times) times->solve += since(t_stage);
        Chol full;
        factorise(full, M, true);
        t_stage = Clock::now();
        x = full.solve(b);
        if (full.info() != Eigen::Success) x.setConstant(std::numeric_limits<double>::quiet_NaN());
      }
    }
  } else {
    const Eigen::SparseMatrix<double> M = coupled();
    if (times) {
      times->assembly += since(t_stage);
      times->unknowns = n3;
      times->nonzeros = M.nonZeros();
    }
    Chol chol;
    factorise(chol, M, solver == Solver::CoupledSupernodal);
    t_stage = Clock::now();
    x = chol.solve(b);
    if (chol.info() != Eigen::Success) x.setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  if (!x.allFinite())
    throw SolverError("the control-point solve failed (" + std::to_string(n3) + " unknowns)");
  std::vector<Point3> out(N);
  for (int j = 0; j < N; ++j) out[j] = x.segment<3>(3 * j);
  if (times) {
    times->solve += since(t_stage);
    for (const Scratch& sc : scratch) times->basis_rows += sc.row_seconds;
    ++times->solves;
  }
  return out;
}

}  // namespace tbs::detail
