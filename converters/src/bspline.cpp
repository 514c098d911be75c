// Clamped B-spline curves and tensor-product surfaces: basis functions and evaluation.

#include "bspline_basis.h"

#include <tbs/cad_regions.h>

#include <algorithm>

namespace tbs {

namespace detail {

int find_span(std::span<const double> knots, int p, double t) {
  const int n = static_cast<int>(knots.size()) - p - 1;  // number of basis functions
  if (t >= knots[static_cast<size_t>(n)]) return n - 1;
  if (t <= knots[static_cast<size_t>(p)]) return p;
  const auto it = std::upper_bound(knots.begin() + p, knots.begin() + n + 1, t);
  return static_cast<int>(it - knots.begin()) - 1;
}

namespace {

// Given the q values (or derivatives) of the degree q-1 functions that are non-zero on span s
// (functions s-q+1 .. s), the derivative combination for the degree-q functions s-q .. s:
//   D N_{i,q} = q (D' N_{i,q-1} / (U_{i+q} - U_i) - D' N_{i+1,q-1} / (U_{i+q+1} - U_{i+1})),
// where a zero-length denominator drops its term.
void raise_derivative(std::span<const double> U, int q, int s, const double* lower, double* out) {
  for (int j = 0; j <= q; ++j) {
    const int i = s - q + j;
    double v = 0;
    if (j >= 1) {
      const double d = U[static_cast<size_t>(i + q)] - U[static_cast<size_t>(i)];
      if (d > 0) v += lower[j - 1] / d;
    }
    if (j <= q - 1) {
      const double d = U[static_cast<size_t>(i + q + 1)] - U[static_cast<size_t>(i + 1)];
      if (d > 0) v -= lower[j] / d;
    }
    out[j] = q * v;
  }
}

}  // namespace

void basis_functions(std::span<const double> U, int p, int s, double t, int derivatives, Basis& b) {
  // table[q][j]: the degree-q function s-q+j at t (Cox-de Boor, one degree at a time).
  double table[kMaxBasisDegree + 1][kMaxBasisDegree + 1];
  table[0][0] = 1;
  for (int q = 1; q <= p; ++q) {
    for (int j = 0; j <= q; ++j) {
      const int i = s - q + j;
      double v = 0;
      if (j >= 1) {
        const double d = U[static_cast<size_t>(i + q)] - U[static_cast<size_t>(i)];
        if (d > 0) v += (t - U[static_cast<size_t>(i)]) / d * table[q - 1][j - 1];
      }
      if (j <= q - 1) {
        const double d = U[static_cast<size_t>(i + q + 1)] - U[static_cast<size_t>(i + 1)];
        if (d > 0) v += (U[static_cast<size_t>(i + q + 1)] - t) / d * table[q - 1][j];
      }
      table[q][j] = v;
    }
  }
  std::copy(table[p], table[p] + p + 1, b.value);
  if (derivatives >= 1) {
    if (p >= 1) {
      raise_derivative(U, p, s, table[p - 1], b.d1);
    } else {
      std::fill(b.d1, b.d1 + 1, 0.0);
    }
  }
  if (derivatives >= 2) {
    if (p >= 2) {
      double mid[kMaxBasisDegree + 1];
      raise_derivative(U, p - 1, s, table[p - 2], mid);
      raise_derivative(U, p, s, mid, b.d2);
    } else {
      std::fill(b.d2, b.d2 + p + 1, 0.0);
    }
  }
}

std::vector<double> clamped_knots(int p, std::span<const double> breaks) {
  std::vector<double> k;
  k.reserve(breaks.size() + 2 * static_cast<size_t>(p));
  for (int i = 0; i < p; ++i) k.push_back(breaks.front());
  k.insert(k.end(), breaks.begin(), breaks.end());
  for (int i = 0; i < p; ++i) k.push_back(breaks.back());
  return k;
}

}  // namespace detail

Point3 BSplineCurve3::value(double t) const {
  const int s = detail::find_span(knots, degree, t);
  detail::Basis b;
  detail::basis_functions(knots, degree, s, std::clamp(t, knots.front(), knots.back()), 0, b);
  Point3 r = Point3::Zero();
  for (int j = 0; j <= degree; ++j) r += b.value[j] * poles[static_cast<size_t>(s - degree + j)];
  return r;
}

void BSplineSurface3::evaluate(const Point2& uv, Point3& value, Vector3& du, Vector3& dv) const {
  const double u = std::clamp(uv.x(), knots_u.front(), knots_u.back());
  const double v = std::clamp(uv.y(), knots_v.front(), knots_v.back());
  const int su = detail::find_span(knots_u, degree_u, u), sv = detail::find_span(knots_v, degree_v, v);
  detail::Basis bu, bv;
  detail::basis_functions(knots_u, degree_u, su, u, 1, bu);
  detail::basis_functions(knots_v, degree_v, sv, v, 1, bv);
  const int nu = pole_count_u();
  value.setZero();
  du.setZero();
  dv.setZero();
  for (int b = 0; b <= degree_v; ++b) {
    Point3 row = Point3::Zero(), row_u = Point3::Zero();
    for (int a = 0; a <= degree_u; ++a) {
      const Point3& p = poles[static_cast<size_t>(su - degree_u + a + nu * (sv - degree_v + b))];
      row += bu.value[a] * p;
      row_u += bu.d1[a] * p;
    }
    value += bv.value[b] * row;
    du += bv.value[b] * row_u;
    dv += bv.d1[b] * row;
  }
}

Point3 BSplineSurface3::value(const Point2& uv) const {
  Point3 p;
  Vector3 du, dv;
  evaluate(uv, p, du, dv);
  return p;
}

}  // namespace tbs
