// The 3D curves of trim edges (trim_curve.h).

#include "trim_curve.h"

#include "bspline_basis.h"

#include <tbs/errors.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>

namespace tbs::detail {

std::vector<double> uniform_breaks(double a, double b, int spans) {
  std::vector<double> br(static_cast<size_t>(spans) + 1);
  for (int i = 0; i <= spans; ++i) br[static_cast<size_t>(i)] = a + (b - a) * i / spans;
  br.back() = b;
  return br;
}

int span_of(const std::vector<double>& breaks, double u) {
  const auto it = std::upper_bound(breaks.begin(), breaks.end(), u);
  const int i = static_cast<int>(it - breaks.begin()) - 1;
  return std::clamp(i, 0, static_cast<int>(breaks.size()) - 2);
}

std::vector<double> breaks_and_midpoints(const std::vector<double>& br) {
  std::vector<double> out;
  for (size_t i = 0; i + 1 < br.size(); ++i) {
    out.push_back(br[i]);
    out.push_back(0.5 * (br[i] + br[i + 1]));
  }
  out.push_back(br.back());
  return out;
}

std::vector<double> inner_points(const std::vector<double>& br, int p) {
  std::vector<double> out;
  for (size_t i = 0; i + 1 < br.size(); ++i)
    for (int k = 0; k <= p; ++k) out.push_back(br[i] + (br[i + 1] - br[i]) * (k + 0.5) / (p + 1));
  return out;
}

BSplineCurve3 fit_trim_curve(const std::function<Point3(double)>& target, double length, int spans,
                             const std::vector<double>& checks, int degree, double tol, int rounds) {
  const Point3 fa = target(0), fb = target(length);
  const int p = degree;
  BSplineCurve3 curve;
  std::vector<double> br = uniform_breaks(0, length, std::max(1, spans));
  for (int round = 0; round < rounds; ++round) {
    const std::vector<double> k = clamped_knots(p, br);
    const int n = static_cast<int>(k.size()) - p - 1;
    // Unknowns: poles 1 .. n-2; the ends are the target's.
    const int m = n - 2;
    std::vector<Point3> poles(static_cast<size_t>(n));
    poles.front() = fa;
    poles.back() = fb;
    if (m > 0) {
      std::vector<Eigen::Triplet<double>> entries;
      Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(m, 3);
      for (double t : inner_points(br, p + 1)) {
        const int s = find_span(k, p, t);
        Basis bs;
        basis_functions(k, p, s, t, 0, bs);
        Point3 f = target(t);
        for (int j = 0; j <= p; ++j) {
          const int idx = s - p + j;
          if (idx == 0) f -= bs.value[j] * fa;
          if (idx == n - 1) f -= bs.value[j] * fb;
        }
        for (int j = 0; j <= p; ++j) {
          const int row = s - p + j - 1;
          if (row < 0 || row >= m) continue;
          rhs.row(row) += bs.value[j] * f.transpose();
          for (int l = 0; l <= p; ++l) {
            const int col = s - p + l - 1;
            if (col < 0 || col >= m) continue;
            entries.emplace_back(row, col, bs.value[j] * bs.value[l]);
          }
        }
      }
      Eigen::SparseMatrix<double> mat(m, m);
      mat.setFromTriplets(entries.begin(), entries.end());
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(mat);
      const Eigen::MatrixX3d x = ldlt.solve(rhs);
      if (ldlt.info() != Eigen::Success || !x.allFinite())
        throw SolverError("region faces: the least-squares system of a trim curve could not be solved");
      for (int i = 0; i < m; ++i) poles[static_cast<size_t>(i) + 1] = x.row(i).transpose();
    }
    curve = {p, k, poles};
    // Check between the fit samples (2p + 2 points per span), at the breaks and at `checks`.
    std::vector<double> check = breaks_and_midpoints(br);
    const std::vector<double> between = inner_points(br, 2 * p + 1);
    check.insert(check.end(), between.begin(), between.end());
    check.insert(check.end(), checks.begin(), checks.end());
    std::vector<char> mark(br.size() - 1, 0);
    bool failed = false;
    for (double t : check) {
      t = std::clamp(t, 0.0, length);
      if ((curve.value(t) - target(t)).norm() > tol) {
        failed = true;
        mark[static_cast<size_t>(span_of(br, t))] = 1;
      }
    }
    if (!failed) break;
    std::vector<double> next;
    for (size_t i = 0; i + 1 < br.size(); ++i) {
      next.push_back(br[i]);
      if (mark[i]) next.push_back(0.5 * (br[i] + br[i + 1]));
    }
    next.push_back(br.back());
    br = std::move(next);
  }
  return curve;
}

}  // namespace tbs::detail
