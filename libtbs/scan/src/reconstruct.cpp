// The surface of a point cloud (reconstruct_surface, scan_mesh.h): CGAL's advancing-front
// reconstruction on the points' Delaunay triangulation, with the faces that bridge gaps in the
// samples removed.

#include "scan_mesh.h"

#include <tbs/errors.h>

#include <CGAL/Advancing_front_surface_reconstruction.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>

// CGAL's advancing-front reconstruction, made to depend on the points alone. Two things in it
// followed memory addresses, so the same points meshed differently from one process layout to
// the next (the command against Python, or a second call in one process):
// - its border edges wait in a std::set ordered by (priority, pointer), and equal priorities
//   are common (the same candidate facet for two edges, the fixed marks for edges put off);
// - its clean-up removes vertices from the Delaunay triangulation, whose re-triangulation
//   orders and hashes vertex and cell handles by address.
// Here the handles carry time stamps (CGAL's Compact_container then compares and hashes them
// by creation order, as Mesh_3 does for the same reason) and equal priorities go by the
// indices of the edge's two points, which identify a border edge for as long as it waits.
namespace tbs::afsr {

template <typename Base>
struct Stamped : Base {
  using Base::Base;
  template <typename Tds2>
  struct Rebind_TDS {
    using Other = Stamped<typename Base::template Rebind_TDS<Tds2>::Other>;
  };
  using Has_timestamp = CGAL::Tag_true;
  std::size_t time_stamp() const { return stamp; }
  void set_time_stamp(const std::size_t& s) { stamp = s; }
  std::size_t stamp = std::size_t(-1);
};

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Tds = CGAL::Triangulation_data_structure_3<
    Stamped<CGAL::Advancing_front_surface_reconstruction_vertex_base_3<Kernel>>,
    Stamped<CGAL::Advancing_front_surface_reconstruction_cell_base_3<Kernel>>>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, Tds>;
using Vertex = Delaunay::Vertex;
using WaitingEdge = Vertex::Radius_ptr_type;  // (priority, the border edge's facets)
static_assert(CGAL::internal::Has_timestamp<Vertex>::value && CGAL::internal::Has_timestamp<Delaunay::Cell>::value);

}  // namespace tbs::afsr

// Must be seen before Advancing_front_surface_reconstruction<afsr::Delaunay> instantiates its set.
template <>
struct std::less<tbs::afsr::WaitingEdge> {
  static std::pair<std::size_t, std::size_t> ends(const tbs::afsr::Vertex::IO_edge_type* e) {
    const auto& edge = e->first.first;  // (cell, i, j): the edge from vertex i to vertex j
    const std::size_t a = edge.first->vertex(edge.second)->info(), b = edge.first->vertex(edge.third)->info();
    return a < b ? std::make_pair(a, b) : std::make_pair(b, a);
  }
  bool operator()(const tbs::afsr::WaitingEdge& x, const tbs::afsr::WaitingEdge& y) const {
    if (x.first != y.first) return x.first < y.first;
    if (x.second == y.second) return false;
    const auto ex = ends(x.second), ey = ends(y.second);
    return ex != ey ? ex < ey : x.second < y.second;  // one entry per border edge: the last never decides
  }
};

namespace tbs::detail {

std::vector<Tri> reconstruct_surface(const Scan& scan, const std::string& name, ParameterizeReport& rep,
                                     const std::function<void(const std::string&)>& say) {
  std::vector<Tri> triangles;
  // A surface needs points that span a plane at least; CGAL's triangulation would only
  // complain on stderr.
  {
    Point3 mean = Point3::Zero();
    for (const Point3& p : scan.positions) mean += p;
    mean /= static_cast<double>(scan.positions.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const Point3& p : scan.positions) cov += (p - mean) * (p - mean).transpose();
    const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();
    if (!(ev[2] > 0))
      throw InvalidInput(name + ": all " + std::to_string(scan.positions.size()) +
                         " points are identical; there is no surface to fit");
    if (ev[1] <= 1e-20 * ev[2])
      throw InvalidInput(name + ": all points lie on one line; there is no surface to fit");
  }
  say("reconstructing a surface from " + plural(scan.positions.size(), "point", "points") + " (advancing front)");
  std::vector<std::pair<P3, std::size_t>> pts;  // each point with its index
  pts.reserve(scan.positions.size());
  for (const Point3& p : scan.positions) pts.emplace_back(P3(p.x(), p.y(), p.z()), pts.size());
  std::vector<std::array<std::size_t, 3>> facets;
  {
    afsr::Delaunay dt(pts.begin(), pts.end());
    // The local spacing of each point: its third-nearest Delaunay neighbour (the nearest
    // neighbours are among them), before the reconstruction removes any vertex.
    std::vector<double> spacing(pts.size(), 0.0);
    std::vector<double> len;
    std::vector<afsr::Delaunay::Vertex_handle> around;
    for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) {
      around.clear();
      len.clear();
      dt.finite_adjacent_vertices(v, std::back_inserter(around));
      for (auto w : around) len.push_back(std::sqrt(CGAL::squared_distance(v->point(), w->point())));
      if (len.empty()) continue;
      const auto k = static_cast<long>(std::min<size_t>(2, len.size() - 1));
      std::nth_element(len.begin(), len.begin() + k, len.end());
      spacing[v->info()] = len[static_cast<size_t>(k)];
    }
    CGAL::Advancing_front_surface_reconstruction<afsr::Delaunay> reconstruction(dt);
    reconstruction.run();  // CGAL's defaults: radius ratio bound 5, beta 0.52
    CGAL::write_triple_indices(std::back_inserter(facets), reconstruction);
    // Bridges: a face with an edge longer than kBridgeRatio times the spacing at both of its
    // ends spans a gap in the samples (the reconstruction joins separate clusters of points
    // that way). Such long, thin faces made LSCM fold on poste_france.xyz and its fallback
    // distort the map 90-fold; they are removed, and a cluster they alone held on becomes a
    // component of its own.
    constexpr double kBridgeRatio = 20;
    const size_t before = facets.size();
    std::erase_if(facets, [&](const std::array<std::size_t, 3>& f) {
      for (int k = 0; k < 3; ++k) {
        const std::size_t a = f[k], b = f[(k + 1) % 3];
        if ((scan.positions[a] - scan.positions[b]).norm() > kBridgeRatio * std::max(spacing[a], spacing[b]))
          return true;
      }
      return false;
    });
    rep.bridge_faces_removed = before - facets.size();
  }
  // The facets come in the order of the reconstruction's surface data structure: each now
  // starts at its smallest index (orientation kept) and they are sorted.
  for (auto& f : facets) std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
  std::sort(facets.begin(), facets.end());
  for (const auto& f : facets) triangles.push_back({int(f[0]), int(f[1]), int(f[2])});
  rep.reconstructed_faces = triangles.size();
  if (triangles.empty())
    throw InvalidInput(name + ": no surface could be reconstructed from these points (they may be collinear, "
                       "coplanar in a line, or too few); give a mesh instead");
  return triangles;
}

}  // namespace tbs::detail
