#pragma once
// Internal: the pieces the fit domain is built from (fit_domain.cpp). The region of the
// parameter plane the points cover and its outline (fit_outline.cpp), and the sharp features
// inside it (fit_features.cpp), over input point indices.

#include <tbs/predicates.h>
#include <tbs/types.h>

#include "edge_key.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <unordered_set>
#include <utility>
#include <vector>

namespace tbs::detail {

// A triangulated region of the parameter plane, over input point indices, CCW in uv.
struct Region {
  std::vector<std::array<int, 3>> tris;
};

inline double signed_area2(const Point2& a, const Point2& b, const Point2& c) { return det3(a, b, c); }

// Triangle neighbours through each point's star (the triangles using it, by index): linear
// in the region's size, and without the hash tables that made a million-point region slow.
struct Adjacency {
  std::vector<int> start, star;  // the star of point v: star[start[v]] .. star[start[v + 1] - 1]
  // across[f][k]: the first other triangle (by index) with both ends of edge (t[k], t[k + 1]);
  // -1 on the outline.
  std::vector<std::array<int, 3>> across;
  // The first triangle (by index) that runs an edge in the same direction as an earlier one
  // (the region is then not manifold), with that edge; face -1 if there is none.
  struct Duplicate {
    int face = -1, a = -1, b = -1;
  } duplicate;

  std::span<const int> star_of(int v) const {
    return {star.data() + start[v], static_cast<size_t>(start[v + 1] - start[v])};
  }
};

// ---------------------------------------------------------------- fit_outline.cpp

// The adjacency of a region: its points' stars and each triangle's neighbours, searched.
Adjacency adjacency(const Region& r, size_t n_points);
// The adjacency of a region whose neighbours are already known (`across`, as Adjacency holds it).
Adjacency adjacency(const Region& r, size_t n_points, std::vector<std::array<int, 3>> across);
// The region of a mesh's faces, oriented counter-clockwise. \throw InvalidInput if the
// faces fold over in (u, v).
Region region_from_faces(std::span<const Point2> uv, std::span<const std::array<int, 3>> faces);
// The region of bare points: their Delaunay triangulation, cut back to an alpha shape of the
// local spacing; `across` receives each kept triangle's neighbours.
Region region_from_points(std::span<const Point2> uv, std::vector<std::array<int, 3>>& across);
// The closed boundary loops of a region, as point indices; the outer loop first.
std::vector<std::vector<int>> boundary_loops(const Region& r, const Adjacency& adj, size_t n_points);
// Keeps the largest edge-connected part of the region, and every other part whose area is at
// least keep_share times its (the charts of an atlas; above 1, none), and renumbers adj;
// returns how many triangles were dropped.
size_t keep_largest_component(Region& r, std::span<const Point2> uv, Adjacency& adj, double keep_share);
// Takes back into the region the excluded points that duplicate a kept one's (u, v).
void include_duplicates(std::span<const Point2> uv, std::vector<char>& excluded);
// Douglas-Peucker on the open polyline p[i..j]: marks in keep the points it keeps (not the ends).
void douglas_peucker(std::span<const Point2> p, size_t i, size_t j, double tol, std::vector<char>& keep);
// The points of a polyline that Douglas-Peucker keeps at tolerance tol (ends always kept).
std::vector<Point2> simplified(const std::vector<Point2>& line, double tol);
// Adds points so that no segment of the polyline is longer than h.
std::vector<Point2> resample(const std::vector<Point2>& poly, double h, bool closed);
// Whether segments ab and cd intersect, other than at a shared endpoint (overlapping
// collinear segments do).
bool segments_cross(const Point2& a, const Point2& b, const Point2& c, const Point2& d);

// --------------------------------------------------------------- fit_features.cpp

// Sharp edges of the region (dihedral angle of the 3D triangles above the threshold), chained
// into polylines of point indices.
std::vector<std::vector<int>> feature_chains(const Region& r, const Adjacency& adj, std::span<const Point3> pos,
                                             double angle_deg);
// Creases that no edge follows (bare points, or meshes whose edges cross the crease): the
// triangles straddling a crease share its angle between several edges, none of them sharp. A
// band of edges bent by more than a third of the feature angle, long and thin, whose two sides
// have normals more than the feature angle apart, is a crease; its centre line (centroids of
// the band's triangles, averaged in bins along the band's main axis) goes into the domain.
std::vector<std::vector<Point2>> band_creases(const Region& r, const Adjacency& adj, std::span<const Point2> uv,
                                              std::span<const Point3> pos, double angle_deg,
                                              double h, const std::unordered_set<uint64_t>& taken);

}  // namespace tbs::detail
