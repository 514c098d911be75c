// tbs::Evaluator (evaluator.h): the spline's basis functions as a graph of simplex-spline
// recurrences per domain triangle, evaluated with value and derivatives; point location on a
// box grid under the half-open rule.

#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/reference.h>
#include <tbs/tolerances.h>

#include "box_grid.h"
#include "thread_arena.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace tbs {
namespace {

constexpr int kMaxKnots = tol::kMaxDegree + 2;  // top sets of the degree n-1 form

// A knot set: sorted global knot ids (vertex * (n+1) + level).
struct Key {
  int size = 0;
  std::array<int, kMaxKnots> id{};
  bool operator==(const Key& o) const {
    return size == o.size && std::equal(id.begin(), id.begin() + size, o.id.begin());
  }
};
struct KeyHash {
  size_t operator()(const Key& k) const {
    uint64_t h = 1469598103934665603ull ^ static_cast<uint64_t>(k.size);
    for (int i = 0; i < k.size; ++i) h = (h ^ static_cast<uint64_t>(k.id[i])) * 1099511628211ull;
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

// One simplex spline M(u | V). Degree 0: the half-open triangle p0 p1 p2 (counter-clockwise)
// with value 1/|d|. Degree > 0: the recurrence with split set W,
// lambda_j(u) = l0[j] + g[j] . (u - o), o = w_0.
// Laid out in two cache lines: what every visit reads (box, kind, children) in the first,
// the geometry of a visit that gets past the box test in the second.
struct alignas(64) Node {
  Box2 box;
  int degree = 0;
  bool zero = false;  // a degenerate (all knots collinear) spline: identically 0
  std::array<int, 3> child{-1, -1, -1};
  double inv_area = 0;  // degree 0
  // Degree 0: the corners, x0 y0 x1 y1 x2 y2. Degree > 0: o.x, o.y, then the gradients
  // gx[0..2], gy[0..2] of lambda_j.
  std::array<double, 8> geo{};
  Point2 corner(int j) const { return Point2(geo[2 * j], geo[2 * j + 1]); }
};

// The memo of one node for the current point: its value and the point's stamp.
struct Memo {
  double val = 0;
  uint32_t stamp = 0;
};

// One term of the degree n-1 form of one triangle: M(u | V_{I,g}) times
// sum_j d(X[j <- u]) c_j, with d(X[j <- u]) = d0[j] + gx[j] (u-x0).x + gy[j] (u-x0).y.
struct Top {
  int node = -1;
  std::array<int, 3> cp{};
  Point2 x0;
  double d = 0;  // d(X)
  std::array<double, 3> gx{}, gy{};
};

struct Scratch {
  std::vector<Memo> memo;
  uint32_t cur = 0;
  void begin(size_t nodes) {
    if (memo.size() != nodes) {
      memo.assign(nodes, Memo{});
      cur = 0;
    }
    if (++cur == 0) {
      std::fill(memo.begin(), memo.end(), Memo{});
      cur = 1;
    }
  }
};

// Gradients of d(Y[j <- u]) for j = 0..2 with respect to u: for the cyclic triple
// (u, b, c), d = b x c + u x (b - c).
void affine_gradients(const std::array<Point2, 3>& y, std::array<double, 3>& gx,
                      std::array<double, 3>& gy) {
  for (int j = 0; j < 3; ++j) {
    const Point2& b = y[(j + 1) % 3];
    const Point2& c = y[(j + 2) % 3];
    gx[j] = b.y() - c.y();
    gy[j] = c.x() - b.x();
  }
}

}  // namespace

struct Evaluator::Impl {
  const Spline* s;
  EvalMode mode;
  int n;
  int nb;  // terms per triangle: beta_count(n - 1)
  std::vector<Node> nodes;
  std::vector<std::array<int, 3>> split;  // knot ids of each node's split set W (degree > 0)
  std::vector<Key> keys;
  std::unordered_map<Key, int, KeyHash> index;
  std::vector<Top> tops;
  std::vector<Box2> tri_box, support;
  detail::BoxGrid tri_grid, support_grid;
  std::vector<std::vector<int>> vertex_nodes;
  mutable tbb::enumerable_thread_specific<Scratch> scratch;

  Impl(const Spline& spline, EvalMode m) : s(&spline), mode(m), n(spline.degree()) { build(); }
  // Everything but the per-thread scratch, for another spline with the same knots.
  Impl(const Impl& o, const Spline& spline)
      : s(&spline), mode(o.mode), n(o.n), nb(o.nb), nodes(o.nodes), split(o.split), keys(o.keys),
        index(o.index), tops(o.tops), tri_box(o.tri_box), support(o.support), tri_grid(o.tri_grid),
        support_grid(o.support_grid), vertex_nodes(o.vertex_nodes) {}

  const Point2& knot(int id) const { return s->knots()[id]; }
  int vertex_of(int id) const { return id / (n + 1); }
  int level_of(int id) const { return id % (n + 1); }

  void build() {
    nb = beta_count(n - 1);
    nodes.clear();
    split.clear();
    keys.clear();
    index.clear();
    tops.clear();
    const Domain& d = s->domain();
    vertex_nodes.assign(d.vertex_count(), {});
    tops.resize(static_cast<size_t>(d.triangle_count()) * nb);
    for (int t = 0; t < d.triangle_count(); ++t) {
      const auto& tri = d.triangle(t);
      for (int i = 0; i < nb; ++i) {
        const Beta g = beta_at(n - 1, i);
        Key k;
        for (int j = 0; j < 3; ++j)
          for (int l = 0; l <= g[j]; ++l) k.id[k.size++] = s->knot_id(tri[j], l);
        std::sort(k.id.begin(), k.id.begin() + k.size);
        Top& top = tops[static_cast<size_t>(t) * nb + i];
        top.node = get(k);
        for (int j = 0; j < 3; ++j) {
          Beta h = g;
          ++h[j];
          top.cp[j] = s->control_point_index(t, h);
        }
      }
    }
    for (int t = 0; t < d.triangle_count(); ++t) refresh_triangle(t);
    rebuild_grids();
  }

  void refresh_triangle(int t) {
    const auto& tri = s->domain().triangle(t);
    for (int i = 0; i < nb; ++i) {
      const Beta g = beta_at(n - 1, i);
      Top& top = tops[static_cast<size_t>(t) * nb + i];
      const std::array<Point2, 3> x{s->knot(tri[0], g[0]), s->knot(tri[1], g[1]),
                                    s->knot(tri[2], g[2])};
      top.x0 = x[0];
      top.d = det3(x[0], x[1], x[2]);
      affine_gradients(x, top.gx, top.gy);
    }
  }

  // The box of triangle t, and the box of its basis functions' supports: the knots of levels
  // 0 .. n-1 of its vertices (those of the degree n-1 form's knot sets).
  void triangle_boxes(int t) {
    const Domain& d = s->domain();
    tri_box[t] = support[t] = Box2{};
    for (int v : d.triangle(t)) {
      tri_box[t].extend(d.vertex(v));
      for (int l = 0; l < n; ++l) support[t].extend(s->knot(v, l));
    }
  }

  void rebuild_grids() {
    const Domain& d = s->domain();
    tri_box.resize(d.triangle_count());
    support.resize(d.triangle_count());
    for (int t = 0; t < d.triangle_count(); ++t) triangle_boxes(t);
    tri_grid.build(tri_box, static_cast<size_t>(d.triangle_count()));
    support_grid.build(support, static_cast<size_t>(d.triangle_count()));
  }

  // Chooses the split set: the highest-level knot of each vertex when the set spans three
  // vertices (an X_{I,beta}, non-degenerate under the knot conditions), otherwise the
  // best-conditioned triple. False if every triple is degenerate.
  bool choose_split(const Key& k, std::array<int, 3>& w) const {
    int groups = 0;
    for (int i = 0; i < k.size; ++i) {
      const bool last_of_group = i + 1 == k.size || vertex_of(k.id[i + 1]) != vertex_of(k.id[i]);
      if (last_of_group) {
        if (groups < 3) w[groups] = k.id[i];
        ++groups;
      }
    }
    if (groups == 3 && orientation(knot(w[0]), knot(w[1]), knot(w[2])) != 0) return true;
    double best = -1;
    for (int a = 0; a < k.size; ++a)
      for (int b = a + 1; b < k.size; ++b)
        for (int c = b + 1; c < k.size; ++c) {
          const double area = std::fabs(det3(knot(k.id[a]), knot(k.id[b]), knot(k.id[c])));
          if (area > best) best = area, w = {k.id[a], k.id[b], k.id[c]};
        }
    return best >= 0 && orientation(knot(w[0]), knot(w[1]), knot(w[2])) != 0;
  }

  int get(const Key& k) {
    if (auto it = index.find(k); it != index.end()) return it->second;
    const int id = static_cast<int>(nodes.size());
    nodes.emplace_back();
    split.push_back({-1, -1, -1});
    keys.push_back(k);
    index.emplace(k, id);
    for (int i = 0; i < k.size; ++i)
      if (i == 0 || vertex_of(k.id[i]) != vertex_of(k.id[i - 1]))
        vertex_nodes[vertex_of(k.id[i])].push_back(id);
    nodes[id].degree = k.size - 3;
    if (k.size > 3) {
      std::array<int, 3> w;
      if (!choose_split(k, w)) {
        nodes[id].zero = true;
      } else {
        split[id] = w;
        for (int j = 0; j < 3; ++j) {
          Key c;
          bool skipped = false;
          for (int i = 0; i < k.size; ++i) {
            if (!skipped && k.id[i] == w[j]) {
              skipped = true;
              continue;
            }
            c.id[c.size++] = k.id[i];
          }
          const int child = get(c);
          nodes[id].child[j] = child;
        }
      }
    }
    refresh_node(id);
    return id;
  }

  // Recomputes the geometry of a node from the current knots. False if its split set became
  // degenerate (the graph must then be rebuilt).
  bool refresh_node(int id) {
    Node& nd = nodes[id];
    const Key& k = keys[id];
    nd.box = Box2{};
    for (int i = 0; i < k.size; ++i) nd.box.extend(knot(k.id[i]));
    if (nd.degree == 0) {
      Point2 a = knot(k.id[0]), b = knot(k.id[1]), c = knot(k.id[2]);
      const int o = orientation(a, b, c);
      nd.zero = o == 0;
      if (o < 0) std::swap(b, c);
      nd.geo = {a.x(), a.y(), b.x(), b.y(), c.x(), c.y(), 0.0, 0.0};
      nd.inv_area = o == 0 ? 0.0 : 1.0 / std::fabs(det3(a, b, c));
      return true;
    }
    if (nd.zero) return nd.child[0] < 0 ? !non_degenerate(k) : true;
    const std::array<int, 3>& ws = split[id];
    const std::array<Point2, 3> w{knot(ws[0]), knot(ws[1]), knot(ws[2])};
    if (orientation(w[0], w[1], w[2]) == 0) return false;
    const double dd = det3(w[0], w[1], w[2]);
    std::array<double, 3> gx, gy;
    affine_gradients(w, gx, gy);
    nd.geo = {w[0].x(), w[0].y(), gx[0] / dd, gx[1] / dd,
              gx[2] / dd, gy[0] / dd, gy[1] / dd, gy[2] / dd};
    return true;
  }

  bool non_degenerate(const Key& k) const {
    std::array<int, 3> w;
    return choose_split(k, w);
  }

  // The value of a degree-0 node: 1/|d| if the perturbed point is inside its triangle.
  static double leaf(const Node& nd, const Perturbation& p) {
    const Point2 a = nd.corner(0), b = nd.corner(1), c = nd.corner(2);
    return perturbed_orientation(a, b, p) > 0 && perturbed_orientation(b, c, p) > 0 &&
                   perturbed_orientation(c, a, p) > 0
               ? nd.inv_area
               : 0.0;
  }
  // M(u | V) of node id, memoized per point. Memo hits and leaves are handled inline; only
  // nodes of degree > 0 not yet seen for this point recurse.
  double eval(int id, const Point2& u, const Perturbation& p, Scratch& sc) const {
    Memo& me = sc.memo[id];
    if (me.stamp == sc.cur) return me.val;
    const Node& nd = nodes[id];
    double v = 0;
    if (!nd.zero && nd.box.contains(u)) v = nd.degree == 0 ? leaf(nd, p) : recurse(nd, u, p, sc);
    me.stamp = sc.cur;
    me.val = v;
    return v;
  }

  __attribute__((noinline)) double recurse(const Node& nd, const Point2& u, const Perturbation& p,
                                           Scratch& sc) const {
    const auto& g = nd.geo;
    const double dx = u.x() - g[0], dy = u.y() - g[1];
    const double l0 = 1.0 + g[2] * dx + g[5] * dy;
    const double l1 = g[3] * dx + g[6] * dy;
    const double l2 = g[4] * dx + g[7] * dy;
    return l0 * eval(nd.child[0], u, p, sc) + l1 * eval(nd.child[1], u, p, sc) +
           l2 * eval(nd.child[2], u, p, sc);
  }

  double eval_recursive(int id, const Perturbation& p) const {
    const Key& k = keys[id];
    std::array<Point2, kMaxKnots> pts;
    for (int i = 0; i < k.size; ++i) pts[i] = knot(k.id[i]);
    return reference::simplex_spline(std::span<const Point2>(pts.data(), k.size), p);
  }

  std::optional<std::pair<int, Perturbation>> prepare(const Point2& u,
                                                      const Perturbation* given = nullptr) const {
    if (!u.allFinite()) return std::nullopt;
    const Domain& d = s->domain();
    if (given) {
      // A caller-chosen side: the triangle that contains the perturbed point, if any.
      for (int t : tri_grid.at(u)) {
        if (!tri_box[t].contains(u)) continue;
        const auto& tri = d.triangle(t);
        const Point2 &a = d.vertex(tri[0]), &b = d.vertex(tri[1]), &c = d.vertex(tri[2]);
        if (perturbed_orientation(a, b, *given) > 0 && perturbed_orientation(b, c, *given) > 0 &&
            perturbed_orientation(c, a, *given) > 0)
          return std::pair{t, *given};
      }
      return std::nullopt;
    }
    const Perturbation ps = Perturbation::standard(u);
    const auto cand = tri_grid.at(u);
    for (int t : cand) {
      if (!tri_box[t].contains(u)) continue;
      const auto& tri = d.triangle(t);
      const Point2 &a = d.vertex(tri[0]), &b = d.vertex(tri[1]), &c = d.vertex(tri[2]);
      if (perturbed_orientation(a, b, ps) > 0 && perturbed_orientation(b, c, ps) > 0 &&
          perturbed_orientation(c, a, ps) > 0)
        return std::pair{t, ps};
    }
    // On the outer boundary the standard perturbation may leave the domain: perturb toward
    // the centroid of a triangle the point lies on instead.
    for (int t : cand) {
      if (!tri_box[t].contains(u)) continue;
      const auto& tri = d.triangle(t);
      const Point2 &a = d.vertex(tri[0]), &b = d.vertex(tri[1]), &c = d.vertex(tri[2]);
      if (!closed_contains_ccw(a, b, c, u)) continue;
      const Point2 centroid = (a + b + c) / 3.0;
      Point2 second = a;
      double best = -1;
      for (const Point2* v : {&a, &b, &c}) {
        const double area = std::fabs(det3(u, centroid, *v));
        if (area > best) best = area, second = *v;
      }
      return std::pair{t, Perturbation::toward(u, centroid, second)};
    }
    return std::nullopt;
  }

  // Calls emit(top, M) for every term of the degree n-1 form that is non-zero at u.
  template <class Emit>
  bool accumulate(const Point2& u, Emit&& emit, const Perturbation* given = nullptr) const {
    const auto loc = prepare(u, given);
    if (!loc) return false;
    const Perturbation& p = loc->second;
    Scratch& sc = scratch.local();
    sc.begin(nodes.size());
    for (int t : support_grid.at(u)) {
      if (!support[t].contains(u)) continue;
      const Top* row = &tops[static_cast<size_t>(t) * nb];
      for (int i = 0; i < nb; ++i) {
        const double m = mode == EvalMode::Graph ? eval(row[i].node, u, p, sc)
                                                 : eval_recursive(row[i].node, p);
        if (m != 0) emit(row[i], m);
      }
    }
    return true;
  }

  bool evaluate(const Point2& u, Point3& f, Vector3& fu, Vector3& fv,
                const Perturbation* given = nullptr) const {
    const auto& cps = s->control_points();
    f.setZero();
    fu.setZero();
    fv.setZero();
    const bool ok = accumulate(u, [&](const Top& top, double m) {
      const double dx = u.x() - top.x0.x(), dy = u.y() - top.x0.y();
      const Point3& c0 = cps[top.cp[0]];
      const Point3& c1 = cps[top.cp[1]];
      const Point3& c2 = cps[top.cp[2]];
      const double w0 = top.d + top.gx[0] * dx + top.gy[0] * dy;
      const double w1 = top.gx[1] * dx + top.gy[1] * dy;
      const double w2 = top.gx[2] * dx + top.gy[2] * dy;
      f += m * (w0 * c0 + w1 * c1 + w2 * c2);
      fu += m * (top.gx[0] * c0 + top.gx[1] * c1 + top.gx[2] * c2);
      fv += m * (top.gy[0] * c0 + top.gy[1] * c1 + top.gy[2] * c2);
    }, given);
    fu *= n;
    fv *= n;
    return ok;
  }
};

Evaluator::Evaluator(const Spline& spline, EvalMode mode)
    : impl_(std::make_unique<Impl>(spline, mode)) {}
Evaluator::Evaluator(const Evaluator& other, const Spline& spline)
    : impl_(std::make_unique<Impl>(*other.impl_, spline)) {}
Evaluator::~Evaluator() = default;
Evaluator::Evaluator(Evaluator&&) noexcept = default;
Evaluator& Evaluator::operator=(Evaluator&&) noexcept = default;

int Evaluator::locate(const Point2& u) const {
  const auto loc = impl_->prepare(u);
  return loc ? loc->first : -1;
}

std::optional<Perturbation> Evaluator::perturbation(const Point2& u) const {
  const auto loc = impl_->prepare(u);
  if (!loc) return std::nullopt;
  return loc->second;
}

namespace {
[[noreturn]] void outside(const Point2& u) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "parameter point (%.17g, %.17g) is outside the domain", u.x(),
                u.y());
  throw OutsideDomain(buf);
}
}  // namespace

Point3 Evaluator::value(const Point2& u) const { return evaluate(u).position; }

SurfacePoint Evaluator::evaluate(const Point2& u) const {
  SurfacePoint r;
  if (!impl_->evaluate(u, r.position, r.du, r.dv)) outside(u);
  return r;
}

std::optional<SurfacePoint> Evaluator::evaluate(const Point2& u, const Perturbation& side) const {
  SurfacePoint r;
  if (side.u != u) throw InvalidInput("Evaluator::evaluate: the perturbation is not of u");
  if (!impl_->evaluate(u, r.position, r.du, r.dv, &side)) return std::nullopt;
  return r;
}

Vector3 Evaluator::derivative(const Point2& u, const Vector2& dir) const {
  const SurfacePoint r = evaluate(u);
  return dir.x() * r.du + dir.y() * r.dv;
}

Vector3 Evaluator::normal(const Point2& u) const {
  const SurfacePoint r = evaluate(u);
  const Vector3 c = r.du.cross(r.dv);
  const double len = c.norm();
  return len > 0 ? Vector3(c / len) : Vector3::Zero();
}

bool Evaluator::basis_row(const Point2& u, BasisRow& row) const {
  row.clear();
  struct Entry {
    int index;
    double v, du, dv;
  };
  thread_local std::vector<Entry> entries;
  entries.clear();
  const int n = impl_->n;
  const bool ok = impl_->accumulate(u, [&](const Top& top, double m) {
    const double dx = u.x() - top.x0.x(), dy = u.y() - top.x0.y();
    const double w[3] = {top.d + top.gx[0] * dx + top.gy[0] * dy, top.gx[1] * dx + top.gy[1] * dy,
                         top.gx[2] * dx + top.gy[2] * dy};
    for (int j = 0; j < 3; ++j)
      entries.push_back({top.cp[j], m * w[j], n * m * top.gx[j], n * m * top.gy[j]});
  });
  if (!ok) return false;
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.index < b.index; });
  for (const Entry& e : entries) {
    if (!row.index.empty() && row.index.back() == e.index) {
      row.value.back() += e.v;
      row.du.back() += e.du;
      row.dv.back() += e.dv;
    } else {
      row.index.push_back(e.index);
      row.value.push_back(e.v);
      row.du.push_back(e.du);
      row.dv.push_back(e.dv);
    }
  }
  return true;
}

namespace {
// Below this many points evaluate_batch keeps the caller's order (sorting would not pay).
constexpr size_t kReorderMin = 1024;
// Points sorted together: 20 bytes of order and copy each, 20 MB at most.
constexpr size_t kReorderBlock = size_t{1} << 20;
// Reorder only when there are at most this many grid cells per point.
constexpr size_t kCellsPerPoint = 64;
}  // namespace

size_t Evaluator::evaluate_batch(std::span<const Point2> u, std::span<Point3> position,
                                 std::span<Vector3> du, std::span<Vector3> dv,
                                 std::span<uint8_t> inside, int threads) const {
  const size_t count = u.size();
  auto check = [count](size_t size, const char* name) {
    if (size != 0 && size != count)
      throw InvalidInput(std::string("evaluate_batch: output '") + name + "' has " +
                         std::to_string(size) + " entries for " + std::to_string(count) +
                         " points");
  };
  check(position.size(), "position");
  check(du.size(), "du");
  check(dv.size(), "dv");
  check(inside.size(), "inside");
  std::vector<uint8_t> own;
  if (inside.empty()) {
    own.resize(count);
    inside = own;
  }
  // Points are visited grouped by the cell of the support grid they fall in (a stable
  // counting sort per block of kReorderBlock points, the points copied in that order), so
  // that consecutive points share their graph nodes in cache: in random order most of the
  // time went to fetching nodes. Each result depends on its point alone, so the order
  // changes no value.
  const detail::BoxGrid& grid = impl_->support_grid;
  // Sorting costs a pass over the grid's cells per block: skip it for a few points on a
  // large domain, where it would not pay.
  const bool reorder = count >= kReorderMin && grid.tile_key_count() / kCellsPerPoint <= count;
  std::vector<uint32_t> start, order;
  std::vector<Point2> sorted;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (size_t first = 0; first < count; first += kReorderBlock) {
    const size_t m = std::min(kReorderBlock, count - first);
    const std::span<const Point2> block = u.subspan(first, m);
    if (reorder) {
      start.assign(grid.tile_key_count() + 1, 0);
      for (const Point2& q : block) ++start[grid.tile_key(q) + 1];
      for (size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
      order.resize(m);
      sorted.resize(m);
      for (size_t i = 0; i < m; ++i) {
        const uint32_t k = start[grid.tile_key(block[i])]++;
        order[k] = static_cast<uint32_t>(i);
        sorted[k] = block[i];
      }
    }
    auto body = [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k != r.end(); ++k) {
        const size_t i = first + (reorder ? order[k] : k);
        Point3 f;
        Vector3 fu, fv;
        const bool ok = impl_->evaluate(reorder ? sorted[k] : u[i], f, fu, fv);
        if (!ok) f = fu = fv = Vector3::Constant(nan);
        inside[i] = ok ? 1 : 0;
        if (!position.empty()) position[i] = f;
        if (!du.empty()) du[i] = fu;
        if (!dv.empty()) dv[i] = fv;
      }
    };
    const tbb::blocked_range<size_t> range(0, m, 256);
    detail::with_threads(threads, [&] { tbb::parallel_for(range, body); });
  }
  return static_cast<size_t>(std::count(inside.begin(), inside.end(), 0));
}

void Evaluator::update_knots(int vertex) {
  Impl& m = *impl_;
  bool ok = true;
  for (int id : m.vertex_nodes[vertex]) ok = m.refresh_node(id) && ok;
  if (!ok) {
    m.build();
    return;
  }
  // Only the boxes of the triangles around the vertex change; the grids are built again only
  // when one of them reaches a cell its grid did not list it in (a grid that lists a triangle
  // in more cells gives the same answers).
  const Domain& d = m.s->domain();
  bool rebuild = false;
  for (int t : d.vertex_triangles(vertex)) {
    m.refresh_triangle(t);
    m.triangle_boxes(t);
    rebuild = rebuild || !m.tri_grid.covers(t, m.tri_box[t]) || !m.support_grid.covers(t, m.support[t]);
  }
  if (rebuild) m.rebuild_grids();
}

size_t Evaluator::node_count() const { return impl_->nodes.size(); }

}  // namespace tbs
