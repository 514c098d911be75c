#pragma once
/// \file
/// Fast evaluation of a DMS spline: value, partial and directional derivatives, normals,
/// batches of points, and the sparse basis rows the fitter assembles its systems from.
///
/// The surface is evaluated through the degree n-1 form (METHOD.md section 4):
///   F(u)   = sum_{I, |g|=n-1} M(u | V_{I,g}) * sum_j d(X_{I,g}[j <- u]) c_{I,g+e_j}
///   D_v F  = n * sum_{I, |g|=n-1} M(u | V_{I,g}) * sum_j |d(X)| mu_j(v | X_{I,g}) c_{I,g+e_j}
/// where the simplex splines M are the nodes of one directed acyclic graph (after Franssen et
/// al., METHOD.md section 6): a node per distinct knot set, linked to the three knot sets of
/// its recurrence, each evaluated at most once per point.

#include <tbs/predicates.h>
#include <tbs/spline.h>

#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace tbs {

/// Sparse basis weights of one parameter point: F(u) = sum_k value[k] * c[index[k]], and
/// likewise F_u with du, F_v with dv. Indices are ascending and unique.
struct BasisRow {
  std::vector<int> index;
  std::vector<double> value, du, dv;
  void clear() {
    index.clear();
    value.clear();
    du.clear();
    dv.clear();
  }
};

/// Value and first partial derivatives at one point.
struct SurfacePoint {
  Point3 position;
  Vector3 du;  ///< dF/du
  Vector3 dv;  ///< dF/dv
};

/// How simplex splines are computed: through the shared graph (the default), or by plain
/// recursion on every knot set (the baseline the benchmarks compare against).
enum class EvalMode { Graph, Recursion };

/// Evaluates one Spline. Thread-safe for concurrent const calls.
///
/// The evaluator keeps a reference to the spline: it must outlive the evaluator. Control
/// points may change freely between calls; after moving knots call update_knots().
class Evaluator {
 public:
  /// Builds the graph and the spatial index. Throws nothing but std::bad_alloc.
  explicit Evaluator(const Spline& spline, EvalMode mode = EvalMode::Graph);
  /// A copy of `other` that evaluates `spline`, which must have the degree, domain and knots of
  /// other's spline (a copy of it, say; its control points may differ). Gives the same numbers
  /// as Evaluator(spline), faster: the graph is copied, not built. Throws nothing but
  /// std::bad_alloc; the precondition is not checked.
  Evaluator(const Evaluator& other, const Spline& spline);
  ~Evaluator();
  Evaluator(Evaluator&&) noexcept;
  Evaluator& operator=(Evaluator&&) noexcept;

  /// The domain triangle that contains u under the half-open rule, or -1 outside the domain.
  /// Points on the outer boundary belong to the triangle they lie on. Throws nothing.
  int locate(const Point2& u) const;

  /// The perturbation used for u (METHOD.md section 7): the standard one, or for points on the
  /// outer boundary one that points into the domain. Empty outside the domain. Throws nothing.
  std::optional<Perturbation> perturbation(const Point2& u) const;

  /// F(u). \throw OutsideDomain if u is not in the domain (or not finite).
  Point3 value(const Point2& u) const;
  /// F(u), F_u(u), F_v(u). \throw OutsideDomain if u is not in the domain (or not finite).
  SurfacePoint evaluate(const Point2& u) const;
  /// F(u), F_u(u), F_v(u) of the polynomial piece on a chosen side of u: the one that holds
  /// the perturbed point side.u + eps (side.c - side.u) + eps^2 (side.d - side.u). On a knot
  /// line or a feature edge this picks the piece (and the one-sided derivatives) of that side.
  /// \return empty if the perturbed point is outside the domain.
  /// \throw InvalidInput if side.u != u (also when u is NaN); never OutsideDomain.
  std::optional<SurfacePoint> evaluate(const Point2& u, const Perturbation& side) const;
  /// The directional derivative D_dir F(u).
  /// \throw OutsideDomain if u is not in the domain (or not finite).
  Vector3 derivative(const Point2& u, const Vector2& dir) const;
  /// The unit normal F_u x F_v / |F_u x F_v| (zero where the surface is singular).
  /// \throw OutsideDomain if u is not in the domain (or not finite).
  Vector3 normal(const Point2& u) const;

  /// Sparse basis weights of u for the value and both partial derivatives.
  /// \return false (row cleared) if u is outside the domain.
  /// Throws nothing but std::bad_alloc.
  bool basis_row(const Point2& u, BasisRow& row) const;

  /// Evaluates many points in parallel (TBB). Output spans may be empty to skip them;
  /// non-empty ones must have u.size() entries. Points outside the domain get NaN and
  /// inside[i] = 0. Results do not depend on the number of threads, nor on the order of the
  /// points: from 1,024 points on (and one point per 64 cells of the spatial index), the batch
  /// visits them grouped by cell of that index
  /// (sorted 2^20 at a time, 20 bytes a point of scratch memory, at most 20 MB), which makes
  /// random-order input about 1.7x faster and changes no value.
  /// \param threads maximum worker threads, 0 for all cores.
  /// \return the number of points outside the domain.
  /// \throw InvalidInput if a non-empty output span's size differs from u.size() (checked
  ///   before anything is written). Points outside the domain are not an error.
  size_t evaluate_batch(std::span<const Point2> u, std::span<Point3> position,
                        std::span<Vector3> du, std::span<Vector3> dv, std::span<uint8_t> inside,
                        int threads = 0) const;

  /// Re-reads the knots of `vertex` after Spline::set_knot(): recomputes only the graph nodes
  /// whose knot sets contain one of them, and the boxes of the triangles around the vertex;
  /// the spatial index is built again only when one of those boxes reaches a cell it was not
  /// listed in (results are the same either way).
  /// Throws nothing but std::bad_alloc; vertex is not range-checked.
  void update_knots(int vertex);

  /// Number of distinct simplex splines in the graph. Throws nothing.
  size_t node_count() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tbs
