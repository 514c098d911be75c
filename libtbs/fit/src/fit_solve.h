#pragma once
// Internal: the control-point sub-problem (paper section 4.3) as one sparse SPD system.

#include <tbs/evaluator.h>
#include <tbs/spline.h>
#include <tbs/tolerances.h>
#include <tbs/types.h>

#include <algorithm>
#include <cstddef>
#include <memory>
#include <span>
#include <vector>

namespace tbs::detail {

/// Weight of the control-net membrane regulariser relative to the mean diagonal of the data
/// term. It decides control points no data point reaches (holes in the data, margins) and is
/// small enough that the fit of well-covered regions moves by about this relative amount.
inline constexpr double kRegularization = 1e-9;

/// A tie across a seam of the atlas (METHOD.md section 10): the glued parameter points a and b
/// should give one surface, F(a) = F(b), and where the seam is smooth one tangent plane: the
/// derivative across the seam in b's chart, along cross_b, equals the derivative in a's chart
/// along cross_a = J cross_b (J, the derivative of the map from b's chart to a's). Each row is
/// scaled to unit length; the tie adds c0 |F(a) - F(b)|^2 + c1 |D_{cross_b} F(b) -
/// D_{cross_a} F(a)|^2 of them, times kTieWeight and the mean diagonal of the data term, to the
/// energy: linear terms in the control points, the same for x, y and z, solved with the rest.
struct SeamTie {
  Point2 a, b;
  double c0 = 1;  ///< weight of the gap
  double c1 = 0;  ///< weight of the cross derivative (0: a crease)
  Vector2 cross_a = Vector2::Zero(), cross_b = Vector2::Zero();
};

/// Weight of the seam ties against the data term: strong enough that the two sides of a seam
/// meet far inside the tolerance, weak enough to keep the system well conditioned.
inline constexpr double kTieWeight = 1e4;

struct FitPoints {
  std::span<const Point3> p;
  std::span<const Vector3> n;       // unit normals
  std::span<const Point2> uv;
  std::span<const int> triangle;    // located domain triangle per point, -1 = not used
  std::span<const int> order;       // point indices grouped by triangle (see group_by_triangle)
  std::span<const int> start;       // order[start[t] .. start[t+1]) are the points of t
  std::span<const double> fair;     // per-point factor of the fairness term (empty: 1)
  /// Per-triangle weight of the thin-plate term (empty: no such term): the bending energy
  /// integral of F over triangle t is multiplied by bend[t]; see solve_control_points.
  std::span<const double> bend = {};
  /// Per-triangle weight of the third-order term (empty: none): the integral over triangle t
  /// of |F_uuu|^2 + 3 |F_uuv|^2 + 3 |F_uvv|^2 + |F_vvv|^2, which vanishes on quadratics.
  std::span<const double> jerk = {};
  /// Per-point weight of the distance and fairness terms (empty: 1); guides have less.
  std::span<const double> weight = {};
  /// Seam ties (empty without an atlas).
  std::span<const SeamTie> ties = {};
  double fair_weight(int i) const { return (fair.empty() ? 1.0 : fair[i]) * point_weight(i); }
  double point_weight(int i) const { return weight.empty() ? 1.0 : weight[i]; }
};

/// Groups the points by triangle, in increasing index inside each group.
void group_by_triangle(std::span<const int> triangle, int triangle_count, std::vector<int>& order,
                       std::vector<int>& start);

/// Wall seconds of the parts of solve_control_points, summed over calls (FitReport::SolveStages).
struct SolveTimes {
  int solves = 0;
  double pattern = 0;        ///< support sets, sparsity pattern, control-net pairs
  double basis_rows = 0;     ///< thread-seconds of the points' basis rows (inside pattern and assembly)
  double assembly = 0;       ///< local normal equations, their scatter, the sparse matrix
  double analysis = 0;       ///< CHOLMOD ordering and symbolic factorisation
  double factorization = 0;  ///< CHOLMOD numeric factorisation
  double solve = 0;          ///< triangular solves and conjugate gradients
  int cg_iterations = 0;     ///< conjugate-gradient iterations of the split solves
  long kept_triangles = 0;   ///< triangles whose basis rows came from the previous solve (KeptRows)
  long unknowns = 0;         ///< rows of the last call's factorised matrix (N split, 3N coupled)
  long nonzeros = 0;         ///< of the last call's factorised matrix (lower triangle)
};

/// At most this many bytes of basis rows are kept from the pattern pass of a solve for its
/// assembly pass (each row is computed once instead of twice while they fit): all of them at
/// 200,000 points and degree 4 (about 145 MB, 3.5 s less per fit there), part at a million
/// points and degree 3, where a row is cheap to compute again.
inline constexpr size_t kRowCacheBytes = size_t{256} << 20;

/// The row-cache budget of one fit's solves, as the memory model counts it: up to about 2 b
/// entries of 28 bytes per point (b = beta_count(degree)), at most kRowCacheBytes. The rows of
/// the smoothness samples share it.
inline size_t row_cache_budget(size_t points, int degree) {
  const double b = beta_count(std::clamp(degree, 1, tol::kMaxDegree));
  return static_cast<size_t>(std::min(static_cast<double>(kRowCacheBytes), static_cast<double>(points) * 56 * b));
}

/// Basis rows one solve keeps for the next solve of the same fit: the rows of the triangles
/// whose points and surrounding knots have not changed since are taken as they are (the same
/// numbers the evaluator would give again), the others computed. Within the solve's budget. Pass
/// one object to the solves of one fit; it notices a new domain or moved knots by itself.
class KeptRows {
 public:
  KeptRows();
  ~KeptRows();
  KeptRows(const KeptRows&) = delete;
  KeptRows& operator=(const KeptRows&) = delete;
  struct Data;
  std::unique_ptr<Data> data;
};

/// How the control-point system is solved. Split (the default): CHOLMOD's supernodal
/// factorisation of the N x N matrix that x, y and z share, and conjugate gradients on the
/// coupling of the fairness term, preconditioned by it. The coupled direct solves factorise
/// the 3N x 3N system (simplicial: the solver before 2026-12-05); kept for comparison, they
/// agree with the split solve to rounding. All run BLAS serially: the result does not depend
/// on the thread count.
enum class Solver { Split, CoupledSupernodal, CoupledSimplicial };

/// Minimises sum |p - F(u)|^2 + lambda sum w_i ((n.F_u)^2 + (n.F_v)^2)
///           + sum_t bend[t] integral_t (|F_uu|^2 + 2 |F_uv|^2 + |F_vv|^2) + regulariser,
/// with w_i = pts.fair_weight(i), over the control
/// points of `spline` (knots fixed) and returns them. Deterministic for any thread count.
/// Adds its times to `times` when given. `row_cache_bytes` bounds the basis rows kept between
/// the two passes and, with `kept`, for the next solve (the result depends on neither).
/// \throw SolverError if the factorisation fails.
std::vector<Point3> solve_control_points(const Spline& spline, const Evaluator& eval,
                                         const FitPoints& pts, double lambda, int threads,
                                         SolveTimes* times = nullptr,
                                         Solver solver = Solver::Split,
                                         size_t row_cache_bytes = kRowCacheBytes,
                                         KeptRows* kept = nullptr);

}  // namespace tbs::detail
