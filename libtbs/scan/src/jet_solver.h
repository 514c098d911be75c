#pragma once
// The least-squares solver of the normals' jet fit, as CGAL's SvdTraits concept
// (CGAL::Monge_via_jet_fitting takes one). CGAL::Eigen_svd solves with a Jacobi SVD, which
// was a fifth of the time of a fit of 1M bare points. Eigen's complete orthogonal
// decomposition gives the same solution, the minimum-norm least-squares one (also where the
// system is rank-deficient), from a column-pivoted QR: far fewer operations on the k x 6
// systems of a degree-2 jet. Internal; the tests compare it with CGAL::Eigen_svd.

#include <CGAL/Eigen_matrix.h>
#include <CGAL/Eigen_vector.h>

#include <Eigen/QR>
#include <limits>

namespace tbs::detail {

struct JetSolver {
  using FT = double;
  using Vector = CGAL::Eigen_vector<FT>;
  using Matrix = CGAL::Eigen_matrix<FT>;
  /// Solves M X = B in the least-squares sense (minimum norm) into B. Returns the condition
  /// number estimated from the diagonal of the pivoted triangular factor (CGAL keeps it with
  /// the fit; tbs does not use it), infinity when M is zero.
  static FT solve(const Matrix& M, Vector& B) {
    const Eigen::CompleteOrthogonalDecomposition<Matrix::EigenType> cod(M.eigen_object());
    B.eigen_object() = cod.solve(Vector::EigenType(B.eigen_object()));
    if (cod.rank() == 0) return std::numeric_limits<FT>::infinity();
    const auto diagonal = cod.matrixQTZ().diagonal().head(cod.rank()).cwiseAbs();
    return diagonal.maxCoeff() / diagonal.minCoeff();
  }
};

}  // namespace tbs::detail
