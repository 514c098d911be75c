#pragma once
/// \file
/// Exact Bezier extraction: the DMS spline as the triangular Bezier patches it is made of.
///
/// On a domain triangle D the spline is a polynomial of its degree n on every cell of the
/// arrangement of the segments between the knots of each knot set V_{J,g} (|g| = n-1) whose
/// hull meets D (METHOD.md section 4). The arrangement is built with CGAL's Arrangement_2 over
/// exact constructions; each cell is triangulated (constrained Delaunay) and each resulting
/// piece gets the degree-n Bezier net of the surface on it.

#include <tbs/spline.h>

#include <span>
#include <vector>

namespace tbs {

/// One polynomial piece: a triangle of the parameter plane inside one arrangement cell.
struct BezierPiece {
  int triangle = -1;                 ///< The domain triangle the piece lies in.
  int cell = -1;                     ///< The arrangement cell within that triangle (0-based).
  std::array<int, 3> corners{};      ///< Indices into Extraction::vertices, counter-clockwise.
};

/// The result of extract_bezier().
struct Extraction {
  int degree = 0;                    ///< n, the degree of every net.
  /// Parameter points of the piece corners. A point shared by several pieces (also across
  /// domain triangles) appears once: the corners are indices into this list.
  std::vector<Point2> vertices;
  std::vector<BezierPiece> pieces;   ///< Grouped by domain triangle, in triangle order.
  /// beta_count(degree) control points per piece, in beta order; b_j goes with corners[j].
  /// Pieces with a common edge have bit-identical control points along it.
  std::vector<Point3> control_points;
  std::vector<int> cells;            ///< Arrangement cells per domain triangle.
  std::vector<int> piece_start;      ///< Pieces of triangle t: [piece_start[t], piece_start[t+1]).

  std::span<const Point3> net(int piece) const {
    const size_t k = static_cast<size_t>(beta_count(degree));
    return {control_points.data() + k * static_cast<size_t>(piece), k};
  }
};

struct ExtractOptions {
  int threads = 0;  ///< Worker threads, 0 for all cores. The result does not depend on it.
};

/// Extracts the exact piecewise Bezier form of `spline`.
/// \pre the spline satisfies the knot conditions (check_knot_conditions()).
/// \throw InvalidInput if the spline has no triangles; Error (the base class) if a triangle's
///   arrangement and its triangulation disagree (an internal failure, named by triangle).
Extraction extract_bezier(const Spline& spline, const ExtractOptions& options = {});

}  // namespace tbs
