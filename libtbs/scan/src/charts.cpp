// The atlas of a mesh (cut_into_charts, scan_mesh.h): a surface that no single flattening
// carries well (closed, with handles, or stretched) is cut into charts, each a disk possibly
// with holes that flattens with little stretch: first along its sharp edges (a CAD part's
// faces), then across its handles (tree-cotree), then between boundary loops of a tube, and in
// two wherever a chart is still closed or its flattening stretches. The charts are flattened
// one by one, laid side by side in the plane, and every cut edge becomes a piece of a seam.

#include <tbs/errors.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <queue>
#include <unordered_map>

#include "scan_mesh.h"

namespace tbs::detail {

namespace {

// Regions of the sharp-edge segmentation smaller than kMinRegionArea of the surface's area, or
// of fewer than kMinRegionFaces faces and smaller than kSmallRegionArea, are noise of the edge
// test (or of the scan), not faces of the object: they join the neighbour they share the
// longest border with. A coarse CAD mesh's faces (a cube's two triangles a side) stay.
constexpr size_t kMinRegionFaces = 20;
constexpr double kMinRegionArea = 1e-3;
constexpr double kSmallRegionArea = 1e-2;
// A chart of fewer faces is flattened as it is and not cut further.
constexpr size_t kMinChartFaces = 12;
// Bounds on the work: charts and cutting rounds.
constexpr int kMaxCharts = 256;
constexpr int kMaxRounds = 64;

constexpr double kPi = 3.14159265358979323846;
// A chart whose normals all lie within this many degrees of each other is split by distance
// along its edges, not by its normals; rounds of the split by normals.
constexpr double kFlatTurn = 20;
constexpr int kSplitRounds = 4;
constexpr int kSmoothPasses = 8;
constexpr int kNormalSmoothing = 6;
// A chart whose normals turn by more than this many degrees is split by its normals before a
// tube in it is cut open: its bends are where CAD faces meet.
constexpr double kBentChart = 100;

double face_area(const Mesh3& m, const Tri& t) {
  return 0.5 * (m.points[t[1]] - m.points[t[0]]).cross(m.points[t[2]] - m.points[t[0]]).norm();
}

Vector3 face_normal(const Mesh3& m, const Tri& t) {
  const Vector3 n = (m.points[t[1]] - m.points[t[0]]).cross(m.points[t[2]] - m.points[t[0]]);
  const double l = n.norm();
  return l > 0 ? Vector3(n / l) : Vector3::Zero();
}

// Half-edges of an oriented manifold mesh: h = 3 f + k runs from corner k of face f to corner
// k + 1; twin[h] is the opposite half-edge or -1 on the boundary; edge[h] numbers the
// undirected edges.
struct HalfEdges {
  std::vector<int> twin, edge;
  int edges = 0;
};

HalfEdges half_edges(const Mesh3& m) {
  HalfEdges he;
  const size_t H = 3 * m.faces.size();
  he.twin.assign(H, -1);
  he.edge.assign(H, -1);
  std::unordered_map<uint64_t, int> at;
  at.reserve(H);
  for (size_t f = 0; f < m.faces.size(); ++f)
    for (int k = 0; k < 3; ++k)
      at[directed_key(m.faces[f][k], m.faces[f][(k + 1) % 3])] = static_cast<int>(3 * f + k);
  for (size_t h = 0; h < H; ++h) {
    if (he.edge[h] >= 0) continue;
    const Tri& t = m.faces[h / 3];
    const int a = t[h % 3], b = t[(h % 3 + 1) % 3];
    const auto it = at.find(directed_key(b, a));
    he.edge[h] = he.edges;
    if (it != at.end()) {
      he.twin[h] = it->second;
      he.twin[static_cast<size_t>(it->second)] = static_cast<int>(h);
      he.edge[static_cast<size_t>(it->second)] = he.edges;
    }
    ++he.edges;
  }
  return he;
}

// A chart's topology and its parts.
struct ChartInfo {
  std::vector<int> faces;   // ascending
  std::vector<int> copies;  // the vertex copies it uses, ascending
  int loops = 0;            // boundary loops
  int genus = 0;
  bool closed() const { return loops == 0; }
};

class Cutter {
 public:
  Cutter(const Mesh3& m, double sharp_deg) : m_(m), he_(half_edges(m)) {
    F_ = static_cast<int>(m.faces.size());
    cut_.assign(static_cast<size_t>(he_.edges), 0);
    label_.assign(static_cast<size_t>(F_), 0);
    sharp_.assign(static_cast<size_t>(he_.edges), 0);
    length_.assign(static_cast<size_t>(he_.edges), 0.0);
    const double cos_sharp = std::cos(sharp_deg * kPi / 180);
    for (int h = 0; h < 3 * F_; ++h) {
      const int g = he_.twin[static_cast<size_t>(h)];
      const Tri& t = m.faces[static_cast<size_t>(h / 3)];
      length_[static_cast<size_t>(he_.edge[static_cast<size_t>(h)])] =
          (m.points[t[(h % 3 + 1) % 3]] - m.points[t[h % 3]]).norm();
      if (g < h) continue;
      const Vector3 n1 = face_normal(m, t),
                    n2 = face_normal(m, m.faces[static_cast<size_t>(g / 3)]);
      sharp_[static_cast<size_t>(he_.edge[static_cast<size_t>(h)])] = n1.dot(n2) < cos_sharp;
    }
  }

  const Mesh3& mesh() const { return m_; }
  const HalfEdges& he() const { return he_; }
  int face_count() const { return F_; }
  bool sharp_edge(int e) const { return sharp_[static_cast<size_t>(e)] != 0; }
  int vertex_of_corner(int c) const { return m_.faces[static_cast<size_t>(c / 3)][c % 3]; }
  int copy_of_corner(int c) const { return copy_[static_cast<size_t>(c)]; }
  int copies() const { return copies_; }
  int chart_of_face(int f) const { return chart_[static_cast<size_t>(f)]; }
  int charts() const { return charts_; }
  int edges_cut() const {
    int n = 0;
    for (int h = 0; h < 3 * F_; ++h) n += he_.twin[static_cast<size_t>(h)] > h && separated(h);
    return n;
  }

  // Whether the two faces of half-edge h lie apart (a chart boundary): a mesh boundary, a cut
  // edge, or an edge between two labels.
  bool separated(int h) const {
    const int g = he_.twin[static_cast<size_t>(h)];
    return g < 0 || cut_[static_cast<size_t>(he_.edge[static_cast<size_t>(h)])] ||
           label_[static_cast<size_t>(h / 3)] != label_[static_cast<size_t>(g / 3)];
  }

  // Faces into regions bounded by sharp edges; small regions join a neighbour.
  void segment_by_sharp_edges(double total_area) {
    UnionFind uf(static_cast<size_t>(F_));
    for (int h = 0; h < 3 * F_; ++h) {
      const int g = he_.twin[static_cast<size_t>(h)];
      if (g > h && !sharp_[static_cast<size_t>(he_.edge[static_cast<size_t>(h)])])
        uf.join(h / 3, g / 3);
    }
    for (int f = 0; f < F_; ++f) label_[static_cast<size_t>(f)] = uf.find(f);
    // Merge the small regions, smallest first, into the neighbour with the longest border.
    for (int round = 0; round < 8; ++round) {
      std::map<int, std::pair<size_t, double>> size;  // label -> faces, area
      for (int f = 0; f < F_; ++f) {
        auto& s = size[label_[static_cast<size_t>(f)]];
        ++s.first;
        s.second += face_area(m_, m_.faces[static_cast<size_t>(f)]);
      }
      std::vector<std::pair<size_t, int>> small;
      for (const auto& [l, s] : size)
        if (s.second < kMinRegionArea * total_area ||
            (s.first < kMinRegionFaces && s.second < kSmallRegionArea * total_area))
          small.push_back({s.first, l});
      if (small.empty() || size.size() == 1) break;
      std::sort(small.begin(), small.end());
      std::map<int, int> into;
      for (const auto& [count, l] : small) {
        (void)count;
        std::map<int, double> border;
        for (int h = 0; h < 3 * F_; ++h) {
          const int g = he_.twin[static_cast<size_t>(h)];
          if (g < 0 || label_[static_cast<size_t>(h / 3)] != l) continue;
          const int other = label_[static_cast<size_t>(g / 3)];
          if (other != l && !into.count(other))
            border[other] += length_[static_cast<size_t>(he_.edge[static_cast<size_t>(h)])];
        }
        if (border.empty()) continue;
        int best = border.begin()->first;
        for (const auto& [o, len] : border)
          if (len > border[best]) best = o;
        into[l] = best;
      }
      if (into.empty()) break;
      for (int f = 0; f < F_; ++f) {
        auto it = into.find(label_[static_cast<size_t>(f)]);
        if (it != into.end()) label_[static_cast<size_t>(f)] = it->second;
      }
    }
  }

  // Vertex copies (one per fan of faces that no chart boundary separates) and charts (faces
  // joined across edges that are not chart boundaries), from the labels and cut edges.
  void rebuild() {
    UnionFind corners(static_cast<size_t>(3 * F_)), faces(static_cast<size_t>(F_));
    for (int f = 0; f < F_; ++f) {
      // Corners of one vertex in one face are one corner already.
      (void)f;
    }
    for (int h = 0; h < 3 * F_; ++h) {
      const int g = he_.twin[static_cast<size_t>(h)];
      if (g < h || separated(h)) continue;
      faces.join(h / 3, g / 3);
      // h runs a -> b in its face, g runs b -> a: a is corner h of one and corner next(g) of
      // the other.
      corners.join(h, 3 * (g / 3) + (g % 3 + 1) % 3);
      corners.join(3 * (h / 3) + (h % 3 + 1) % 3, g);
    }
    // Corners of one vertex in faces of one fan are joined through their shared edges above;
    // number the classes in corner order.
    copy_.assign(static_cast<size_t>(3 * F_), -1);
    std::vector<int> number(static_cast<size_t>(3 * F_), -1);
    copies_ = 0;
    copy_vertex_.clear();
    for (int c = 0; c < 3 * F_; ++c) {
      const int r = corners.find(c);
      if (number[static_cast<size_t>(r)] < 0) {
        number[static_cast<size_t>(r)] = copies_++;
        copy_vertex_.push_back(vertex_of_corner(c));
      }
      copy_[static_cast<size_t>(c)] = number[static_cast<size_t>(r)];
    }
    chart_.assign(static_cast<size_t>(F_), -1);
    std::vector<int> fnumber(static_cast<size_t>(F_), -1);
    charts_ = 0;
    for (int f = 0; f < F_; ++f) {
      const int r = faces.find(f);
      if (fnumber[static_cast<size_t>(r)] < 0) fnumber[static_cast<size_t>(r)] = charts_++;
      chart_[static_cast<size_t>(f)] = fnumber[static_cast<size_t>(r)];
    }
  }

  int copy_vertex(int c) const { return copy_vertex_[static_cast<size_t>(c)]; }

  std::vector<ChartInfo> chart_infos() const {
    std::vector<ChartInfo> info(static_cast<size_t>(charts_));
    for (int f = 0; f < F_; ++f)
      info[static_cast<size_t>(chart_[static_cast<size_t>(f)])].faces.push_back(f);
    std::vector<int> chart_of_copy(static_cast<size_t>(copies_), -1);
    for (int c = 0; c < 3 * F_; ++c)
      chart_of_copy[static_cast<size_t>(copy_[static_cast<size_t>(c)])] =
          chart_[static_cast<size_t>(c / 3)];
    for (int v = 0; v < copies_; ++v)
      info[static_cast<size_t>(chart_of_copy[static_cast<size_t>(v)])].copies.push_back(v);
    std::vector<long> edges(static_cast<size_t>(charts_), 0);
    UnionFind loops(static_cast<size_t>(copies_));
    std::vector<char> on_boundary(static_cast<size_t>(copies_), 0);
    for (int h = 0; h < 3 * F_; ++h) {
      const int g = he_.twin[static_cast<size_t>(h)];
      const int ch = chart_[static_cast<size_t>(h / 3)];
      if (separated(h)) {
        ++edges[static_cast<size_t>(ch)];
        const int a = copy_[static_cast<size_t>(h)],
                  b = copy_[static_cast<size_t>(3 * (h / 3) + (h % 3 + 1) % 3)];
        loops.join(a, b);
        on_boundary[static_cast<size_t>(a)] = on_boundary[static_cast<size_t>(b)] = 1;
      } else if (g > h) {
        ++edges[static_cast<size_t>(ch)];
      }
    }
    std::vector<int> loop_count(static_cast<size_t>(charts_), 0);
    for (int v = 0; v < copies_; ++v)
      if (on_boundary[static_cast<size_t>(v)] && loops.find(v) == v)
        ++loop_count[static_cast<size_t>(chart_of_copy[static_cast<size_t>(v)])];
    for (int c = 0; c < charts_; ++c) {
      ChartInfo& i = info[static_cast<size_t>(c)];
      i.loops = loop_count[static_cast<size_t>(c)];
      const long chi = static_cast<long>(i.copies.size()) - edges[static_cast<size_t>(c)] +
                       static_cast<long>(i.faces.size());
      i.genus = static_cast<int>((2 - chi - i.loops) / 2);
    }
    return info;
  }

  // The chart as a mesh of its own: local vertices (its copies, ascending) and its faces in
  // order. `local` receives the local index of each copy (-1 elsewhere).
  Mesh3 chart_mesh(const ChartInfo& c, std::vector<int>& local) const {
    Mesh3 out;
    local.assign(static_cast<size_t>(copies_), -1);
    for (int v : c.copies) {
      local[static_cast<size_t>(v)] = static_cast<int>(out.points.size());
      out.points.push_back(m_.points[static_cast<size_t>(copy_vertex_[static_cast<size_t>(v)])]);
    }
    for (int f : c.faces)
      out.faces.push_back({local[static_cast<size_t>(copy_[static_cast<size_t>(3 * f)])],
                           local[static_cast<size_t>(copy_[static_cast<size_t>(3 * f + 1)])],
                           local[static_cast<size_t>(copy_[static_cast<size_t>(3 * f + 2)])]});
    return out;
  }

  // The edges inside a chart, between its copies: (copy a, copy b, half-edge).
  struct InnerEdge {
    int a, b, h;
  };
  std::vector<InnerEdge> inner_edges(const ChartInfo& c) const {
    std::vector<InnerEdge> out;
    for (int f : c.faces)
      for (int k = 0; k < 3; ++k) {
        const int h = 3 * f + k, g = he_.twin[static_cast<size_t>(h)];
        if (g > h && !separated(h))
          out.push_back(
              {copy_[static_cast<size_t>(h)], copy_[static_cast<size_t>(3 * f + (k + 1) % 3)], h});
      }
    return out;
  }

  double edge_length(int h) const {
    return length_[static_cast<size_t>(he_.edge[static_cast<size_t>(h)])];
  }

  // Shortest-path distances over the chart's inner edges from the sources (multi-source).
  std::vector<double> distances(const ChartInfo& c, const std::vector<int>& sources,
                                std::vector<int>* pred_edge = nullptr,
                                const std::vector<InnerEdge>* edges_in = nullptr) const {
    std::vector<InnerEdge> own;
    const std::vector<InnerEdge>& edges = edges_in ? *edges_in : (own = inner_edges(c));
    std::vector<std::vector<std::pair<int, int>>> adj(
        static_cast<size_t>(copies_));  // (other copy, edge index)
    for (size_t e = 0; e < edges.size(); ++e) {
      adj[static_cast<size_t>(edges[e].a)].push_back({edges[e].b, static_cast<int>(e)});
      adj[static_cast<size_t>(edges[e].b)].push_back({edges[e].a, static_cast<int>(e)});
    }
    std::vector<double> d(static_cast<size_t>(copies_), std::numeric_limits<double>::infinity());
    if (pred_edge) pred_edge->assign(static_cast<size_t>(copies_), -1);
    using Q = std::pair<double, int>;
    std::priority_queue<Q, std::vector<Q>, std::greater<>> q;
    for (int s : sources) d[static_cast<size_t>(s)] = 0, q.push({0.0, s});
    while (!q.empty()) {
      const auto [dist, v] = q.top();
      q.pop();
      if (dist > d[static_cast<size_t>(v)]) continue;
      for (const auto& [w, e] : adj[static_cast<size_t>(v)]) {
        const double nd = dist + edge_length(edges[static_cast<size_t>(e)].h);
        if (nd < d[static_cast<size_t>(w)]) {
          d[static_cast<size_t>(w)] = nd;
          if (pred_edge) (*pred_edge)[static_cast<size_t>(w)] = e;
          q.push({nd, w});
        }
      }
    }
    return d;
  }

  // Splits a chart in two where its normals turn most: two regions grown from two seed faces
  // over the chart's inner edges, each face going to the region whose mean normal it is nearer,
  // cheapest first (variational shape approximation with two proxies, Cohen-Steiner et al.
  // 2004, a few rounds). A region of a CAD part that stretches in one flattening (a face and a
  // fillet or a hole around a corner) comes apart at its bends. Where the normals hardly turn,
  // or the proxies would leave one side empty, the faces nearer (along the edges) to one of
  // two far apart vertices than to the other go. False if one side would still be empty.
  bool split_in_two(const ChartInfo& c, int new_label) {
    if (c.faces.size() < 2) return false;
    if (split_by_normals(c, new_label)) return true;
    if (c.copies.size() < 3) return false;
    const auto edges = inner_edges(c);
    auto farthest = [&](const std::vector<double>& d) {
      int best = c.copies.front();
      for (int v : c.copies)
        if (std::isfinite(d[static_cast<size_t>(v)]) &&
            d[static_cast<size_t>(v)] > d[static_cast<size_t>(best)])
          best = v;
      return best;
    };
    const int s1 = farthest(distances(c, {c.copies.front()}, nullptr, &edges));
    const std::vector<double> d1 = distances(c, {s1}, nullptr, &edges);
    const int s2 = farthest(d1);
    if (s2 == s1) return false;
    const std::vector<double> d2 = distances(c, {s2}, nullptr, &edges);
    const size_t F = c.faces.size();
    std::vector<int> side(F, 0);
    for (size_t i = 0; i < F; ++i) {
      double a = 0, b = 0;
      for (int k = 0; k < 3; ++k) {
        a += d1[static_cast<size_t>(copy_[static_cast<size_t>(3 * c.faces[i] + k)])];
        b += d2[static_cast<size_t>(copy_[static_cast<size_t>(3 * c.faces[i] + k)])];
      }
      side[i] = b < a;
    }
    return apply_split(c, neighbours(c), side, new_label);
  }

  // Each face's neighbours across the chart's inner edges, as positions in c.faces (-1 none).
  std::vector<std::array<int, 3>> neighbours(const ChartInfo& c) const {
    const size_t F = c.faces.size();
    std::unordered_map<int, size_t> local;
    for (size_t i = 0; i < F; ++i) local[c.faces[i]] = i;
    std::vector<std::array<int, 3>> next(F, {-1, -1, -1});
    for (size_t i = 0; i < F; ++i)
      for (int k = 0; k < 3; ++k) {
        const int h = 3 * c.faces[i] + k;
        if (!separated(h))
          next[i][static_cast<size_t>(k)] =
              static_cast<int>(local.at(he_.twin[static_cast<size_t>(h)] / 3));
      }
    return next;
  }

  bool split_by_normals(const ChartInfo& c, int new_label) {
    const size_t F = c.faces.size();
    const std::vector<std::array<int, 3>> next = neighbours(c);
    std::vector<Vector3> normal(F);
    std::vector<double> area(F);
    for (size_t i = 0; i < F; ++i) {
      const Tri& t = m_.faces[static_cast<size_t>(c.faces[i])];
      normal[i] = face_normal(m_, t);
      area[i] = face_area(m_, t);
    }
    // Normals averaged over a few rings of faces: a scan's noise in the face normals would
    // otherwise make the border between the two sides zigzag.
    for (int pass = 0; pass < kNormalSmoothing; ++pass) {
      std::vector<Vector3> smoothed(F);
      for (size_t i = 0; i < F; ++i) {
        Vector3 sum = area[i] * normal[i];
        for (int g : next[i])
          if (g >= 0) sum += area[static_cast<size_t>(g)] * normal[static_cast<size_t>(g)];
        smoothed[i] = sum.norm() > 0 ? Vector3(sum.normalized()) : normal[i];
      }
      normal.swap(smoothed);
    }
    Vector3 mean = Vector3::Zero();
    for (size_t i = 0; i < F; ++i) mean += area[i] * normal[i];
    // Seeds: the face farthest in normal from the mean, and the one farthest from that.
    auto farthest_from = [&](const Vector3& n) {
      size_t best = 0;
      for (size_t i = 1; i < F; ++i)
        if (normal[i].dot(n) < normal[best].dot(n)) best = i;
      return best;
    };
    size_t s1 = farthest_from(mean.norm() > 0 ? Vector3(mean.normalized()) : normal[0]);
    size_t s2 = farthest_from(normal[s1]);
    // Normals within kFlatTurn of each other: nothing to split by.
    if (normal[s1].dot(normal[s2]) > std::cos(kFlatTurn * kPi / 180)) return false;
    std::vector<int> side(F, -1);
    Vector3 proxy[2] = {normal[s1], normal[s2]};
    size_t seed[2] = {s1, s2};
    for (int round = 0; round < kSplitRounds; ++round) {
      std::fill(side.begin(), side.end(), -1);
      using Q = std::pair<double, std::pair<int, int>>;  // (cost, (face, side))
      std::priority_queue<Q, std::vector<Q>, std::greater<>> q;
      for (int p = 0; p < 2; ++p) q.push({0.0, {static_cast<int>(seed[p]), p}});
      while (!q.empty()) {
        const auto [cost, item] = q.top();
        q.pop();
        const auto [f, p] = item;
        if (side[static_cast<size_t>(f)] >= 0) continue;
        side[static_cast<size_t>(f)] = p;
        for (int g : next[static_cast<size_t>(f)])
          if (g >= 0 && side[static_cast<size_t>(g)] < 0)
            q.push({area[static_cast<size_t>(g)] *
                        (normal[static_cast<size_t>(g)] - proxy[p]).squaredNorm(),
                    {g, p}});
      }
      // New proxies: the mean normals; new seeds: the faces nearest to them.
      Vector3 sum[2] = {Vector3::Zero(), Vector3::Zero()};
      for (size_t i = 0; i < F; ++i)
        if (side[i] >= 0) sum[side[i]] += area[i] * normal[i];
      for (int p = 0; p < 2; ++p) {
        if (!(sum[p].norm() > 0)) return false;
        proxy[p] = sum[p].normalized();
        double best = std::numeric_limits<double>::infinity();
        for (size_t i = 0; i < F; ++i)
          if (side[i] == p && (normal[i] - proxy[p]).squaredNorm() < best)
            best = (normal[i] - proxy[p]).squaredNorm(), seed[p] = i;
      }
    }
    return apply_split(c, next, side, new_label);
  }

  // Gives the faces on side 1 of a split the new label, after straightening the border
  // between the sides; false (nothing changed) if a side is empty.
  bool apply_split(const ChartInfo& c, const std::vector<std::array<int, 3>>& next, std::vector<int>& side,
                   int new_label) {
    smooth_sides(next, side);
    const size_t F = c.faces.size();
    size_t second = 0;
    for (size_t i = 0; i < F; ++i) second += side[i] == 1;
    if (second == 0 || second == F) return false;
    for (size_t i = 0; i < F; ++i)
      if (side[i] == 1) label_[static_cast<size_t>(c.faces[i])] = new_label;
    return true;
  }

  // The angle (degrees) between the two most different normals of a chart, roughly: the face
  // farthest from the mean normal and the face farthest from that one.
  double normal_spread(const ChartInfo& c) const {
    Vector3 mean = Vector3::Zero();
    for (int f : c.faces)
      mean += face_area(m_, m_.faces[static_cast<size_t>(f)]) *
              face_normal(m_, m_.faces[static_cast<size_t>(f)]);
    auto farthest_from = [&](const Vector3& n) {
      Vector3 best = face_normal(m_, m_.faces[static_cast<size_t>(c.faces.front())]);
      for (int f : c.faces) {
        const Vector3 g = face_normal(m_, m_.faces[static_cast<size_t>(f)]);
        if (g.dot(n) < best.dot(n)) best = g;
      }
      return best;
    };
    const Vector3 a =
        farthest_from(mean.norm() > 0 ? Vector3(mean.normalized()) : Vector3::UnitZ());
    const Vector3 b = farthest_from(a);
    return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / kPi;
  }

  // Straightens the border between the two sides of a split: a face with two or three
  // neighbours on the other side goes over (a few passes), so that seams follow the mesh's
  // edges without zigzags of one face.
  static void smooth_sides(const std::vector<std::array<int, 3>>& next, std::vector<int>& side) {
    for (int pass = 0; pass < kSmoothPasses; ++pass) {
      bool changed = false;
      for (size_t i = 0; i < side.size(); ++i) {
        int other = 0, count = 0;
        for (int g : next[i])
          if (g >= 0) ++count, other += side[static_cast<size_t>(g)] != side[i];
        if (count >= 2 && other >= 2) side[i] = 1 - side[i], changed = true;
      }
      if (!changed) break;
    }
  }

  // Joins two boundary loops of a chart by a cut along the shortest path between them: a tube
  // becomes a disk. False if there is no such path.
  bool join_loops(const ChartInfo& c) {
    // The chart's boundary copies by loop.
    std::vector<int> loop_of(static_cast<size_t>(copies_), -1);
    UnionFind uf(static_cast<size_t>(copies_));
    std::vector<int> boundary;
    for (int f : c.faces)
      for (int k = 0; k < 3; ++k) {
        const int h = 3 * f + k;
        if (!separated(h)) continue;
        const int a = copy_[static_cast<size_t>(h)],
                  b = copy_[static_cast<size_t>(3 * f + (k + 1) % 3)];
        uf.join(a, b);
        boundary.push_back(a);
      }
    if (boundary.empty()) return false;
    // The longest loop is the start.
    std::map<int, double> length;
    for (int f : c.faces)
      for (int k = 0; k < 3; ++k)
        if (separated(3 * f + k))
          length[uf.find(copy_[static_cast<size_t>(3 * f + k)])] += edge_length(3 * f + k);
    if (length.size() < 2) return false;
    int start = length.begin()->first;
    for (const auto& [r, l] : length)
      if (l > length[start]) start = r;
    std::vector<int> sources;
    for (int v : boundary)
      if (uf.find(v) == start) sources.push_back(v);
    std::sort(sources.begin(), sources.end());
    sources.erase(std::unique(sources.begin(), sources.end()), sources.end());
    const auto edges = inner_edges(c);
    std::vector<int> pred;
    const std::vector<double> d = distances(c, sources, &pred, &edges);
    int end = -1;
    for (int v : boundary)
      if (uf.find(v) != start && std::isfinite(d[static_cast<size_t>(v)]) &&
          (end < 0 || d[static_cast<size_t>(v)] < d[static_cast<size_t>(end)]))
        end = v;
    if (end < 0) return false;
    for (int v = end; pred[static_cast<size_t>(v)] >= 0;) {
      const InnerEdge& e = edges[static_cast<size_t>(pred[static_cast<size_t>(v)])];
      cut_[static_cast<size_t>(he_.edge[static_cast<size_t>(e.h)])] = 1;
      v = e.a == v ? e.b : e.a;
    }
    return true;
  }

  // Cuts a chart with handles along a system of loops that leaves it of genus 0
  // (tree-cotree, Eppstein 2003): a shortest-path tree of its copies, a spanning tree of the
  // faces (and one cap per boundary loop) across the other edges; each edge in neither closes
  // a loop through the first tree. False if no loop was found.
  bool cut_handles(const ChartInfo& c) {
    const auto edges = inner_edges(c);
    std::vector<int> pred;
    const int root = c.copies.front();
    distances(c, {root}, &pred, &edges);
    std::vector<char> in_tree(edges.size(), 0);
    for (int v : c.copies)
      if (pred[static_cast<size_t>(v)] >= 0)
        in_tree[static_cast<size_t>(pred[static_cast<size_t>(v)])] = 1;
    // Dual nodes: the chart's faces, then a cap per boundary loop.
    std::unordered_map<int, int> face_node;
    for (size_t i = 0; i < c.faces.size(); ++i) face_node[c.faces[i]] = static_cast<int>(i);
    UnionFind loop_uf(static_cast<size_t>(copies_));
    for (int f : c.faces)
      for (int k = 0; k < 3; ++k)
        if (separated(3 * f + k))
          loop_uf.join(copy_[static_cast<size_t>(3 * f + k)],
                       copy_[static_cast<size_t>(3 * f + (k + 1) % 3)]);
    std::unordered_map<int, int> cap_node;
    const int F = static_cast<int>(c.faces.size());
    UnionFind dual(c.faces.size() + c.copies.size());
    for (int f : c.faces)
      for (int k = 0; k < 3; ++k) {
        if (!separated(3 * f + k)) continue;
        const int r = loop_uf.find(copy_[static_cast<size_t>(3 * f + k)]);
        auto it = cap_node.find(r);
        if (it == cap_node.end())
          it = cap_node.emplace(r, F + static_cast<int>(cap_node.size())).first;
        dual.join(face_node[f], it->second);
      }
    std::vector<int> leftover;
    for (size_t e = 0; e < edges.size(); ++e) {
      if (in_tree[e]) continue;
      const int h = edges[e].h, g = he_.twin[static_cast<size_t>(h)];
      const int a = face_node[h / 3], b = face_node[g / 3];
      if (dual.find(a) != dual.find(b))
        dual.join(a, b);
      else
        leftover.push_back(static_cast<int>(e));
    }
    if (leftover.empty()) return false;
    for (int e : leftover) {
      // The loop: the edge and the tree paths from its ends up to where they meet.
      std::unordered_map<int, int> seen;  // tree edge -> times on the two paths
      for (int end : {edges[static_cast<size_t>(e)].a, edges[static_cast<size_t>(e)].b})
        for (int v = end; pred[static_cast<size_t>(v)] >= 0;) {
          const InnerEdge& t = edges[static_cast<size_t>(pred[static_cast<size_t>(v)])];
          ++seen[pred[static_cast<size_t>(v)]];
          v = t.a == v ? t.b : t.a;
        }
      cut_[static_cast<size_t>(he_.edge[static_cast<size_t>(edges[static_cast<size_t>(e)].h)])] = 1;
      for (const auto& [t, times] : seen)
        if (times == 1)
          cut_[static_cast<size_t>(
              he_.edge[static_cast<size_t>(edges[static_cast<size_t>(t)].h)])] = 1;
    }
    return true;
  }

 private:
  const Mesh3& m_;
  HalfEdges he_;
  int F_ = 0;
  std::vector<char> cut_, sharp_;
  std::vector<double> length_;
  std::vector<int> label_;
  std::vector<int> copy_, copy_vertex_, chart_;
  int copies_ = 0, charts_ = 0;
};

// How far a flattening would stretch the spline over it: the largest |F_u|, |F_v| (1 over the
// smaller singular value of the map from a triangle to its (u, v) image, the map scaled to the
// surface's area) times the diameter of the (u, v) box over that of the 3D box, as the fit's
// max_stretch measures it; over the triangles that hold all but kStretchShare of the area, so
// that a few slivers of a noisy mesh do not decide it.
constexpr double kStretchShare = 0.005;
double stretch_estimate(const Mesh3& m, const std::vector<P2>& uv) {
  std::vector<P2> q = uv;
  normalise(m, q);
  Eigen::AlignedBox2d box2;
  Eigen::AlignedBox3d box3;
  std::vector<std::pair<double, double>> speed;  // (speed, area)
  double total = 0;
  for (const Tri& t : m.faces) {
    const Point3 &a = m.points[t[0]], &b = m.points[t[1]], &c = m.points[t[2]];
    box3.extend(a), box3.extend(b), box3.extend(c);
    for (int k = 0; k < 3; ++k) box2.extend(Eigen::Vector2d(q[t[k]].x(), q[t[k]].y()));
    const Vector3 e1 = b - a, e2 = c - a;
    const double l = e1.norm();
    const double w = 0.5 * e1.cross(e2).norm();
    if (!(l > 0) || !(w > 0)) continue;
    const Vector3 ex = e1 / l, ey = e1.cross(e2).cross(e1).normalized();
    Eigen::Matrix2d ps, qs;
    ps << l, e2.dot(ex), 0, e2.dot(ey);
    qs << q[t[1]].x() - q[t[0]].x(), q[t[2]].x() - q[t[0]].x(), q[t[1]].y() - q[t[0]].y(),
        q[t[2]].y() - q[t[0]].y();
    const Eigen::Vector2d sv =
        Eigen::JacobiSVD<Eigen::Matrix2d>(qs * ps.inverse()).singularValues();
    speed.push_back({sv[1] > 0 ? 1 / sv[1] : std::numeric_limits<double>::infinity(), w});
    total += w;
  }
  if (speed.empty()) return 1;
  std::sort(speed.begin(), speed.end(),
            [](const auto& x, const auto& y) { return x.first > y.first; });
  double skipped = 0;
  size_t i = 0;
  while (i + 1 < speed.size() && skipped + speed[i].second <= kStretchShare * total)
    skipped += speed[i++].second;
  const double d3 = box3.diagonal().norm();
  return d3 > 0 ? speed[i].first * box2.diagonal().norm() / d3 : 1;
}

// One chart's flattening: LSCM (relaxed toward equal areas where it shrinks parts), or mean
// value where LSCM folds, scaled to the surface's area; ok when bijective and its stretch is
// within the bound.
struct Flat {
  std::vector<P2> uv;
  double stretch = std::numeric_limits<double>::infinity();
  bool bijective = false;
  std::string method;
};

Flat flatten_chart(const Mesh3& m, const ParameterizeOptions& o) {
  Flat out;
  ParameterizeOptions quiet = o;
  quiet.progress = nullptr;
  ParameterizeReport rep;
  try {
    out.uv = flatten(m, quiet, rep);
  } catch (const InvalidInput&) {
    return out;
  } catch (const SolverError&) {
    return out;
  }
  out.bijective = true;
  out.method = rep.method;
  normalise(m, out.uv);
  out.stretch = stretch_estimate(m, out.uv);
  return out;
}

}  // namespace

double flattening_stretch(const Mesh3& m, const std::vector<P2>& uv) {
  return stretch_estimate(m, uv);
}

ChartCut cut_into_charts(const Mesh3& m, const ParameterizeOptions& o, ParameterizeReport& rep) {
  auto say = [&](const std::string& s) {
    if (o.progress) o.progress(s);
  };
  Cutter cutter(m, o.sharp_angle);
  double area = 0;
  for (const Tri& t : m.faces) area += face_area(m, t);
  cutter.segment_by_sharp_edges(area);
  cutter.rebuild();
  say("cutting the surface into charts: " +
      plural(static_cast<size_t>(cutter.charts()), "region", "regions") + " between sharp edges");

  // Flattenings of accepted charts, by (first face, faces): a chart that no cut touched keeps
  // its faces and is not flattened again.
  std::map<std::pair<int, size_t>, Flat> done;
  int next_label = cutter.face_count() + 1;
  for (int round = 0;; ++round) {
    const auto infos = cutter.chart_infos();
    bool changed = false;
    const bool last = round + 1 >= kMaxRounds || cutter.charts() >= kMaxCharts;
    for (const ChartInfo& c : infos) {
      const auto key = std::make_pair(c.faces.front(), c.faces.size());
      if (done.count(key)) continue;
      const bool small = c.faces.size() < kMinChartFaces;
      bool cut = false;
      if (c.closed()) {
        cut = cutter.split_in_two(c, next_label++);
      } else if (c.genus > 0) {
        cut = (!last && cutter.cut_handles(c)) || cutter.split_in_two(c, next_label++);
      } else {
        std::vector<int> local;
        Flat flat = flatten_chart(cutter.chart_mesh(c, local), o);
        const bool good = flat.bijective && flat.stretch <= o.chart_stretch;
        if (good || (flat.bijective && (small || last))) {
          done[key] = std::move(flat);
          continue;
        }
        const bool bent = cutter.normal_spread(c) > kBentChart;
        cut = (bent && cutter.split_in_two(c, next_label++)) ||
              (c.loops >= 2 && cutter.join_loops(c)) || cutter.split_in_two(c, next_label++);
        if (!cut && flat.bijective) {
          done[key] = std::move(flat);
          continue;
        }
      }
      if (!cut)
        throw InvalidInput("a chart of " + plural(c.faces.size(), "face", "faces") + " (genus " +
                           std::to_string(c.genus) + ", " +
                           plural(static_cast<size_t>(c.loops), "boundary loop", "boundary loops") +
                           ") could be neither cut nor flattened; repair the mesh (e.g. remove "
                           "slivers) and retry");
      changed = true;
    }
    if (!changed) break;
    cutter.rebuild();
  }

  // Every chart is flattened now; lay them out side by side, largest first, in rows.
  const auto infos = cutter.chart_infos();
  ChartCut out;
  out.charts = static_cast<int>(infos.size());
  out.uv.assign(static_cast<size_t>(cutter.copies()), P2(0, 0));
  struct Placed {
    size_t chart;
    double w, h;
  };
  std::vector<Placed> order;
  std::vector<std::vector<P2>> chart_uv(infos.size());
  double box_area = 0;
  for (size_t i = 0; i < infos.size(); ++i) {
    const Flat& f = done.at({infos[i].faces.front(), infos[i].faces.size()});
    chart_uv[i] = f.uv;
    double w = 0, h = 0;
    for (const P2& p : f.uv) w = std::max(w, p.x()), h = std::max(h, p.y());
    order.push_back({i, w, h});
    box_area += w * h;
    out.stretch = std::max(out.stretch, f.stretch);
  }
  // The gap between charts: wide enough that no domain triangle, margin or knot cloud of one
  // chart reaches another at the fit's coarsest start (32 triangles over the whole area).
  const double gap = 0.3 * std::sqrt(area);
  std::stable_sort(order.begin(), order.end(),
                   [](const Placed& a, const Placed& b) { return a.h > b.h; });
  double row_width = 0;
  for (const Placed& p : order) row_width = std::max(row_width, p.w);
  row_width = std::max(row_width,
                       1.2 * std::sqrt(box_area + static_cast<double>(order.size()) * gap * gap));
  double x = 0, y = 0, row_h = 0;
  std::vector<P2> offset(infos.size());
  for (const Placed& p : order) {
    if (x > 0 && x + p.w > row_width) x = 0, y += row_h + gap, row_h = 0;
    offset[p.chart] = P2(x, y);
    x += p.w + gap;
    row_h = std::max(row_h, p.h);
  }
  for (size_t i = 0; i < infos.size(); ++i)
    for (size_t k = 0; k < infos[i].copies.size(); ++k)
      out.uv[static_cast<size_t>(infos[i].copies[k])] =
          P2(chart_uv[i][k].x() + offset[i].x(), chart_uv[i][k].y() + offset[i].y());

  // The cut mesh: a vertex per copy, the faces in their order.
  out.mesh.points.resize(static_cast<size_t>(cutter.copies()));
  out.origin.resize(static_cast<size_t>(cutter.copies()));
  for (int c = 0; c < cutter.copies(); ++c) {
    out.origin[static_cast<size_t>(c)] = cutter.copy_vertex(c);
    out.mesh.points[static_cast<size_t>(c)] = m.points[static_cast<size_t>(cutter.copy_vertex(c))];
  }
  for (int f = 0; f < cutter.face_count(); ++f)
    out.mesh.faces.push_back({cutter.copy_of_corner(3 * f), cutter.copy_of_corner(3 * f + 1),
                              cutter.copy_of_corner(3 * f + 2)});

  // Seams: chains of cut edges between vertices where they branch, end or meet the mesh's
  // boundary, split where the edges change from sharp to smooth. Walking p -> q, side a is the
  // face on the left (the one that runs p -> q), side b the other.
  const HalfEdges& he = cutter.he();
  const int V = static_cast<int>(m.points.size());
  std::vector<std::vector<int>> at(
      static_cast<size_t>(V));  // seam half-edges leaving each vertex (both directions)
  std::vector<char> on_boundary(static_cast<size_t>(V), 0);
  for (int h = 0; h < 3 * cutter.face_count(); ++h) {
    const Tri& t = m.faces[static_cast<size_t>(h / 3)];
    const int p = t[h % 3];
    if (he.twin[static_cast<size_t>(h)] < 0) {
      on_boundary[static_cast<size_t>(p)] = on_boundary[static_cast<size_t>(t[(h % 3 + 1) % 3])] =
          1;
      continue;
    }
    if (cutter.separated(h)) at[static_cast<size_t>(p)].push_back(h);
  }
  auto end_of = [&](int h) { return m.faces[static_cast<size_t>(h / 3)][(h % 3 + 1) % 3]; };
  auto node = [&](int v) {
    return at[static_cast<size_t>(v)].size() != 2 || on_boundary[static_cast<size_t>(v)];
  };
  std::vector<char> used(static_cast<size_t>(he.edges), 0);
  auto walk = [&](int h0) {
    // h0 leaves the chain's first vertex; follow it to the next node (or back to the start).
    std::vector<int> chain{h0};
    used[static_cast<size_t>(he.edge[static_cast<size_t>(h0)])] = 1;
    for (int h = h0;;) {
      const int q = end_of(h);
      if (node(q)) break;
      int next = -1;
      for (int g : at[static_cast<size_t>(q)])
        if (!used[static_cast<size_t>(he.edge[static_cast<size_t>(g)])]) next = g;
      if (next < 0) break;  // back at the start of a closed chain
      used[static_cast<size_t>(he.edge[static_cast<size_t>(next)])] = 1;
      chain.push_back(next);
      h = next;
    }
    return chain;
  };
  std::vector<std::vector<int>> chains;
  for (int v = 0; v < V; ++v)
    if (node(v))
      for (int h : at[static_cast<size_t>(v)])
        if (!used[static_cast<size_t>(he.edge[static_cast<size_t>(h)])]) chains.push_back(walk(h));
  for (int v = 0; v < V; ++v)
    for (int h : at[static_cast<size_t>(v)])
      if (!used[static_cast<size_t>(he.edge[static_cast<size_t>(h)])]) chains.push_back(walk(h));
  for (const auto& chain : chains) {
    // Corner copies of a half-edge's start and end in its own face (side a) and in its twin's
    // face (side b).
    auto copies_of = [&](int h) {
      const int g = he.twin[static_cast<size_t>(h)];
      return std::array<int, 4>{
          cutter.copy_of_corner(h), cutter.copy_of_corner(3 * (h / 3) + (h % 3 + 1) % 3),
          cutter.copy_of_corner(3 * (g / 3) + (g % 3 + 1) % 3), cutter.copy_of_corner(g)};
    };
    Seam seam;
    std::vector<int> a_copies, b_copies;
    auto flush = [&] {
      if (seam.a.size() >= 2) {
        out.seams.push_back(seam);
        out.seam_edges += seam.a.size() - 1;
      }
      seam = Seam();
    };
    for (size_t i = 0; i < chain.size(); ++i) {
      const int h = chain[i];
      const bool sharp = cutter.sharp_edge(he.edge[static_cast<size_t>(h)]);
      const auto c = copies_of(h);
      const bool continues = !seam.a.empty() && sharp == seam.sharp && a_copies.back() == c[0] &&
                             b_copies.back() == c[2];
      if (!continues) {
        flush();
        seam.sharp = sharp;
        a_copies = {c[0]};
        b_copies = {c[2]};
        seam.a.push_back(
            Point2(out.uv[static_cast<size_t>(c[0])].x(), out.uv[static_cast<size_t>(c[0])].y()));
        seam.b.push_back(
            Point2(out.uv[static_cast<size_t>(c[2])].x(), out.uv[static_cast<size_t>(c[2])].y()));
      }
      a_copies.push_back(c[1]);
      b_copies.push_back(c[3]);
      seam.a.push_back(
          Point2(out.uv[static_cast<size_t>(c[1])].x(), out.uv[static_cast<size_t>(c[1])].y()));
      seam.b.push_back(
          Point2(out.uv[static_cast<size_t>(c[3])].x(), out.uv[static_cast<size_t>(c[3])].y()));
    }
    flush();
  }
  // Borders: the runs of mesh boundary along each chart's outline, walked with the chart on
  // the left (each boundary copy has one outgoing outline half-edge).
  {
    std::vector<int> outgoing(static_cast<size_t>(cutter.copies()), -1);
    std::vector<int> outline;
    for (int h = 0; h < 3 * cutter.face_count(); ++h)
      if (cutter.separated(h)) {
        outgoing[static_cast<size_t>(cutter.copy_of_corner(h))] = h;
        outline.push_back(h);
      }
    auto next = [&](int h) {
      return outgoing[static_cast<size_t>(cutter.copy_of_corner(3 * (h / 3) + (h % 3 + 1) % 3))];
    };
    auto uv_of = [&](int copy) {
      return Point2(out.uv[static_cast<size_t>(copy)].x(), out.uv[static_cast<size_t>(copy)].y());
    };
    auto free_edge = [&](int h) { return he.twin[static_cast<size_t>(h)] < 0; };
    std::vector<char> seen(static_cast<size_t>(3 * cutter.face_count()), 0);
    for (int h0 : outline) {
      if (seen[static_cast<size_t>(h0)] || !free_edge(h0)) continue;
      // Back to the run's first half-edge (or all the way round a loop that is all border).
      int first = h0;
      std::vector<int> loop{h0};
      for (int h = next(h0); h >= 0 && h != h0 && loop.size() <= outline.size(); h = next(h))
        loop.push_back(h);
      const bool all_free =
          std::all_of(loop.begin(), loop.end(), free_edge) && next(loop.back()) == h0;
      if (!all_free) {
        // The loop as a cycle starting after a seam edge: runs of free half-edges.
        size_t start = 0;
        while (start < loop.size() && free_edge(loop[start])) ++start;
        std::rotate(loop.begin(), loop.begin() + static_cast<long>(start), loop.end());
      }
      (void)first;
      std::vector<Point2> run;
      auto flush = [&] {
        if (run.size() >= 2) out.borders.push_back(run);
        run.clear();
      };
      for (int h : loop) {
        if (seen[static_cast<size_t>(h)]) continue;
        seen[static_cast<size_t>(h)] = 1;
        if (!free_edge(h)) {
          flush();
          continue;
        }
        if (run.empty()) run.push_back(uv_of(cutter.copy_of_corner(h)));
        run.push_back(uv_of(cutter.copy_of_corner(3 * (h / 3) + (h % 3 + 1) % 3)));
      }
      flush();
    }
  }
  say("cut into " + plural(static_cast<size_t>(out.charts), "chart", "charts") + " along " +
      plural(out.seam_edges, "edge", "edges") + " (" + plural(out.seams.size(), "seam", "seams") +
      ")");
  (void)rep;
  return out;
}

}  // namespace tbs::detail
