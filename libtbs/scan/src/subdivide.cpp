// The guide subdivision (subdivide, scan_mesh.h): one 1-to-4 split of the flattened mesh with
// the new vertices on a smooth surface through the old ones (PN triangles), for meshes whose
// vertices alone are too few to fit.

#include "scan_mesh.h"

#include <cmath>
#include <unordered_map>

namespace tbs::detail {

namespace {

// Unit normal of each face corner: the area-weighted mean of the normals of the faces around
// the vertex that turn by less than `sharp_deg` from this face (so creases stay creases).
std::vector<std::array<Vector3, 3>> corner_normals(const Mesh3& m, double sharp_deg) {
  std::vector<Vector3> fn(m.faces.size());
  std::vector<std::vector<int>> around(m.points.size());
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const Tri& t = m.faces[f];
    fn[f] = (m.points[t[1]] - m.points[t[0]]).cross(m.points[t[2]] - m.points[t[0]]);  // |.| = 2 area
    for (int v : t) around[v].push_back(int(f));
  }
  const double cos_sharp = std::cos(sharp_deg * M_PI / 180);
  std::vector<std::array<Vector3, 3>> out(m.faces.size());
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const Vector3 nf = fn[f].normalized();
    for (int k = 0; k < 3; ++k) {
      Vector3 sum = Vector3::Zero();
      for (int g : around[m.faces[f][k]])
        if (fn[g].normalized().dot(nf) >= cos_sharp) sum += fn[g];
      out[f][k] = sum.norm() > 0 ? Vector3(sum.normalized()) : nf;
    }
  }
  return out;
}

}  // namespace

// One 1-to-4 subdivision with new vertices on a smooth surface through the old ones: the
// midpoint of each edge's cubic curve of the PN triangle (Vlachos et al. 2001) built from the
// end points and their corner normals. Where the two faces of an edge disagree on a normal (a
// crease) the edge stays straight. Parameters are the midpoints in (u, v). `origin` maps each
// vertex to an original vertex (for normals).
void subdivide(Mesh3& m, std::vector<P2>& uv, std::vector<int>& origin, double sharp_deg) {
  const auto normals = corner_normals(m, sharp_deg);
  struct Mid {
    int vertex;
    Vector3 na, nb;  // the corner normals of the face that made it
  };
  std::unordered_map<uint64_t, Mid> mid;
  auto curve_mid = [&](int a, int b, const Vector3& na, const Vector3& nb) {
    const Point3 &pa = m.points[a], &pb = m.points[b];
    const Point3 b1 = (2 * pa + pb - (pb - pa).dot(na) * na) / 3;
    const Point3 b2 = (2 * pb + pa - (pa - pb).dot(nb) * nb) / 3;
    return Point3((pa + 3 * b1 + 3 * b2 + pb) / 8);
  };
  std::vector<Tri> faces;
  faces.reserve(4 * m.faces.size());
  const size_t old_count = m.points.size();
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const Tri& t = m.faces[f];
    int e[3];
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const Vector3 &na = normals[f][k], &nb = normals[f][(k + 1) % 3];
      auto it = mid.find(edge_key(a, b));
      if (it == mid.end()) {
        const int v = static_cast<int>(m.points.size());
        m.points.push_back(curve_mid(a, b, na, nb));
        uv.push_back(CGAL::midpoint(uv[a], uv[b]));
        origin.push_back(origin[std::min(a, b)]);
        // Keyed by (min, max): store the normals in that order.
        it = mid.emplace(edge_key(a, b), a < b ? Mid{v, na, nb} : Mid{v, nb, na}).first;
      } else {
        // The second face of the edge: if it sees other normals, the edge is a crease.
        const Vector3 &ma = a < b ? na : nb, &mb = a < b ? nb : na;
        if (ma.dot(it->second.na) < 1 - 1e-12 || mb.dot(it->second.nb) < 1 - 1e-12)
          m.points[it->second.vertex] = 0.5 * (m.points[a] + m.points[b]);
      }
      e[k] = it->second.vertex;
    }
    faces.push_back({t[0], e[0], e[2]});
    faces.push_back({e[0], t[1], e[1]});
    faces.push_back({e[2], e[1], t[2]});
    faces.push_back({e[0], e[1], e[2]});
  }
  (void)old_count;
  m.faces = std::move(faces);
}

}  // namespace tbs::detail
