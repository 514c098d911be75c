#pragma once
// Internal: the triangle mesh parameterize_scan() works on, and its steps, each in its own
// file: the surface of a point cloud (reconstruct.cpp), repair, components, topology and the
// seam cut (mesh_repair.cpp), flattening (flatten.cpp) and the guide subdivision
// (subdivide.cpp).

#include <tbs/parameterize.h>
#include <tbs/scan.h>

#include "edge_key.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <array>
#include <cstdint>
#include <functional>
#include <numeric>
#include <string>
#include <vector>

namespace tbs::detail {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P3 = K::Point_3;
using P2 = K::Point_2;
using Tri = std::array<int, 3>;

// A number for a message, in 4 significant digits.
std::string short_number(double x);
// "1 point", "2 points".
std::string plural(size_t n, const char* one, const char* many);

// A key for the directed edge a -> b.
inline uint64_t directed_key(int a, int b) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
}


struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(int a, int b) { parent[find(a)] = find(b); }
};

// A triangle soup with int indices.
struct Mesh3 {
  std::vector<Point3> points;
  std::vector<Tri> faces;
};


// Boundary loops of an oriented manifold mesh as vertex cycles (a boundary halfedge a->b has
// no opposite b->a).
std::vector<std::vector<int>> boundary_loops(const std::vector<Tri>& faces);

// The surface of a point cloud: CGAL's advancing-front reconstruction, made to depend on the
// points alone, without the faces that bridge gaps in the samples. \throw InvalidInput if the
// points span no plane or no surface comes out.
std::vector<Tri> reconstruct_surface(const Scan& scan, const std::string& name, ParameterizeReport& rep,
                                     const std::function<void(const std::string&)>& say);


// Merges duplicate vertices, drops degenerate and duplicate faces and unused vertices, orients
// the faces consistently (splitting non-manifold vertices), and removes zero-area faces by
// edge collapses and flips, all with CGAL's Polygon_mesh_processing.
Mesh3 repair(const std::vector<Point3>& positions, const std::vector<Tri>& triangles, ParameterizeReport& rep);


// Components by shared edges, numbered by decreasing face count (ties: first face first).
std::vector<int> face_components(const std::vector<Tri>& faces, int& count);


// The atlas of a surface (charts.cpp): the mesh with a vertex per chart it is in (faces in
// their order), the parameters of the charts laid side by side, and the seams between them.
struct ChartCut {
  Mesh3 mesh;
  std::vector<P2> uv;
  std::vector<int> origin;  // the input vertex of each vertex
  std::vector<Seam> seams;
  std::vector<std::vector<Point2>> borders;  // the mesh's boundary, as Atlas::borders
  int charts = 0;
  size_t seam_edges = 0;
  double stretch = 0;  // the largest flattening_stretch of a chart
};

// Cuts a surface (a repaired, oriented, connected manifold mesh) into charts: along sharp
// edges, across handles, between the boundary loops of tubes, and in two where a chart is
// closed or stretches beyond options.chart_stretch; flattens each and lays them out.
// \throw InvalidInput if a chart can be neither cut nor flattened.
ChartCut cut_into_charts(const Mesh3& m, const ParameterizeOptions& o, ParameterizeReport& rep);

// How far a flattening would stretch a spline fitted over it (charts.cpp): 1 over the smaller
// singular value of the triangles' maps, times the (u, v) box's diagonal over the 3D box's,
// the map scaled to the surface's area; the largest but for 0.5 % of the area.
double flattening_stretch(const Mesh3& m, const std::vector<P2>& uv);

// Scales the parameters to the surface's area, turns them to their principal axes (a rotation,
// so orientation is kept) and moves their box to the origin.
void normalise(const Mesh3& m, std::vector<P2>& uv);

// The distortion of the map uv of m, weighted by the triangles' 3D areas.
Distortion distortion(const Mesh3& m, const std::vector<P2>& uv);

// Flattens a disk with holes; tries LSCM first unless told otherwise.
std::vector<P2> flatten(const Mesh3& m, const ParameterizeOptions& o, ParameterizeReport& rep);


// One 1-to-4 subdivision with new vertices on a smooth surface through the old ones: the
// midpoint of each edge's cubic curve of the PN triangle (Vlachos et al. 2001) built from the
// end points and their corner normals. Where the two faces of an edge disagree on a normal (a
// crease) the edge stays straight. Parameters are the midpoints in (u, v). `origin` maps each
// vertex to an original vertex (for normals).
void subdivide(Mesh3& m, std::vector<P2>& uv, std::vector<int>& origin, double sharp_deg);

}  // namespace tbs::detail
