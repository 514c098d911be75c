#pragma once
/// \file
/// The parameter domain: a planar triangulation with boundary loops (holes included) and
/// optional feature edges.

#include <tbs/types.h>

#include <span>
#include <vector>

namespace tbs {

/// A validated planar triangulation. Triangles are counter-clockwise; every edge has one or
/// two triangles; every vertex has a single fan of triangles (no pinch points); the boundary
/// loops are simple and do not touch each other, so the triangles never overlap.
///
/// Edges are numbered by ascending (min vertex, max vertex). Edge k of triangle t joins
/// corners k+1 and k+2 (mod 3), i.e. it is the edge opposite corner k.
class Domain {
 public:
  Domain() = default;

  /// Builds and validates a domain.
  /// \param vertices      #V parameter points.
  /// \param triangles     #F triangles, each three distinct vertex indices, counter-clockwise.
  /// \param feature_edges vertex pairs that must be interior edges of the triangulation.
  /// \throw InvalidInput naming the offending vertex, triangle or edge.
  Domain(std::vector<Point2> vertices, std::vector<std::array<int, 3>> triangles,
         std::vector<std::array<int, 2>> feature_edges = {});

  int vertex_count() const { return static_cast<int>(vertices_.size()); }
  int triangle_count() const { return static_cast<int>(triangles_.size()); }
  int edge_count() const { return static_cast<int>(edges_.size()); }

  const std::vector<Point2>& vertices() const { return vertices_; }
  const Point2& vertex(int i) const { return vertices_[i]; }
  const std::vector<std::array<int, 3>>& triangles() const { return triangles_; }
  const std::array<int, 3>& triangle(int t) const { return triangles_[t]; }

  /// Edges as (min vertex, max vertex), ascending.
  const std::vector<std::array<int, 2>>& edges() const { return edges_; }
  /// Edge index of (a, b) in either order, or -1. Throws nothing.
  int find_edge(int a, int b) const;
  /// The edge opposite corner k of triangle t.
  int triangle_edge(int t, int k) const { return triangle_edges_[3 * t + k]; }
  /// The two triangles of edge e (the second is -1 on the boundary).
  std::array<int, 2> edge_triangles(int e) const { return edge_triangles_[e]; }
  bool is_boundary_edge(int e) const { return edge_triangles_[e][1] < 0; }

  /// Triangles around vertex v (unordered).
  std::span<const int> vertex_triangles(int v) const {
    return {vertex_triangles_.data() + vertex_triangle_start_[v],
            vertex_triangles_.data() + vertex_triangle_start_[v + 1]};
  }
  bool is_boundary_vertex(int v) const { return boundary_next_[v] >= 0; }
  /// For a boundary vertex: the next and previous vertices along its boundary loop (the
  /// domain lies to the left of prev -> v -> next). -1 for interior vertices.
  int boundary_next(int v) const { return boundary_next_[v]; }
  int boundary_prev(int v) const { return boundary_prev_[v]; }

  /// Boundary loops, each a vertex cycle with the domain on its left (outer loops
  /// counter-clockwise, holes clockwise), in a deterministic order.
  const std::vector<std::vector<int>>& boundary_loops() const { return boundary_loops_; }

  /// Feature edges as given (normalized to (min, max), ascending, duplicates removed).
  const std::vector<std::array<int, 2>>& feature_edges() const { return feature_edges_; }
  bool is_feature_edge(int e) const { return is_feature_edge_[e] != 0; }

  /// Bounding box of the vertices. Throws nothing.
  Box2 bounding_box() const;

  /// Moves vertex v (used when a primary knot moves). Checks that the triangles around v stay
  /// counter-clockwise; it does not re-check the boundary for self-intersection.
  /// \throw InvalidInput if p is not finite or a triangle around v would flip or degenerate; the
  ///   vertex then stays where it was. v is not range-checked.
  void move_vertex(int v, const Point2& p);

 private:
  void build_topology();
  void check_boundary_simple() const;

  std::vector<Point2> vertices_;
  std::vector<std::array<int, 3>> triangles_;
  std::vector<std::array<int, 2>> edges_;
  std::vector<std::array<int, 2>> edge_triangles_;
  std::vector<int> triangle_edges_;
  std::vector<int> vertex_triangle_start_;
  std::vector<int> vertex_triangles_;
  std::vector<int> boundary_next_;
  std::vector<int> boundary_prev_;
  std::vector<std::vector<int>> boundary_loops_;
  std::vector<std::array<int, 2>> feature_edges_;
  std::vector<char> is_feature_edge_;
};

}  // namespace tbs
