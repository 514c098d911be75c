#include <tbs/bezier.h>

#include <cassert>

namespace tbs {

namespace {

// One de Casteljau step: degree k -> k-1 in place (the first beta_count(k-1) entries).
void casteljau_step(std::vector<Point3>& w, int k, const Bary& b) {
  for (int i = 0; i < beta_count(k - 1); ++i) {
    const Beta g = beta_at(k - 1, i);
    w[i] = b[0] * w[beta_index({g[0] + 1, g[1], g[2]})] +
           b[1] * w[beta_index({g[0], g[1] + 1, g[2]})] +
           b[2] * w[beta_index({g[0], g[1], g[2] + 1})];
  }
}

}  // namespace

Point3 bezier_value(std::span<const Point3> net, int m, const Bary& b) {
  assert(static_cast<int>(net.size()) == beta_count(m));
  thread_local std::vector<Point3> w;
  w.assign(net.begin(), net.end());
  for (int k = m; k > 0; --k) casteljau_step(w, k, b);
  return w[0];
}

void bezier_derivatives(std::span<const Point3> net, int m, const Bary& b, Point3& value,
                        Vector3& d01, Vector3& d02) {
  assert(static_cast<int>(net.size()) == beta_count(m));
  if (m == 0) {
    value = net[0];
    d01.setZero();
    d02.setZero();
    return;
  }
  thread_local std::vector<Point3> w;
  w.assign(net.begin(), net.end());
  for (int k = m; k > 1; --k) casteljau_step(w, k, b);
  // The degree-1 net (1,0,0), (0,1,0), (0,0,1) sits at indices 0, 1, 2.
  value = b[0] * w[0] + b[1] * w[1] + b[2] * w[2];
  d01 = m * (w[1] - w[0]);
  d02 = m * (w[2] - w[0]);
}

void bernstein_triangle(int m, const Bary& b, std::span<double> out) {
  assert(static_cast<int>(out.size()) == beta_count(m));
  // B_beta = m! / (b0! b1! b2!) l0^b0 l1^b1 l2^b2, built by the recurrence on degree.
  std::vector<double> cur(1, 1.0), next;
  for (int k = 1; k <= m; ++k) {
    next.assign(beta_count(k), 0.0);
    for (int i = 0; i < beta_count(k - 1); ++i) {
      const Beta g = beta_at(k - 1, i);
      next[beta_index({g[0] + 1, g[1], g[2]})] += b[0] * cur[i];
      next[beta_index({g[0], g[1] + 1, g[2]})] += b[1] * cur[i];
      next[beta_index({g[0], g[1], g[2] + 1})] += b[2] * cur[i];
    }
    cur.swap(next);
  }
  std::copy(cur.begin(), cur.end(), out.begin());
}

Point3 bezier_curve_value(std::span<const Point3> cps, double t) {
  thread_local std::vector<Point3> w;
  w.assign(cps.begin(), cps.end());
  for (size_t k = w.size(); k > 1; --k)
    for (size_t i = 0; i + 1 < k; ++i) w[i] = (1 - t) * w[i] + t * w[i + 1];
  return w[0];
}

std::vector<Point3> bezier_curve_restrict(std::span<const Point3> cps, double t0, double t1) {
  // The blossom of the curve: control point j of the restriction is
  // blossom(t0 (m-j times), t1 (j times)).
  const int m = static_cast<int>(cps.size()) - 1;
  std::vector<Point3> out(cps.size());
  std::vector<Point3> w;
  for (int j = 0; j <= m; ++j) {
    w.assign(cps.begin(), cps.end());
    for (int k = 0; k < m; ++k) {
      const double t = k < m - j ? t0 : t1;
      for (int i = 0; i + 1 < m + 1 - k; ++i) w[i] = (1 - t) * w[i] + t * w[i + 1];
    }
    out[j] = w[0];
  }
  // Exact endpoints where the interval reaches the curve's ends.
  if (t0 == 0) out.front() = cps.front();
  if (t0 == 1) out.front() = cps.back();
  if (t1 == 1) out.back() = cps.back();
  if (t1 == 0) out.back() = cps.front();
  return out;
}

void bernstein_curve(int m, double t, std::span<double> out) {
  assert(static_cast<int>(out.size()) == m + 1);
  out[0] = 1;
  for (int k = 1; k <= m; ++k) {
    out[k] = t * out[k - 1];
    for (int i = k - 1; i > 0; --i) out[i] = (1 - t) * out[i] + t * out[i - 1];
    out[0] *= 1 - t;
  }
}

std::vector<int> bezier_side_indices(int m, int k) {
  std::vector<int> idx(m + 1);
  const int a = (k + 1) % 3, c = (k + 2) % 3;
  for (int i = 0; i <= m; ++i) {
    Beta b{0, 0, 0};
    b[a] = m - i;
    b[c] = i;
    idx[i] = beta_index(b);
  }
  return idx;
}

std::vector<Point3> bezier_side(std::span<const Point3> net, int m, int k) {
  std::vector<Point3> out;
  for (int i : bezier_side_indices(m, k)) out.push_back(net[i]);
  return out;
}

namespace {

// The blossom of a triangular patch at m barycentric arguments: de Casteljau with a
// different point per step.
Point3 triangle_blossom(std::span<const Point3> net, int m, std::span<const Bary> args) {
  std::vector<Point3> w(net.begin(), net.end());
  for (int k = m; k > 0; --k) casteljau_step(w, k, args[m - k]);
  return w[0];
}

double binomial(int n, int k) {
  if (k < 0 || k > n) return 0;
  double r = 1;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

}  // namespace

std::vector<Point3> bezier_bilinear_compose(std::span<const Point3> net, int m, const Bary& b00,
                                            const Bary& b10, const Bary& b01, const Bary& b11) {
  // The bi-blossom of F(B(s, t)) is the blossom of F at the pairs (s_a, t_b) averaged over all
  // pairings; at s = 0^(m-i) 1^i, t = 0^(m-j) 1^j a pairing is fixed by the number k of
  // (1, 1) pairs, which has the hypergeometric weight C(i,k) C(m-i, j-k) / C(m, j).
  std::vector<Point3> out(static_cast<size_t>((m + 1) * (m + 1)));
  std::vector<Bary> args(m);
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i <= m; ++i) {
      Point3 c = Point3::Zero();
      const double total = binomial(m, j);
      for (int k = std::max(0, i + j - m); k <= std::min(i, j); ++k) {
        const double w = binomial(i, k) * binomial(m - i, j - k) / total;
        int a = 0;
        for (int q = 0; q < k; ++q) args[a++] = b11;
        for (int q = 0; q < i - k; ++q) args[a++] = b10;
        for (int q = 0; q < j - k; ++q) args[a++] = b01;
        for (int q = 0; q < m - i - j + k; ++q) args[a++] = b00;
        c += w * triangle_blossom(net, m, args);
      }
      out[static_cast<size_t>(i + (m + 1) * j)] = c;
    }
  return out;
}

std::array<std::vector<Point3>, 3> bezier_triangle_to_quads(std::span<const Point3> net, int m) {
  const Bary e[3] = {Bary(1, 0, 0), Bary(0, 1, 0), Bary(0, 0, 1)};
  const Bary centre = Bary(1, 1, 1) / 3.0;
  std::array<std::vector<Point3>, 3> out;
  for (int k = 0; k < 3; ++k) {
    const Bary& a = e[k];
    const Bary next = (e[k] + e[(k + 1) % 3]) / 2, prev = (e[k] + e[(k + 2) % 3]) / 2;
    out[k] = bezier_bilinear_compose(net, m, a, next, prev, centre);
  }
  return out;
}

std::vector<Point3> bezier_triangle_to_collapsed_quad(std::span<const Point3> net, int m) {
  return bezier_bilinear_compose(net, m, Bary(1, 0, 0), Bary(0, 1, 0), Bary(1, 0, 0), Bary(0, 0, 1));
}

Point3 bezier_tensor_value(std::span<const Point3> cps, int m, double s, double t) {
  std::vector<Point3> row(m + 1);
  for (int j = 0; j <= m; ++j)
    row[j] = bezier_curve_value(cps.subspan(static_cast<size_t>((m + 1) * j), m + 1), s);
  return bezier_curve_value(row, t);
}

}  // namespace tbs
