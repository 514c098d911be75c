#pragma once
// Internal: the fitting domain (paper section 4.2) and its refinement, on CGAL's constrained
// Delaunay triangulation. Vertices have stable ids across refinement so knots can follow them.

#include <tbs/domain.h>
#include <tbs/types.h>

#include <array>
#include <memory>
#include <span>
#include <vector>

namespace tbs::detail {

struct DomainInput {
  std::span<const Point2> uv;
  std::span<const Point3> positions;
  std::span<const std::array<int, 3>> faces;  // empty for bare points
  int target_triangles = 200;
  bool features = true;
  double feature_angle_deg = 40;
  /// The parameters lie in several charts of an atlas: every component of the region the
  /// points cover is kept (but specks below 1e-4 of the largest's area), not the largest alone,
  /// and each keeps a margin beyond its outline.
  bool charts = false;
};

struct DomainStats {
  int holes = 0;
  int feature_chains = 0;
  double boundary_tolerance = 0;  // Douglas-Peucker tolerance finally used (parameter units)
  double target_edge = 0;         // the edge length aimed at
  double grid = 0;                // vertices lie on multiples of this power of two
};

class FitDomain {
 public:
  /// Builds the initial domain. \throw InvalidInput for degenerate or folded parameters.
  explicit FitDomain(const DomainInput& input);
  ~FitDomain();

  /// The current domain; vertex i has stable id ids()[i].
  const Domain& domain() const;
  const std::vector<int>& ids() const;
  const DomainStats& stats() const;
  /// Input points that are not in the parameter region (outliers of bare point sets).
  const std::vector<char>& excluded() const;

  /// Refines the given domain triangles by longest-edge bisection (a vertex at the midpoint
  /// of each one's longest edge; exact on boundary and feature edges, snapped elsewhere), keeps
  /// the constrained Delaunay property (edge flips), and rebuilds domain().
  void split(std::span<const int> triangles);

  /// Moves the vertex with stable id `id` (an interior vertex on no constraint) to p, as
  /// knot optimisation moved its primary knot; the triangulation follows at the next split().
  void move_vertex(int id, const Point2& p);

  /// Snaps a parameter point to the vertex grid.
  Point2 snap(const Point2& p) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tbs::detail
