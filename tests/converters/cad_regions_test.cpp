// Region faces: the decomposition into smooth regions, the trims, and every face within the
// tolerance of the spline, checked at points the fit never saw.
#include <tbs/cad_regions.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/knots.h>

#include "random_spline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

namespace tbs {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A 40 x 40 sheet over an 8 x 8 grid: smooth, with a crease along the grid column x = 1/4
// (feature edges, C^0) and a square hole, as a scan of a bent plate has. The control points
// sample z(u) at the blossom points, so the spline follows the height field.
// With `bend`, the crease's vertices move across it by 2^-24, alternately left and right: the
// chain then bends by about 5e-7 radians at each vertex, as a crease found in a scan whose
// parameters are floats does, and a vertex's sub-knots (on one of its two feature edges) miss
// the other edge by about 1e-8.
Spline sheet(int degree, bool hole, int feature_column, uint64_t seed = 3, bool bend = false) {
  test::GridOptions o;
  o.nx = o.ny = 8;
  o.hole = hole;
  o.feature_column = feature_column;
  Domain d = test::grid_domain(o, seed);
  if (bend) {
    std::vector<Point2> v = d.vertices();
    std::vector<char> moved(v.size(), 0);
    for (const auto& e : d.feature_edges())
      for (int k : e)
        if (!moved[static_cast<size_t>(k)]) {
          moved[static_cast<size_t>(k)] = 1;
          const int row = static_cast<int>(std::lround(v[static_cast<size_t>(k)].y() * 8));
          v[static_cast<size_t>(k)].x() += (row % 2 ? 1 : -1) * std::ldexp(1.0, -24);
        }
    d = Domain(v, d.triangles(), d.feature_edges());
  }
  Spline s = Spline::with_canonical_map(degree, d, default_knots(d, degree));
  const double crease = feature_column > 0 ? feature_column / 8.0 : -1;
  for (int t = 0; t < d.triangle_count(); ++t)
    for (int i = 0; i < beta_count(degree); ++i) {
      const Point2 b = s.blossom_point(t, beta_at(degree, i));
      double z = 4 * std::sin(3 * b.x()) * std::cos(2 * b.y());
      if (crease > 0) z += 10 * std::fabs(b.x() - crease);
      s.control_points()[static_cast<size_t>(s.control_point_index(t, i))] = Point3(40 * b.x(), 40 * b.y(), z);
    }
  return s;
}

// The same sheet with its crease only on the lower half: it ends inside the surface, and fades
// out above its end (smoothly, but the fading kink is a narrow band of strong curvature).
Spline sheet_with_crease_ending_inside(int degree) {
  const Spline full = sheet(degree, false, 2);
  const Domain& fd = full.domain();
  std::vector<std::array<int, 2>> lower;
  double tip = 0;
  for (const auto& e : fd.feature_edges()) {
    const double top = std::max(fd.vertex(e[0]).y(), fd.vertex(e[1]).y());
    if (top <= 0.5) {
      lower.push_back(e);
      tip = std::max(tip, top);
    }
  }
  EXPECT_GE(lower.size(), 2u);
  const Domain d(fd.vertices(), fd.triangles(), lower);
  Spline s = Spline::with_canonical_map(degree, d, default_knots(d, degree));
  for (int t = 0; t < d.triangle_count(); ++t)
    for (int i = 0; i < beta_count(degree); ++i) {
      const Point2 b = s.blossom_point(t, beta_at(degree, i));
      const double fade = 1 / (1 + std::exp((b.y() - tip - 0.15) / 0.05));
      const double z = 4 * std::sin(3 * b.x()) * std::cos(2 * b.y()) + 10 * std::fabs(b.x() - 0.25) * fade;
      s.control_points()[static_cast<size_t>(s.control_point_index(t, i))] = Point3(40 * b.x(), 40 * b.y(), z);
    }
  return s;
}

// Random parameter points inside a face's triangles.
std::vector<std::pair<int, Point2>> points_in_faces(const Spline& s, const CadRegions& r, int per_triangle) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uni(0, 1);
  std::vector<std::pair<int, Point2>> out;
  for (size_t f = 0; f < r.faces.size(); ++f)
    for (int t : r.faces[f].triangles) {
      const auto& c = s.domain().triangle(t);
      for (int k = 0; k < per_triangle; ++k) {
        double a = uni(rng), b = uni(rng);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        const Point2 u = s.domain().vertex(c[0]) + a * (s.domain().vertex(c[1]) - s.domain().vertex(c[0])) +
                         b * (s.domain().vertex(c[2]) - s.domain().vertex(c[0]));
        out.emplace_back(static_cast<int>(f), u);
      }
    }
  return out;
}

// Every face within the tolerance of the spline at points the fit did not use.
void expect_within_tolerance(const Spline& s, const CadRegions& r) {
  const Evaluator ev(s);
  double worst = 0;
  for (const auto& [f, u] : points_in_faces(s, r, 40))
    worst = std::max(worst, (r.faces[static_cast<size_t>(f)].surface.value(u) - ev.value(u)).norm());
  EXPECT_LE(worst, r.tolerance) << "largest distance face - spline at random points";
  EXPECT_LE(r.max_position_deviation, r.tolerance);
  // An edge's gap: the face's deviation plus its 3D curve's (a quarter of the tolerance).
  EXPECT_LE(r.max_gap, 1.25 * r.tolerance);
}

TEST(BSplineBasis, SurfaceDerivativesMatchCentralDifferences) {
  const Spline s = sheet(3, true, 2);
  const CadRegions r = make_cad_regions(s, {.tolerance = 1e-4});
  const BSplineSurface3& f = r.faces[0].surface;
  const double h = 1e-6;
  for (const Point2& u : {Point2(0.1, 0.2), Point2(0.2, 0.9), Point2(0.05, 0.5)}) {
    Point3 p;
    Vector3 du, dv;
    f.evaluate(u, p, du, dv);
    const Vector3 fu = (f.value(u + Point2(h, 0)) - f.value(u - Point2(h, 0))) / (2 * h);
    const Vector3 fv = (f.value(u + Point2(0, h)) - f.value(u - Point2(0, h))) / (2 * h);
    EXPECT_LE((du - fu).norm(), 1e-5 * du.norm());
    EXPECT_LE((dv - fv).norm(), 1e-5 * dv.norm());
  }
}

TEST(CadRegions, CreasedAndHoledSheetIsOneFacePerFlankWithTheCreaseAsOneEdge) {
  const Spline s = sheet(3, true, 2);
  ASSERT_EQ(s.domain().boundary_loops().size(), 2u);  // outer + hole
  const CadRegions r = make_cad_regions(s, {.tolerance = 1e-4});
  EXPECT_EQ(r.smooth_regions, 2);
  ASSERT_EQ(r.faces.size(), 2u);
  EXPECT_EQ(r.crease_extensions, 0);
  EXPECT_EQ(r.budget_splits, 0);
  EXPECT_TRUE(r.within_tolerance);
  // The face on the left of the crease (x < 1/4) has one loop, the other the hole too.
  std::map<RegionEdgeKind, int> kinds;
  for (const RegionEdge& e : r.edges) ++kinds[e.kind];
  EXPECT_EQ(kinds[RegionEdgeKind::Crease], 1) << "the straight crease is one edge";
  size_t loops = 0;
  for (const RegionFace& f : r.faces) loops += f.loops.size();
  EXPECT_EQ(loops, 3u);
  for (const RegionEdge& e : r.edges) {
    if (e.kind != RegionEdgeKind::Crease) continue;
    EXPECT_GE(e.faces[0], 0);
    EXPECT_GE(e.faces[1], 0);
    EXPECT_NE(e.faces[0], e.faces[1]);
    EXPECT_LE(e.gap, 2 * r.tolerance);
  }
  expect_within_tolerance(s, r);

  // Across the crease the normal turns; each face keeps the spline's normal on its own side.
  const Evaluator ev(s);
  double worst = 0;
  for (int i = 1; i < 20; ++i) {
    const Point2 on(0.25, i / 20.0);
    for (int side : {-1, 1}) {
      const Point2 u = on + Point2(side * 1e-9, 0);
      const SurfacePoint sp = ev.evaluate(u);
      const int f = side < 0 ? (r.faces[0].surface.knots_u.front() < 0.1 ? 0 : 1)
                             : (r.faces[0].surface.knots_u.front() < 0.1 ? 1 : 0);
      Point3 p;
      Vector3 du, dv;
      r.faces[static_cast<size_t>(f)].surface.evaluate(u, p, du, dv);
      const Vector3 a = sp.du.cross(sp.dv), b = du.cross(dv);
      worst = std::max(worst, std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / kPi);
    }
  }
  EXPECT_LE(worst, 0.5) << "normal deviation at the crease, degrees";
}

// A crease chain bent by rounding: the knot lines of its vertices run within 1e-8 of the
// feature edges they do not serve, and the spline's derivatives change across that strip. The
// faces follow the spline on each side of it: two faces, no splits for the budget.
TEST(CadRegions, ACreaseBentByRoundingIsStillOneFacePerFlank) {
  const Spline s = sheet(3, false, 2, 3, true);
  const CadRegions r = make_cad_regions(s, {.tolerance = 1e-4});
  EXPECT_EQ(r.smooth_regions, 2);
  EXPECT_EQ(r.faces.size(), 2u);
  EXPECT_EQ(r.budget_splits, 0);
  EXPECT_TRUE(r.within_tolerance) << "position " << r.max_position_deviation << ", normals "
                                  << r.max_normal_deviation << " degrees";
  EXPECT_LE(r.max_normal_deviation, 0.5);
  expect_within_tolerance(s, r);
}

// A sheet with a sharp dimple: z has a cone-like tip, rounded at 1e-2, near a vertex inside.
// Around it the error falls like a kink's as knots are added, while the rest converges fast:
// the triangles around the tip become an island face of their own, and the faces are within
// the tolerance.
TEST(CadRegions, ASpotThatConvergesSlowlyBecomesAnIsland) {
  test::GridOptions o;
  o.nx = o.ny = 12;
  const Domain d = test::grid_domain(o, 5);
  Spline s = Spline::with_canonical_map(3, d, default_knots(d, 3));
  for (int t = 0; t < d.triangle_count(); ++t)
    for (int i = 0; i < beta_count(3); ++i) {
      const Point2 b = s.blossom_point(t, beta_at(3, i));
      const double r = std::hypot(b.x() - 0.4375, b.y() - 0.5625);
      const double z = 4 * std::sin(3 * b.x()) * std::cos(2 * b.y()) + 8 * std::sqrt(r * r + 1e-4);
      s.control_points()[static_cast<size_t>(s.control_point_index(t, i))] = Point3(40 * b.x(), 40 * b.y(), z);
    }
  const CadRegions r = make_cad_regions(s, {.tolerance = 1e-5, .angle_tolerance = 30, .max_poles = 4000});
  EXPECT_GE(r.islands, 1) << r.faces.size() << " faces, " << r.budget_splits << " splits";
  size_t smallest = static_cast<size_t>(d.triangle_count());
  for (const RegionFace& f : r.faces) smallest = std::min(smallest, f.triangles.size());
  EXPECT_LE(smallest, 24u) << "the island: the triangles around one triangle";
  EXPECT_LE(r.max_position_deviation, r.tolerance);
  expect_within_tolerance(s, r);
}

TEST(CadRegions, ACreaseEndingInsideIsExtendedToTheBorder) {
  const Spline s = sheet_with_crease_ending_inside(3);
  // The band where the kink fades needs many poles for tight normals; the topology is the point.
  const CadRegions r = make_cad_regions(s, {.tolerance = 1e-3, .angle_tolerance = 10});
  EXPECT_EQ(r.crease_extensions, 1);
  EXPECT_EQ(r.creases_left_inside, 0);
  EXPECT_EQ(r.faces.size(), 2u);
  int extension = 0;
  for (const RegionEdge& e : r.edges)
    if (e.kind == RegionEdgeKind::CreaseExtension) {
      ++extension;
      EXPECT_GE(e.faces[1], 0) << "an extension lies between two faces";
    }
  EXPECT_GE(extension, 1);
  EXPECT_TRUE(r.within_tolerance);
  expect_within_tolerance(s, r);
}

TEST(CadRegions, ARegionOverThePoleBudgetIsSplitAlongDomainEdges) {
  const Spline s = sheet(3, false, -1);
  const CadRegions one = make_cad_regions(s, {.tolerance = 1e-4});
  ASSERT_EQ(one.faces.size(), 1u);
  const long poles = static_cast<long>(one.faces[0].surface.poles.size()) / 4;
  const CadRegions r = make_cad_regions(s, {.tolerance = 1e-4, .max_poles = poles});
  EXPECT_GT(r.faces.size(), 1u);
  EXPECT_GE(r.budget_splits, 1);
  EXPECT_EQ(r.unsplittable, 0) << r.faces.size() << " faces, " << r.budget_splits << " splits, " << r.islands << " islands";
  for (const RegionFace& f : r.faces) EXPECT_LE(static_cast<long>(f.surface.poles.size()), poles);
  int split = 0;
  for (const RegionEdge& e : r.edges) split += e.kind == RegionEdgeKind::Split;
  EXPECT_GE(split, 1);
  expect_within_tolerance(s, r);
  // Every domain triangle is in exactly one face.
  std::vector<int> owner(static_cast<size_t>(s.domain().triangle_count()), 0);
  for (const RegionFace& f : r.faces)
    for (int t : f.triangles) ++owner[static_cast<size_t>(t)];
  for (int n : owner) EXPECT_EQ(n, 1);
}

// A ring one cell wide around a square hole (4 x 4 cells, the middle 2 x 2 removed): every
// vertex is on the outer loop or on the hole's, so no chain of domain edges joins two points
// of the outer loop through the inside. Over the pole budget it is cut in two by chains from
// the hole to the outer loop (before, it stayed one face over the tolerance: an
// "unsplittable" region, as rings around islands were on the libcgal-demo head and lion).
TEST(CadRegions, AThinRingOverThePoleBudgetIsCutFromItsHoleToItsOuterLoop) {
  std::vector<Point2> v;
  std::vector<int> id(25, -1);  // grid vertex (i, j) -> domain vertex; the hole's centre has none
  for (int j = 0; j <= 4; ++j)
    for (int i = 0; i <= 4; ++i)
      if (i != 2 || j != 2) {
        id[static_cast<size_t>(j * 5 + i)] = static_cast<int>(v.size());
        v.emplace_back(i / 4.0, j / 4.0);
      }
  auto at = [&](int i, int j) { return id[static_cast<size_t>(j * 5 + i)]; };
  std::vector<std::array<int, 3>> tris;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      if (i >= 1 && i <= 2 && j >= 1 && j <= 2) continue;
      tris.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      tris.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  const Domain d(v, tris, {});
  ASSERT_EQ(d.boundary_loops().size(), 2u);
  Spline s = Spline::with_canonical_map(3, d, default_knots(d, 3));
  for (int t = 0; t < d.triangle_count(); ++t)
    for (int i = 0; i < beta_count(3); ++i) {
      const Point2 b = s.blossom_point(t, beta_at(3, i));
      const double z = 4 * std::sin(3 * b.x()) * std::cos(2 * b.y());
      s.control_points()[static_cast<size_t>(s.control_point_index(t, i))] = Point3(40 * b.x(), 40 * b.y(), z);
    }
  const CadRegions one = make_cad_regions(s, {.tolerance = 1e-4});
  ASSERT_EQ(one.faces.size(), 1u);
  const long poles = static_cast<long>(one.faces[0].surface.poles.size()) / 4;
  const CadRegions r = make_cad_regions(s, {.tolerance = 1e-4, .max_poles = poles});
  EXPECT_EQ(r.unsplittable, 0) << r.faces.size() << " faces, " << r.budget_splits << " splits, " << r.islands << " islands";
  EXPECT_GE(r.budget_splits, 1);
  EXPECT_GE(r.faces.size(), 2u);
  for (const RegionFace& f : r.faces) {
    EXPECT_LE(static_cast<long>(f.surface.poles.size()), poles);
    EXPECT_EQ(f.loops.size(), 1u) << "no face is a ring any more";
  }
  EXPECT_TRUE(r.within_tolerance) << "position " << r.max_position_deviation << ", normals " << r.max_normal_deviation;
  expect_within_tolerance(s, r);
  std::vector<int> owner(static_cast<size_t>(d.triangle_count()), 0);
  for (const RegionFace& f : r.faces)
    for (int t : f.triangles) ++owner[static_cast<size_t>(t)];
  for (int n : owner) EXPECT_EQ(n, 1);
}

TEST(CadRegions, LoopsCloseAndEveryEdgeIsUsedOncePerSide) {
  for (const Spline& s : {sheet(3, true, 2), sheet_with_crease_ending_inside(2), sheet(4, true, -1)}) {
    const CadRegions r = make_cad_regions(s, {.tolerance = 1e-3, .max_poles = 400});
    std::vector<int> forward(r.edges.size(), 0), backward(r.edges.size(), 0);
    for (size_t f = 0; f < r.faces.size(); ++f)
      for (const auto& loop : r.faces[f].loops) {
        ASSERT_FALSE(loop.empty());
        for (size_t i = 0; i < loop.size(); ++i) {
          const RegionEdge& a = r.edges[static_cast<size_t>(loop[i].edge)];
          const RegionEdge& b = r.edges[static_cast<size_t>(loop[(i + 1) % loop.size()].edge)];
          const int end = loop[i].reversed ? a.vertices[0] : a.vertices[1];
          const int start = loop[(i + 1) % loop.size()].reversed ? b.vertices[1] : b.vertices[0];
          EXPECT_EQ(end, start) << "loop of face " << f << " is not closed";
          (loop[i].reversed ? backward : forward)[static_cast<size_t>(loop[i].edge)]++;
          EXPECT_EQ(a.faces[loop[i].reversed ? 1 : 0], static_cast<int>(f));
        }
      }
    for (size_t e = 0; e < r.edges.size(); ++e) {
      EXPECT_EQ(forward[e], 1);
      EXPECT_EQ(backward[e], r.edges[e].faces[1] >= 0 ? 1 : 0);
    }
  }
}

TEST(CadRegions, TheResultDoesNotDependOnTheThreadCount) {
  const Spline s = sheet(3, true, 2);
  const CadRegions a = make_cad_regions(s, {.tolerance = 1e-4, .max_poles = 300, .threads = 1});
  const CadRegions b = make_cad_regions(s, {.tolerance = 1e-4, .max_poles = 300, .threads = 2});
  ASSERT_EQ(a.faces.size(), b.faces.size());
  for (size_t f = 0; f < a.faces.size(); ++f) {
    EXPECT_EQ(a.faces[f].surface.knots_u, b.faces[f].surface.knots_u);
    EXPECT_EQ(a.faces[f].surface.poles, b.faces[f].surface.poles);
  }
  ASSERT_EQ(a.edges.size(), b.edges.size());
  for (size_t e = 0; e < a.edges.size(); ++e) EXPECT_EQ(a.edges[e].curve.poles, b.edges[e].curve.poles);
}

TEST(CadRegions, ProgressEndsWithTheFacesFitted) {
  const Spline s = sheet(3, true, 2);
  std::vector<std::string> lines;
  CadRegionOptions o{.tolerance = 1e-4, .max_poles = 300, .threads = 2};
  o.progress = [&](const std::string& line) { lines.push_back(line); };  // called one at a time
  const CadRegions r = make_cad_regions(s, o);
  ASSERT_GT(r.budget_splits + r.islands, 0);  // regions were split: more fits than faces
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines.back(), "fitted " + std::to_string(r.faces.size()) + " region faces (" +
                              std::to_string(r.budget_splits) + " splits and " + std::to_string(r.islands) +
                              " islands for the pole budget)");
}

TEST(CadRegions, OptionsOutOfRangeAreRefused) {
  const Spline s = sheet(2, false, -1);
  EXPECT_THROW(make_cad_regions(s, {.tolerance = 0}), InvalidInput);
  EXPECT_THROW(make_cad_regions(s, {.angle_tolerance = 90}), InvalidInput);
  EXPECT_THROW(make_cad_regions(s, {.degree = 1}), InvalidInput);
  EXPECT_THROW(make_cad_regions(s, {.degree = 10}), InvalidInput);
  EXPECT_THROW(make_cad_regions(s, {.max_poles = 15}), InvalidInput);
  EXPECT_THROW(make_cad_regions(Spline(), CadRegionOptions{}), InvalidInput);
}

}  // namespace
}  // namespace tbs
