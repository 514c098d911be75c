// The sharp features inside the fit region: chains of mesh edges whose dihedral angle exceeds
// the feature angle, and creases of bare points found as narrow bands of turning normals.

#include "fit_region.h"

#include <Eigen/Eigenvalues>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <numeric>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace tbs::detail {

// Sharp edges of the region (dihedral angle of the 3D triangles above the threshold), chained
// into polylines of point indices.
std::vector<std::vector<int>> feature_chains(const Region& r, const Adjacency& adj, std::span<const Point3> pos,
                                             double angle_deg) {
  std::vector<Vector3> fn(r.tris.size());
  for (size_t f = 0; f < r.tris.size(); ++f) {
    const auto& t = r.tris[f];
    const Vector3 n = (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]);
    fn[f] = n.norm() > 0 ? Vector3(n.normalized()) : Vector3::Zero();
  }
  const double cos_limit = std::cos(angle_deg * std::numbers::pi / 180);
  std::map<int, std::vector<int>> nbr;  // ordered: deterministic chaining
  std::vector<std::pair<int, int>> sharp;
  for (size_t f = 0; f < r.tris.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int g = adj.across[f][k];
      if (g < static_cast<int>(f)) continue;  // the outline, or seen from g
      if (fn[f].isZero() || fn[g].isZero()) continue;
      if (fn[f].dot(fn[g]) >= cos_limit) continue;
      const int a = r.tris[f][k], b = r.tris[f][(k + 1) % 3];
      sharp.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(sharp.begin(), sharp.end());
  for (auto [a, b] : sharp) nbr[a].push_back(b), nbr[b].push_back(a);
  for (auto& [v, list] : nbr) std::sort(list.begin(), list.end());
  std::unordered_set<uint64_t> used;
  std::vector<std::vector<int>> chains;
  auto walk = [&](int start, int first) {
    std::vector<int> chain{start};
    int p = start, q = first;
    while (!used.count(edge_key(p, q))) {
      used.insert(edge_key(p, q));
      chain.push_back(q);
      const auto& nq = nbr[q];
      if (nq.size() != 2) break;
      const int nx = nq[0] == p ? nq[1] : nq[0];
      p = q;
      q = nx;
    }
    if (chain.size() >= 2) chains.push_back(std::move(chain));
  };
  for (const auto& [v, list] : nbr)
    if (list.size() != 2)
      for (int w : list) walk(v, w);
  for (const auto& [v, list] : nbr)
    for (int w : list) walk(v, w);  // closed loops
  return chains;
}

// Creases that no edge follows (bare points, or meshes whose edges cross the crease): the
// triangles straddling a crease share its angle between several edges, none of them sharp. A
// band of edges bent by more than a third of the feature angle, long and thin, whose two sides
// have normals more than the feature angle apart, is a crease; its centre line (centroids of
// the band's triangles, averaged in bins along the band's main axis) goes into the domain.
std::vector<std::vector<Point2>> band_creases(const Region& r, const Adjacency& adj, std::span<const Point2> uv,
                                              std::span<const Point3> pos, double angle_deg,
                                              double h, const std::unordered_set<uint64_t>& taken) {
  const size_t F = r.tris.size();
  std::vector<Vector3> fn(F);
  std::vector<Point2> centroid(F);
  tbb::parallel_for(size_t{0}, F, [&](size_t f) {
    const auto& t = r.tris[f];
    const Vector3 nrm = (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]);
    fn[f] = nrm.norm() > 0 ? Vector3(nrm.normalized()) : Vector3::Zero();
    centroid[f] = (uv[t[0]] + uv[t[1]] + uv[t[2]]) / 3.0;
  });
  const double cos_band = std::cos(angle_deg / 3 * std::numbers::pi / 180);
  const double cos_crease = std::cos(angle_deg * std::numbers::pi / 180);
  // Triangles at the region's outline are stretched and tilted (alpha shape): not crease clues.
  std::vector<char> rim(uv.size(), 0);
  for (size_t f = 0; f < F; ++f)
    for (int k = 0; k < 3; ++k)
      if (adj.across[f][k] < 0) rim[r.tris[f][k]] = rim[r.tris[f][(k + 1) % 3]] = 1;
  auto at_rim = [&](int f) {
    for (int v : r.tris[f])
      if (rim[v]) return true;
    return false;
  };
  // Whether the edge k of f, to its neighbour g, bends by more than the band angle.
  auto bent = [&](size_t f, int k, int g) {
    if (taken.count(edge_key(r.tris[f][k], r.tris[f][(k + 1) % 3])) || fn[f].isZero() || fn[g].isZero()) return false;
    if (at_rim(static_cast<int>(f)) || at_rim(g)) return false;
    return fn[f].dot(fn[g]) < cos_band;
  };
  std::vector<char> band(F, 0);
  if (adj.duplicate.face < 0) {
    // Every edge has at most two triangles, each the other's neighbour: each triangle looks at
    // its own edges, in parallel.
    tbb::parallel_for(size_t{0}, F, [&](size_t f) {
      for (int k = 0; k < 3; ++k)
        if (const int g = adj.across[f][k]; g >= 0 && bent(f, k, g)) band[f] = 1;
    });
  } else {
    for (size_t f = 0; f < F; ++f)
      for (int k = 0; k < 3; ++k)
        if (const int g = adj.across[f][k]; g > static_cast<int>(f) && bent(f, k, g)) band[f] = band[g] = 1;
  }
  // Components of band triangles, each listed by index, ordered by their first triangle.
  // Band triangles sharing a vertex are neighbours (a crease passing near a vertex leaves
  // gaps between edge-adjacent ones). Union-find: at a million noisy points most triangles
  // are band triangles.
  std::vector<int> parent(F);
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int f) {
    while (parent[f] != f) f = parent[f] = parent[parent[f]];
    return f;
  };
  for (size_t v = 0; v < uv.size(); ++v) {
    int last = -1;
    for (int f : adj.star_of(static_cast<int>(v))) {
      if (!band[f]) continue;
      if (last >= 0) {
        const int a = root(last), b = root(f);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
      last = f;
    }
  }
  std::vector<int> comp_of(F, -1);
  std::vector<std::vector<int>> comps;
  for (size_t f = 0; f < F; ++f) {
    if (!band[f]) continue;
    int& c = comp_of[root(static_cast<int>(f))];
    if (c < 0) c = static_cast<int>(comps.size()), comps.emplace_back();
    comps[c].push_back(static_cast<int>(f));
  }
  std::vector<std::vector<Point2>> lines;
  for (const auto& c : comps) {
    if (c.size() < 8) continue;
    Point2 mean = Point2::Zero();
    for (int f : c) mean += centroid[f];
    mean /= static_cast<double>(c.size());
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (int f : c) cov += (centroid[f] - mean) * (centroid[f] - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
    const Vector2 axis = es.eigenvectors().col(1), side(-axis.y(), axis.x());
    double tmin = 1e300, tmax = -1e300, wmax = 0;
    for (int f : c) {
      const double t = (centroid[f] - mean).dot(axis);
      tmin = std::min(tmin, t), tmax = std::max(tmax, t);
      wmax = std::max(wmax, std::fabs((centroid[f] - mean).dot(side)));
    }
    const double length = tmax - tmin;
    if (length < 2 * h || 2 * wmax > 0.25 * length) continue;
    // The two sides: non-band triangles next to the band.
    Vector3 nl = Vector3::Zero(), nr = Vector3::Zero();
    size_t cl = 0, cr = 0;
    for (int f : c)
      for (int k = 0; k < 3; ++k) {
        const int g = adj.across[f][k];
        if (g < 0 || band[g]) continue;
        if ((centroid[g] - mean).dot(side) < 0)
          nl += fn[g], ++cl;
        else
          nr += fn[g], ++cr;
      }
    // Both sides must be well represented, and bent against each other by the feature angle.
    const size_t need = std::max<size_t>(3, c.size() / 8);
    if (cl < need || cr < need || nl.normalized().dot(nr.normalized()) >= cos_crease) continue;
    // Centre line: centroids averaged in bins of h / 2 along the axis.
    const int bins = std::max(3, static_cast<int>(std::ceil(length / (0.5 * h))));
    std::vector<Point2> sum(bins, Point2::Zero());
    std::vector<int> count(bins, 0);
    for (int f : c) {
      const double t = (centroid[f] - mean).dot(axis);
      const int b = std::min(bins - 1, static_cast<int>((t - tmin) / length * bins));
      sum[b] += centroid[f];
      ++count[b];
    }
    std::vector<Point2> line;
    for (int b = 0; b < bins; ++b)
      if (count[b] > 0) line.push_back(sum[b] / count[b]);
    if (line.size() >= 2) lines.push_back(std::move(line));
  }
  return lines;
}

}  // namespace tbs::detail
