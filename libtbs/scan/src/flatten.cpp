// Flattening a disk with holes (flatten, scan_mesh.h): LSCM by our sparse solve, relaxed
// toward equal areas where it shrinks parts of the surface (SLIM on the symmetric Dirichlet
// energy, holes filled while it moves), the mean-value fallback (CGAL
// Surface_mesh_parameterization) where LSCM folds, and the distortion of the result.

#include "scan_mesh.h"

#include <tbs/errors.h>

#include "nesting_levels.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/Circular_border_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/Mean_value_coordinates_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/box_intersection_d.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Geometry>
#include <Eigen/Sparse>
#include <Eigen/SparseLU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <unordered_map>

namespace tbs::detail {

namespace {

using SM = CGAL::Surface_mesh<P3>;
using HoleVb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using HoleFb = CGAL::Constrained_triangulation_face_base_2<K>;
using HoleCdt = CGAL::Constrained_Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<HoleVb, HoleFb>>;
namespace SMP = CGAL::Surface_mesh_parameterization;

// Above this mean area distortion (area-weighted, of the map scaled to the surface's area),
// `auto` relaxes a fold-free LSCM map toward equal areas (relax_areas). Measured on
// libcgal-demo's meshes: head 35.9 and lion 21.1 gain (their largest |F_u|, |F_v| fall 3 to 4
// times, lion's folds 28 -> 6); fandisk 4.66, sphere966 2.62 and patch-20 1.35 lose (folds
// appear), docs/benchmarks.md#flattening-relaxed-toward-equal-areas-2026-12-06.
constexpr double kRelaxAbove = 10;

// A triangle's corners in a 2D frame of its plane: (0, 0), (l, 0), (x, y) with y > 0.
std::array<Eigen::Vector2d, 3> local_frame(const Point3& a, const Point3& b, const Point3& c) {
  const Vector3 e1 = b - a, e2 = c - a;
  const double l = e1.norm();
  const Vector3 ex = e1 / l;
  const Vector3 ey = e1.cross(e2).cross(e1).normalized();
  return {Eigen::Vector2d(0, 0), Eigen::Vector2d(l, 0), Eigen::Vector2d(e2.dot(ex), e2.dot(ey))};
}

double area3(const Mesh3& m, const Tri& t) {
  return 0.5 * (m.points[t[1]] - m.points[t[0]]).cross(m.points[t[2]] - m.points[t[0]]).norm();
}

// LSCM (Levy et al. 2002): the least-squares conformal energy sum_T |sum_j W_j U_j|^2 / A_T,
// W_j the edge opposite corner j as a complex number in the triangle's frame, U_j = u_j + i v_j,
// with two boundary vertices pinned. Holes need nothing special.
std::vector<P2> lscm(const Mesh3& m, int pin_a, int pin_b) {
  const int nv = static_cast<int>(m.points.size());
  const double d = (m.points[pin_a] - m.points[pin_b]).norm();
  std::vector<int> column(2 * nv, -1);
  int free = 0;
  for (int v = 0; v < nv; ++v)
    if (v != pin_a && v != pin_b) column[2 * v] = free++, column[2 * v + 1] = free++;
  auto pinned = [&](int var) { return var == 2 * pin_b ? d : 0.0; };  // a at (0, 0), b at (d, 0)
  std::vector<Eigen::Triplet<double>> trip;
  std::vector<double> rhs;
  int row = 0;
  for (const Tri& t : m.faces) {
    const double area = area3(m, t);
    if (!(area > 0)) continue;
    const auto p = local_frame(m.points[t[0]], m.points[t[1]], m.points[t[2]]);
    const double s = 1 / std::sqrt(area);
    double b_re = 0, b_im = 0;
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector2d w = (p[(j + 2) % 3] - p[(j + 1) % 3]) * s;
      const int iu = 2 * t[j], iv = iu + 1;
      // Re: a u - b v; Im: b u + a v.
      const double re[2] = {w.x(), -w.y()}, im[2] = {w.y(), w.x()};
      const int var[2] = {iu, iv};
      for (int k = 0; k < 2; ++k) {
        if (column[var[k]] >= 0) {
          trip.emplace_back(row, column[var[k]], re[k]);
          trip.emplace_back(row + 1, column[var[k]], im[k]);
        } else {
          b_re -= re[k] * pinned(var[k]);
          b_im -= im[k] * pinned(var[k]);
        }
      }
    }
    rhs.push_back(b_re);
    rhs.push_back(b_im);
    row += 2;
  }
  Eigen::SparseMatrix<double> a(row, free);
  a.setFromTriplets(trip.begin(), trip.end());
  const Eigen::Map<const Eigen::VectorXd> b(rhs.data(), row);
  const Eigen::SparseMatrix<double> n = (a.transpose() * a).eval();
  const Eigen::VectorXd r = a.transpose() * b;
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> chol;
  chol.compute(n);
  if (chol.info() != Eigen::Success) throw SolverError("LSCM: the conformal system could not be factorised");
  const Eigen::VectorXd x = chol.solve(r);
  if (chol.info() != Eigen::Success || !x.allFinite()) throw SolverError("LSCM: the conformal system could not be solved");
  std::vector<P2> uv(nv);
  for (int v = 0; v < nv; ++v)
    uv[v] = column[2 * v] >= 0 ? P2(x[column[2 * v]], x[column[2 * v + 1]]) : P2(pinned(2 * v), 0);
  return uv;
}

// Mean-value coordinates (CGAL) with the longest boundary loop on a circle; the other loops
// (holes) are filled by a fan around their centroid while solving, so the mesh is a disk, and
// the map cannot fold (positive weights, convex boundary: Tutte / Floater).
std::vector<P2> mean_value(const Mesh3& m, const std::vector<std::vector<int>>& loops, int outer) {
  SM sm;
  std::vector<SM::Vertex_index> vh;
  for (const Point3& p : m.points) vh.push_back(sm.add_vertex(P3(p.x(), p.y(), p.z())));
  for (const Tri& t : m.faces)
    if (sm.add_face(vh[t[0]], vh[t[1]], vh[t[2]]) == SM::null_face())
      throw InvalidInput("the mesh could not be built for the mean-value parameterization (non-manifold)");
  for (size_t l = 0; l < loops.size(); ++l) {
    if (int(l) == outer) continue;
    Point3 c = Point3::Zero();
    for (int v : loops[l]) c += m.points[v];
    c /= double(loops[l].size());
    const auto cv = sm.add_vertex(P3(c.x(), c.y(), c.z()));
    const auto& loop = loops[l];
    for (size_t i = 0; i < loop.size(); ++i) {
      // The boundary runs loop[i] -> loop[i+1]; the fan face takes that direction.
      const int a = loop[i], b = loop[(i + 1) % loop.size()];
      if (sm.add_face(vh[a], vh[b], cv) == SM::null_face())
        throw InvalidInput("a hole could not be filled for the mean-value parameterization");
    }
  }
  using Border = SMP::Circular_border_arc_length_parameterizer_3<SM>;
  using Solver = CGAL::Eigen_solver_traits<
      Eigen::SparseLU<CGAL::Eigen_sparse_matrix<double>::EigenType, Eigen::COLAMDOrdering<int>>>;
  using Mvc = SMP::Mean_value_coordinates_parameterizer_3<SM, Border, Solver>;
  // The outer loop's first halfedge: a border halfedge (no face) from loop[0] to loop[1].
  const auto& lo = loops[outer];
  const auto h = sm.halfedge(vh[lo[0]], vh[lo[1]]);
  if (h == SM::null_halfedge() || !sm.is_border(h))
    throw InvalidInput("the outer boundary could not be found for the mean-value parameterization");
  auto uvmap = sm.add_property_map<SM::Vertex_index, P2>("v:uv").first;
  const SMP::Error_code err = SMP::parameterize(sm, Mvc(), h, uvmap);
  if (err != SMP::OK)
    throw SolverError(std::string("mean-value parameterization failed: ") + SMP::get_error_message(err));
  std::vector<P2> uv(m.points.size());
  for (size_t v = 0; v < uv.size(); ++v) uv[v] = uvmap[vh[v]];
  return uv;
}

// Where the map folds: the number of triangles not positively oriented, and whether two
// boundary edges cross or overlap.
struct Folds {
  size_t flipped = 0;
  bool boundary_crosses = false;
  bool ok() const { return flipped == 0 && !boundary_crosses; }
  std::string describe() const {
    std::string s;
    if (flipped) s = plural(flipped, "triangle", "triangles") + " flipped";
    if (boundary_crosses) s += (s.empty() ? "" : ", ") + std::string("the boundary crosses itself");
    return s;
  }
};

Folds find_folds(const Mesh3& m, const std::vector<P2>& uv, const std::vector<std::vector<int>>& loops) {
  Folds f;
  for (const Tri& t : m.faces)
    if (CGAL::orientation(uv[t[0]], uv[t[1]], uv[t[2]]) != CGAL::LEFT_TURN) ++f.flipped;
  std::vector<std::array<int, 2>> seg;
  for (const auto& loop : loops)
    for (size_t i = 0; i < loop.size(); ++i) seg.push_back({loop[i], loop[(i + 1) % loop.size()]});
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 2, size_t>;
  std::vector<Box> boxes;
  for (size_t i = 0; i < seg.size(); ++i)
    boxes.emplace_back(uv[seg[i][0]].bbox() + uv[seg[i][1]].bbox(), i);
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& a, const Box& b) {
    if (f.boundary_crosses) return;
    const auto& s = seg[a.info()];
    const auto& t = seg[b.info()];
    int shared = -1, ps = -1, pt = -1;
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j)
        if (s[i] == t[j]) shared = s[i], ps = s[1 - i], pt = t[1 - j];
    if (shared >= 0) {
      // Adjacent edges meet at their shared vertex; they fold if they overlap.
      const P2 &o = uv[shared], &p = uv[ps], &q = uv[pt];
      if (CGAL::orientation(o, p, q) == CGAL::COLLINEAR && (p - o) * (q - o) > 0) f.boundary_crosses = true;
      return;
    }
    if (CGAL::do_intersect(K::Segment_2(uv[s[0]], uv[s[1]]), K::Segment_2(uv[t[0]], uv[t[1]])))
      f.boundary_crosses = true;
  });
  return f;
}

// Fills the holes of a flattened disk with triangles, for a map that moves: a fan around the
// hole's centroid where that fan is positive in (u, v), else the hole polygon's constrained
// Delaunay triangulation. Appends the new points and faces to `ext` and `uv`; returns the
// loops still to be checked for crossings (the outer one, and any hole left open).
std::vector<std::vector<int>> fill_holes(Mesh3& ext, std::vector<P2>& uv, const std::vector<std::vector<int>>& loops,
                                         int outer) {
  std::vector<std::vector<int>> open{loops[outer]};
  for (size_t l = 0; l < loops.size(); ++l) {
    if (int(l) == outer) continue;
    const auto& loop = loops[l];
    const size_t L = loop.size();
    Point3 c = Point3::Zero();
    double cu = 0, cv = 0;
    for (int v : loop) c += ext.points[v], cu += uv[v].x(), cv += uv[v].y();
    const P2 centre(cu / double(L), cv / double(L));
    bool star = true;
    for (size_t i = 0; i < L && star; ++i)
      star = CGAL::orientation(uv[loop[i]], uv[loop[(i + 1) % L]], centre) == CGAL::LEFT_TURN;
    if (star) {
      const int id = static_cast<int>(ext.points.size());
      ext.points.push_back(c / double(L));
      uv.push_back(centre);
      for (size_t i = 0; i < L; ++i) ext.faces.push_back({loop[i], loop[(i + 1) % L], id});
      continue;
    }
    HoleCdt cdt;
    std::vector<HoleCdt::Vertex_handle> vh;
    for (int v : loop) {
      vh.push_back(cdt.insert(uv[v]));
      vh.back()->info() = v;
    }
    for (size_t i = 0; i < L; ++i) cdt.insert_constraint(vh[i], vh[(i + 1) % L]);
    // Inside the polygon: level 1 (every constraint is an edge of the loop).
    const auto level = detail::nesting_levels(cdt, [](HoleCdt::Vertex_handle, HoleCdt::Vertex_handle) { return true; });
    std::vector<Tri> fill;
    bool simple = cdt.number_of_vertices() == L;  // no two loop vertices at one (u, v)
    for (auto f = cdt.finite_faces_begin(); simple && f != cdt.finite_faces_end(); ++f)
      if (level.at(f) == 1) fill.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
    if (simple && fill.size() + 2 == L)
      ext.faces.insert(ext.faces.end(), fill.begin(), fill.end());
    else
      open.push_back(loop);
  }
  return open;
}

// Relaxes a fold-free flattening toward equal areas, keeping it fold-free. SLIM (Rabinovich
// et al. 2017) on the symmetric Dirichlet energy sum_T A_T (|J_T|^2 + |J_T^-1|^2), J_T the map
// of triangle T from its rest shape: infinite where a triangle degenerates, so no step flips
// one. The rest shape of each triangle is its 3D shape scaled by sqrt(r_T), r_T its area in the
// starting map over its 3D area (the map scaled to the surface's area): half of the way, on a
// log scale, from the start's areas to the surface's. The starting map's angles are largely
// kept and its largest area ratios fall to about their square root. Each step solves a
// weighted least-squares problem toward the nearest rotations (the u and v of every vertex
// together; `pin` keeps its place), then moves as far as keeps every triangle positive and the
// boundary free of crossings and lowers the energy. Holes are filled while it moves
// (fill_holes, the fill weighing a hundredth), so they cannot close or cross.
std::vector<P2> relax_areas(const Mesh3& m, const std::vector<P2>& start, const std::vector<std::vector<int>>& loops,
                            int outer, int pin, const std::function<void(const std::string&)>& say) {
  constexpr double kFillWeight = 0.01;
  constexpr int kMaxSteps = 100;
  constexpr double kStall = 1e-5;  // stop when a step lowers the energy by less (relative)
  Mesh3 ext = m;
  std::vector<P2> uv = start;
  const auto open = fill_holes(ext, uv, loops, outer);
  const int nv = static_cast<int>(ext.points.size());
  struct Face {
    Tri t;
    double weight;                  // 3D area (times kFillWeight for the fill)
    Eigen::Matrix<double, 2, 3> d;  // the gradient of a function of the corners on the rest shape
  };
  std::vector<Face> faces;
  double a3 = 0, a2 = 0;
  for (const Tri& t : m.faces) a3 += area3(m, t), a2 += std::fabs(CGAL::area(uv[t[0]], uv[t[1]], uv[t[2]]));
  if (!(a3 > 0) || !(a2 > 0)) return start;
  const double scale = std::sqrt(a3 / a2);
  for (P2& p : uv) p = P2(scale * p.x(), scale * p.y());
  for (size_t fi = 0; fi < ext.faces.size(); ++fi) {
    const Tri& t = ext.faces[fi];
    const double area = area3(ext, t);
    if (!(area > 0)) continue;
    const auto p = local_frame(ext.points[t[0]], ext.points[t[1]], ext.points[t[2]]);
    Eigen::Matrix2d ps;
    ps << p[1] - p[0], p[2] - p[0];
    const Eigen::Matrix2d pinv = ps.inverse();
    Eigen::Matrix<double, 2, 3> d;
    for (int k = 0; k < 2; ++k) d.row(k) << -(pinv(0, k) + pinv(1, k)), pinv(0, k), pinv(1, k);
    const bool fill = fi >= m.faces.size();
    if (!fill) {
      const double ratio = std::fabs(CGAL::area(uv[t[0]], uv[t[1]], uv[t[2]])) / area;
      if (ratio > 0) d /= std::pow(ratio, 0.25);  // rest edges times ratio^(1/4): areas times sqrt(ratio)
    }
    faces.push_back({t, fill ? kFillWeight * area : area, d});
  }
  using Vec = Eigen::VectorXd;
  auto jacobian = [](const Face& f, const Vec& x) {
    Eigen::Matrix2d j;
    for (int c = 0; c < 2; ++c)
      for (int k = 0; k < 2; ++k)
        j(c, k) = f.d(k, 0) * x[2 * f.t[0] + c] + f.d(k, 1) * x[2 * f.t[1] + c] + f.d(k, 2) * x[2 * f.t[2] + c];
    return j;
  };
  auto energy = [&](const Vec& x) {
    double e = 0;
    for (const Face& f : faces) {
      const Eigen::Matrix2d j = jacobian(f, x);
      const double det = j.determinant();
      if (!(det > 0)) return std::numeric_limits<double>::infinity();
      e += f.weight * j.squaredNorm() * (1 + 1 / (det * det));  // |J^-1|^2 = |J|^2 / det^2 in 2D
    }
    return e;
  };
  auto to_uv = [](const Vec& x, size_t count) {
    std::vector<P2> r(count);
    for (size_t v = 0; v < count; ++v) r[v] = P2(x[2 * v], x[2 * v + 1]);
    return r;
  };
  Vec x(2 * nv);
  for (int v = 0; v < nv; ++v) x[2 * v] = uv[v].x(), x[2 * v + 1] = uv[v].y();
  double e = energy(x);
  if (!std::isfinite(e)) return start;
  std::vector<int> column(2 * nv, -1);
  int unknowns = 0;
  for (int v = 0; v < 2 * nv; ++v)
    if (v / 2 != pin) column[v] = unknowns++;
  const int rows = 4 * static_cast<int>(faces.size());
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> chol;
  std::vector<Eigen::Triplet<double>> trip;
  Vec b(rows);
  int taken = 0;
  auto last_said = std::chrono::steady_clock::now();
  for (int step = 0; step < kMaxSteps; ++step) {
    if (say && std::chrono::steady_clock::now() - last_said > std::chrono::seconds(2)) {
      say("relaxing toward equal areas: step " + std::to_string(step + 1) + " of at most " + std::to_string(kMaxSteps));
      last_said = std::chrono::steady_clock::now();
    }
    // Local step: per triangle the nearest rotation R and the weight W = U diag(w) U^T with
    // w = sqrt(f'(s) / (2 (s - 1))) for f(s) = s^2 + s^-2, that is sqrt((s + 1)(s^2 + 1) / s^3).
    // Global step: min sum_T weight_T |W_T (J_T - R_T)|^2, rows (i, k) of each triangle.
    trip.clear();
    for (size_t fi = 0; fi < faces.size(); ++fi) {
      const Face& f = faces[fi];
      const Eigen::JacobiSVD<Eigen::Matrix2d> svd(jacobian(f, x), Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Eigen::Matrix2d u = svd.matrixU();
      Eigen::Vector2d w;
      for (int i = 0; i < 2; ++i) {
        const double sv = std::max(svd.singularValues()[i], 1e-8);
        w[i] = std::sqrt((sv + 1) * (sv * sv + 1) / (sv * sv * sv));
      }
      const Eigen::Matrix2d wm = u * w.asDiagonal() * u.transpose();
      const Eigen::Matrix2d target = wm * u * svd.matrixV().transpose();
      const double sw = std::sqrt(f.weight);
      for (int i = 0; i < 2; ++i)
        for (int k = 0; k < 2; ++k) {
          const int row = static_cast<int>(4 * fi + 2 * i + k);
          double rhs = sw * target(i, k);
          for (int c = 0; c < 2; ++c)
            for (int j = 0; j < 3; ++j) {
              const double coef = sw * wm(i, c) * f.d(k, j);
              const int var = 2 * f.t[j] + c;
              if (column[var] >= 0)
                trip.emplace_back(row, column[var], coef);
              else
                rhs -= coef * x[var];
            }
          b[row] = rhs;
        }
    }
    Eigen::SparseMatrix<double> a(rows, unknowns);
    a.setFromTriplets(trip.begin(), trip.end());
    const Eigen::SparseMatrix<double> at = a.transpose();
    const Eigen::SparseMatrix<double> n = (at * a).eval();
    if (taken == 0) chol.analyzePattern(n);
    chol.factorize(n);
    if (chol.info() != Eigen::Success) break;
    const Vec sol = chol.solve(at * b);
    if (chol.info() != Eigen::Success || !sol.allFinite()) break;
    Vec dir = Vec::Zero(2 * nv);
    for (int v = 0; v < 2 * nv; ++v)
      if (column[v] >= 0) dir[v] = sol[column[v]] - x[v];
    // The first step length tried: 0.9 times the largest that keeps every triangle positive,
    // the smallest positive root of det(J + t D) = det J + t c1 + t^2 det D.
    double t = 1;
    for (const Face& f : faces) {
      const Eigen::Matrix2d j = jacobian(f, x), dj = jacobian(f, dir);
      const double c0 = j.determinant(), c2 = dj.determinant();
      const double c1 = j(0, 0) * dj(1, 1) + dj(0, 0) * j(1, 1) - j(0, 1) * dj(1, 0) - dj(0, 1) * j(1, 0);
      double root = std::numeric_limits<double>::infinity();
      if (c2 == 0) {
        if (c1 < 0) root = -c0 / c1;
      } else if (const double disc = c1 * c1 - 4 * c2 * c0; disc >= 0) {
        const double sq = std::sqrt(disc);
        for (const double r : {(-c1 - sq) / (2 * c2), (-c1 + sq) / (2 * c2)})
          if (r > 0) root = std::min(root, r);
      }
      t = std::min(t, 0.9 * root);
    }
    bool moved = false;
    double gain = 0;
    for (int tries = 0; tries < 30 && !moved; ++tries, t *= 0.5) {
      const Vec y = x + t * dir;
      const double ey = energy(y);
      if (!(ey < e)) continue;
      if (!find_folds(ext, to_uv(y, ext.points.size()), open).ok()) continue;
      gain = (e - ey) / e;
      x = y, e = ey, moved = true;
      ++taken;
    }
    if (!moved || gain < kStall) break;
  }
  if (say) say("relaxed toward equal areas in " + plural(static_cast<size_t>(taken), "step", "steps"));
  return to_uv(x, m.points.size());
}

}  // namespace

// Scales the parameters to the surface's area, turns them to their principal axes (a rotation,
// so orientation is kept) and moves their box to the origin.
void normalise(const Mesh3& m, std::vector<P2>& uv) {
  double a3 = 0, a2 = 0;
  for (const Tri& t : m.faces) {
    a3 += area3(m, t);
    a2 += std::fabs(CGAL::area(uv[t[0]], uv[t[1]], uv[t[2]]));
  }
  const double s = a2 > 0 ? std::sqrt(a3 / a2) : 1.0;
  Eigen::Vector2d mean(0, 0);
  for (const P2& p : uv) mean += Eigen::Vector2d(p.x(), p.y());
  mean /= double(uv.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const P2& p : uv) {
    const Eigen::Vector2d d = Eigen::Vector2d(p.x(), p.y()) - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  Eigen::Vector2d ax = eig.eigenvectors().col(1);  // the largest spread along u
  if (ax.x() < 0) ax = -ax;
  const Eigen::Vector2d ay(-ax.y(), ax.x());
  double umin = 1e300, vmin = 1e300;
  std::vector<Eigen::Vector2d> q(uv.size());
  for (size_t i = 0; i < uv.size(); ++i) {
    const Eigen::Vector2d d = Eigen::Vector2d(uv[i].x(), uv[i].y()) - mean;
    q[i] = s * Eigen::Vector2d(d.dot(ax), d.dot(ay));
    umin = std::min(umin, q[i].x());
    vmin = std::min(vmin, q[i].y());
  }
  for (size_t i = 0; i < uv.size(); ++i) uv[i] = P2(q[i].x() - umin, q[i].y() - vmin);
}

Distortion distortion(const Mesh3& m, const std::vector<P2>& uv) {
  Distortion d;
  double wsum = 0, angle = 0, area = 0;
  d.angle_max = d.area_max = 1;
  for (const Tri& t : m.faces) {
    const double w = area3(m, t);
    if (!(w > 0)) continue;
    const auto p = local_frame(m.points[t[0]], m.points[t[1]], m.points[t[2]]);
    Eigen::Matrix2d ps, qs;
    ps << p[1] - p[0], p[2] - p[0];
    qs << uv[t[1]].x() - uv[t[0]].x(), uv[t[2]].x() - uv[t[0]].x(), uv[t[1]].y() - uv[t[0]].y(),
        uv[t[2]].y() - uv[t[0]].y();
    const Eigen::Matrix2d j = qs * ps.inverse();
    const Eigen::Vector2d sv = Eigen::JacobiSVD<Eigen::Matrix2d>(j).singularValues();
    const double a = sv[1] > 0 ? sv[0] / sv[1] : std::numeric_limits<double>::infinity();
    const double r = sv[0] * sv[1] > 0 ? std::max(sv[0] * sv[1], 1 / (sv[0] * sv[1])) : std::numeric_limits<double>::infinity();
    angle += w * a;
    area += w * r;
    wsum += w;
    d.angle_max = std::max(d.angle_max, a);
    d.area_max = std::max(d.area_max, r);
  }
  if (wsum > 0) d.angle_mean = angle / wsum, d.area_mean = area / wsum;
  return d;
}

// Flattens a disk with holes; tries LSCM first unless told otherwise.


// Flattens a disk with holes; tries LSCM first unless told otherwise.
std::vector<P2> flatten(const Mesh3& m, const ParameterizeOptions& o, ParameterizeReport& rep) {
  const auto loops = boundary_loops(m.faces);
  if (loops.empty()) throw InvalidInput("the surface has no boundary to flatten");
  auto loop_length = [&](const std::vector<int>& l) {
    double len = 0;
    for (size_t i = 0; i < l.size(); ++i) len += (m.points[l[(i + 1) % l.size()]] - m.points[l[i]]).norm();
    return len;
  };
  int outer = 0;
  for (size_t l = 1; l < loops.size(); ++l)
    if (loop_length(loops[l]) > loop_length(loops[outer])) outer = int(l);
  auto say = [&](const std::string& s) {
    if (o.progress) o.progress(s);
  };
  std::vector<P2> uv;
  if (o.method != FlattenMethod::MeanValue) {
    // Pins: two far apart vertices of the outer boundary.
    const auto& lo = loops[outer];
    int a = lo[0], b = lo[0];
    for (int v : lo)
      if ((m.points[v] - m.points[lo[0]]).squaredNorm() > (m.points[a] - m.points[lo[0]]).squaredNorm()) a = v;
    for (int v : lo)
      if ((m.points[v] - m.points[a]).squaredNorm() > (m.points[b] - m.points[a]).squaredNorm()) b = v;
    if (a == b) throw InvalidInput("the surface's boundary has no extent");
    say("flattening " + plural(m.faces.size(), "triangle", "triangles") + " (LSCM)");
    try {
      uv = lscm(m, a, b);
    } catch (const SolverError& e) {
      if (o.method == FlattenMethod::Lscm) throw;
      uv.clear();
      rep.fallback_reason = std::string("LSCM could not be solved: ") + e.what();
    }
    Folds f = uv.empty() ? Folds{} : find_folds(m, uv, loops);
    if (f.flipped > m.faces.size() / 2) {  // a mirror image: LSCM keeps orientation, so only if
      for (P2& p : uv) p = P2(p.x(), -p.y());  // the pins made it so; flip back
      f = find_folds(m, uv, loops);
    }
    if (!uv.empty() && f.ok()) {
      rep.method = "LSCM";
      if (o.method == FlattenMethod::Auto) {
        // A conformal map shrinks a part of a surface that bulges away from its boundary
        // exponentially (a near-closed surface opened at one small loop): relaxed toward equal
        // areas where the mean area distortion exceeds kRelaxAbove.
        std::vector<P2> scaled = uv;
        normalise(m, scaled);
        const Distortion conformal = distortion(m, scaled);
        if (conformal.area_mean > kRelaxAbove) {
          char text[160];
          std::snprintf(text, sizeof text, "LSCM shrinks parts of the surface (area distortion %.3g mean, %.3g max); "
                        "relaxing it toward equal areas", conformal.area_mean, conformal.area_max);
          say(text);
          std::vector<P2> relaxed = relax_areas(m, uv, loops, outer, a, o.progress);
          if (find_folds(m, relaxed, loops).ok()) {
            rep.method = "LSCM, areas relaxed";
            rep.conformal = conformal;
            return relaxed;
          }
        }
      }
      return uv;
    }
    if (!uv.empty()) rep.fallback_reason = "LSCM folds: " + f.describe();
    if (o.method == FlattenMethod::Lscm)
      throw InvalidInput("the LSCM parameterization folds (" + f.describe() + "); use the default method, which falls back to mean-value coordinates");
    say(rep.fallback_reason + "; using mean-value coordinates with a circular boundary");
  } else {
    say("flattening " + plural(m.faces.size(), "triangle", "triangles") + " (mean-value coordinates)");
  }
  uv = mean_value(m, loops, outer);
  const Folds f = find_folds(m, uv, loops);
  if (!f.ok())
    throw InvalidInput("no bijective parameterization found: the mean-value map folds too (" + f.describe() +
                       "); repair the mesh (e.g. remove slivers, fill holes) or cut it into simpler pieces and retry");
  rep.method = "mean value (circular boundary)";
  return uv;
}

}  // namespace tbs::detail
