// Normal estimation: CGAL's jet fitting (Monge_via_jet_fitting, the fit behind
// CGAL::jet_estimate_normals) on k nearest neighbours found with CGAL's kd-tree, then an
// orientation from the parameters, the faces or the scan's PCA frame (see tbs/scan.h).
//
// We run the per-point loop ourselves rather than calling CGAL::jet_estimate_normals so that
// the orientation sees exactly the neighbours the fit saw, with one search per point. The loop
// visits the points in Hilbert order, so that consecutive searches walk the same part of the
// tree and of the point array; each point's normal does not depend on that order. The jet's
// least-squares systems are solved by a complete orthogonal decomposition (jet_solver.h), not
// by the SVD CGAL's jet_estimate_normals uses: the same solutions, in about half the time.
#include <CGAL/Monge_via_jet_fitting.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Spatial_sort_traits_adapter_3.h>
#include <CGAL/Hilbert_sort_median_3.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbs/errors.h>
#include <tbs/scan.h>

#include "jet_solver.h"

#include <Eigen/Eigenvalues>
#include <boost/iterator/counting_iterator.hpp>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <thread>

namespace tbs {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using CPoint = Kernel::Point_3;

// The kd-tree stores indices; this map gives their points.
struct IndexPointMap {
  const std::vector<CPoint>* points = nullptr;
  using key_type = std::uint32_t;
  using value_type = CPoint;
  using reference = const CPoint&;
  using category = boost::readable_property_map_tag;
  friend reference get(const IndexPointMap& m, key_type i) { return (*m.points)[i]; }
};

using TreeTraits =
    CGAL::Search_traits_adapter<std::uint32_t, IndexPointMap, CGAL::Search_traits_3<Kernel>>;
using Search = CGAL::Orthogonal_k_neighbor_search<TreeTraits>;
using Tree = Search::Tree;
using Distance = Search::Distance;
using JetFit = CGAL::Monge_via_jet_fitting<Kernel, Kernel, detail::JetSolver>;

constexpr int kJetDegree = 2;
constexpr int kMinNeighbours = (kJetDegree + 1) * (kJetDegree + 2) / 2;  // jet coefficients
// A neighbourhood whose second PCA variance is below this fraction of the first is a line or a
// point: no plane, hence no normal. Far below any real sampling anisotropy.
constexpr double kDegenerateRatio = 1e-12;

// The axis of least variance of `pts`, signed so that its largest component is positive.
Vector3 pca_up(std::span<const Point3> pts) {
  Point3 mean = Point3::Zero();
  for (const Point3& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Point3& p : pts) cov += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Vector3 up = eig.eigenvectors().col(0);
  Eigen::Index i = 0;
  up.cwiseAbs().maxCoeff(&i);
  return up[i] < 0 ? Vector3(-up) : up;
}

}  // namespace

std::vector<Vector3> estimate_normals(std::span<const Point3> positions, std::span<const Point2> uv,
                                      std::span<const std::array<int, 3>> triangles, int k,
                                      const std::function<void(double)>& progress) {
  const std::size_t n = positions.size();
  if (k < kMinNeighbours)
    throw InvalidInput("estimate_normals: k = " + std::to_string(k) +
                       " is too small; jet fitting of degree 2 needs at least " +
                       std::to_string(kMinNeighbours) + " neighbours");
  if (!uv.empty() && uv.size() != n)
    throw InvalidInput("estimate_normals: " + std::to_string(uv.size()) + " parameters for " +
                       std::to_string(n) + " points; give one (u, v) per point or none");
  if (n > UINT32_MAX) throw InvalidInput("estimate_normals: more than 2^32 - 1 points");
  for (std::size_t i = 0; i < n; ++i)
    if (!positions[i].allFinite())
      throw InvalidInput("estimate_normals: point " + std::to_string(i) + " is not finite");
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int c = 0; c < 3; ++c)
      if (triangles[t][c] < 0 || static_cast<std::size_t>(triangles[t][c]) >= n)
        throw InvalidInput("estimate_normals: triangle " + std::to_string(t) + " refers to point " +
                           std::to_string(triangles[t][c]) + ", outside 0 to " + std::to_string(n) +
                           " - 1");

  // Duplicated positions (UV seams, merged scans) would fill a neighbourhood with copies of one
  // point; the fit sees each position once and every copy gets its normal. Unique positions are
  // numbered in the order of their first copy: (position, index) sorted in parallel, so that
  // each group of equal positions starts with its first copy.
  std::vector<CPoint> unique;
  std::vector<std::uint32_t> unique_of(n);
  std::vector<std::uint32_t> first_of;  // a point at each unique position
  {
    const auto key = [&](std::size_t i) {
      Point3 k = positions[i];
      for (int c = 0; c < 3; ++c)
        if (k[c] == 0.0) k[c] = 0.0;  // +0 and -0 are one position
      return k;
    };
    struct Entry {
      Point3 p;
      std::uint32_t i;
    };
    std::vector<Entry> sorted(n);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) { sorted[i] = {key(i), static_cast<std::uint32_t>(i)}; });
    tbb::parallel_sort(sorted.begin(), sorted.end(), [](const Entry& a, const Entry& b) {
      for (int c = 0; c < 3; ++c)
        if (a.p[c] != b.p[c]) return a.p[c] < b.p[c];
      return a.i < b.i;
    });
    // first[i]: the first copy of point i's position (first[i] <= i).
    std::vector<std::uint32_t> first(n);
    std::size_t groups = 0;
    for (std::size_t j = 0; j < n; ++groups) {
      std::size_t e = j + 1;
      while (e < n && sorted[e].p == sorted[j].p) ++e;
      for (std::size_t q = j; q < e; ++q) first[sorted[q].i] = sorted[j].i;
      j = e;
    }
    sorted = std::vector<Entry>();
    unique.reserve(groups);
    first_of.reserve(groups);
    for (std::size_t i = 0; i < n; ++i) {
      if (first[i] != i) {
        unique_of[i] = unique_of[first[i]];
        continue;
      }
      unique_of[i] = static_cast<std::uint32_t>(unique.size());
      const Point3 k = key(i);
      unique.emplace_back(k.x(), k.y(), k.z());
      first_of.push_back(static_cast<std::uint32_t>(i));
    }
  }
  if (unique.size() < static_cast<std::size_t>(kMinNeighbours))
    throw InvalidInput("estimate_normals: " + std::to_string(unique.size()) +
                       " distinct positions; jet fitting needs at least " +
                       std::to_string(kMinNeighbours));
  const unsigned k_used =
      static_cast<unsigned>(std::min<std::size_t>(static_cast<std::size_t>(k), unique.size()));

  // Orientation references from the faces: per point, the sum of its faces' area-weighted
  // normals, each times the sign of the face's area in uv when there is uv. For a triangle,
  // (p1 - p0) x (p2 - p0) = det(uv1 - uv0, uv2 - uv0) P_u x P_v, so the signed sum points like
  // P_u x P_v of the faces' affine maps.
  std::vector<Vector3> face_ref;
  if (!triangles.empty()) {
    face_ref.assign(n, Vector3::Zero());
    for (const auto& t : triangles) {
      Vector3 fn = (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
      if (!uv.empty()) {
        const Vector2 a = uv[t[1]] - uv[t[0]], b = uv[t[2]] - uv[t[0]];
        const double det = a.x() * b.y() - a.y() * b.x();
        if (det == 0) continue;
        if (det < 0) fn = -fn;
      }
      for (int c = 0; c < 3; ++c) face_ref[t[c]] += fn;
    }
  }
  const Vector3 up = pca_up(positions);

  const IndexPointMap point_map{&unique};
  Tree tree(boost::counting_iterator<std::uint32_t>(0),
            boost::counting_iterator<std::uint32_t>(static_cast<std::uint32_t>(unique.size())),
            Tree::Splitter(), TreeTraits(point_map));
  // Built before the parallel queries (it builds lazily otherwise); the parallel build makes
  // the same splits as the serial one, only the two halves of a split in parallel.
  tree.build<CGAL::Parallel_tag>();
  const Distance distance(point_map);

  // The copies of each unique position, in point order (compressed rows).
  std::vector<std::uint32_t> copy_start(unique.size() + 1, 0), copies(n);
  for (std::size_t i = 0; i < n; ++i) ++copy_start[unique_of[i] + 1];
  for (std::size_t u = 0; u < unique.size(); ++u) copy_start[u + 1] += copy_start[u];
  {
    std::vector<std::uint32_t> next(copy_start.begin(), copy_start.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
      copies[next[unique_of[i]]++] = static_cast<std::uint32_t>(i);
  }

  // The order of the queries: along a Hilbert curve through the points. Scans often come in
  // random order (merged views, resampled clouds), and searches from random places miss the
  // cache at every tree node and point.
  std::vector<std::uint32_t> order(unique.size());
  for (std::size_t u = 0; u < unique.size(); ++u) order[u] = static_cast<std::uint32_t>(u);
  // CGAL's median-policy Hilbert sort, its halves sorted in parallel, called directly:
  // CGAL::hilbert_sort would first shuffle the range at random, serially (the order only
  // makes the searches faster; it changes no normal).
  CGAL::Hilbert_sort_median_3<CGAL::Spatial_sort_traits_adapter_3<Kernel, IndexPointMap>, CGAL::Parallel_tag>(
      CGAL::Spatial_sort_traits_adapter_3<Kernel, IndexPointMap>(point_map))(order.begin(), order.end());

  // A point's normal depends only on its own neighbourhood, so neither the order of the points
  // nor the parallel loop changes it: the result is the same for any number of threads.
  std::vector<Vector3> normals(n);
  std::vector<char> degenerate(unique.size(), 0);
  // Progress: blocks done, reported by the calling thread (which works in the loop too).
  using Clock = std::chrono::steady_clock;
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<std::size_t> done{0};
  Clock::time_point last_report = Clock::now();
  const auto estimate = [&](const tbb::blocked_range<std::size_t>& range) {
    if (progress) {
      const std::size_t now_done = done.fetch_add(range.size()) + range.size();
      if (std::this_thread::get_id() == caller && Clock::now() - last_report > std::chrono::seconds(2)) {
        last_report = Clock::now();
        progress(static_cast<double>(now_done) / static_cast<double>(unique.size()));
      }
    }
    std::vector<CPoint> pts;
    std::vector<std::uint32_t> ids;
    JetFit fit;
    for (std::size_t j = range.begin(); j != range.end(); ++j) {
      const std::uint32_t u = order[j];
      const Search search(tree, unique[u], k_used, 0.0, true, distance);
      pts.clear();
      ids.clear();
      for (const auto& [id, d2] : search) {
        ids.push_back(id);
        pts.push_back(unique[id]);
      }
      const auto p3 = [&](std::uint32_t id) {
        return Point3(unique[id].x(), unique[id].y(), unique[id].z());
      };
      Point3 mean = Point3::Zero();
      for (std::uint32_t id : ids) mean += p3(id);
      mean /= static_cast<double>(ids.size());
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (std::uint32_t id : ids) cov += (p3(id) - mean) * (p3(id) - mean).transpose();
      const Eigen::Vector3d ev =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov, Eigen::EigenvaluesOnly).eigenvalues();
      if (!(ev[1] > kDegenerateRatio * ev[2])) {
        degenerate[u] = 1;
        continue;
      }
      const Kernel::Vector_3 jet = fit(pts.begin(), pts.end(), kJetDegree, 1).normal_direction();
      Vector3 normal(jet.x(), jet.y(), jet.z());
      const double len = normal.norm();
      if (!(len > 0) || !std::isfinite(len)) {
        degenerate[u] = 1;
        continue;
      }
      normal /= len;

      for (std::uint32_t c = copy_start[u]; c < copy_start[u + 1]; ++c) {
        const std::uint32_t i = copies[c];
        Vector3 ref = face_ref.empty() ? Vector3::Zero() : face_ref[i];
        if (ref.dot(normal) == 0 && !uv.empty()) {
          // Least-squares affine fit P ~ P0 + [P_u P_v] (uv - uv0) over the neighbours: with
          // B = sum dp duv^T and M = sum duv duv^T, [P_u P_v] = B M^-1 and P_u x P_v =
          // (B e1 x B e2) / det M with det M > 0, so n . (B e1 x B e2) has the sign we need.
          // A neighbour stands for its first copy; the point itself uses its own uv.
          const auto param = [&](std::uint32_t id) { return id == u ? uv[i] : uv[first_of[id]]; };
          Point2 um = Point2::Zero();
          for (std::uint32_t id : ids) um += param(id);
          um /= static_cast<double>(ids.size());
          Vector3 bu = Vector3::Zero(), bv = Vector3::Zero();
          for (std::uint32_t id : ids) {
            const Vector3 dp = p3(id) - mean;
            const Vector2 du = param(id) - um;
            bu += dp * du.x();
            bv += dp * du.y();
          }
          ref = bu.cross(bv);
        }
        if (ref.dot(normal) == 0) ref = up;
        normals[i] = ref.dot(normal) < 0 ? Vector3(-normal) : normal;
      }
    }
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, unique.size(), 256), estimate);
  for (std::size_t u = 0; u < unique.size(); ++u)
    if (degenerate[u])
      throw InvalidInput("estimate_normals: the " + std::to_string(k_used) +
                         " nearest neighbours of point " + std::to_string(first_of[u]) +
                         " are collinear or coincide, so they give no normal; remove stray "
                         "points or use a larger k");
  return normals;
}

}  // namespace tbs
