// Parameters for scans without them: topology, repairs, charts and seams, LSCM and its fallback, point
// clouds, subdivision; and real meshes from Debian's libcgal-demo.
#include <tbs/atlas.h>
#include <tbs/errors.h>
#include <tbs/fit.h>
#include <tbs/parameterize.h>
#include <tbs/predicates.h>
#include <tbs/scan.h>

#include "cgal_demo_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <set>

namespace tbs {
namespace {

// An nx x ny grid over [0,1]^2 lifted by z(x, y), two triangles per cell; cells for which
// `skip` is true are left out (holes).
Scan grid(int nx, int ny, const std::function<Point3(double, double)>& f,
          const std::function<bool(int, int)>& skip = [](int, int) { return false; }) {
  Scan s;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) s.positions.push_back(f(double(i) / nx, double(j) / ny));
  auto id = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (skip(i, j)) continue;
      s.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  // Drop vertices no face uses (inside holes), renumbering.
  std::vector<int> used(s.positions.size(), -1);
  Scan out;
  for (auto& t : s.triangles)
    for (int& v : t) {
      if (used[v] < 0) used[v] = int(out.positions.size()), out.positions.push_back(s.positions[v]);
      v = used[v];
    }
  out.triangles = s.triangles;
  return out;
}

Point3 paraboloid(double x, double y) { return Point3(x, y, 0.3 * (x * x - y * y)); }

// A unit sphere: an octahedron subdivided `levels` times, vertices pushed onto the sphere.
Scan sphere(int levels) {
  Scan s;
  s.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  s.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto m = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      s.positions.push_back((s.positions[a] + s.positions[b]).normalized());
      return mid[key] = int(s.positions.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& t : s.triangles) {
      const int ab = m(t[0], t[1]), bc = m(t[1], t[2]), ca = m(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({ab, t[1], bc});
      next.push_back({ca, bc, t[2]});
      next.push_back({ab, bc, ca});
    }
    s.triangles = std::move(next);
  }
  return s;
}

// A torus, n x n quads split in two.
Scan torus(int n) {
  Scan s;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n, b = 2 * M_PI * j / n;
      s.positions.emplace_back((2 + std::cos(b)) * std::cos(a), (2 + std::cos(b)) * std::sin(a), std::sin(b));
    }
  auto id = [&](int i, int j) { return (j % n) * n + (i % n); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      s.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return s;
}

// The map is bijective: every (u, v) triangle counter-clockwise, and no two boundary edges
// crossing (checked pairwise with exact predicates).
void expect_bijective(const Scan& s) {
  ASSERT_EQ(s.uv.size(), s.positions.size());
  for (const auto& t : s.triangles)
    ASSERT_GT(detail::orientation_exact(s.uv[t[0]], s.uv[t[1]], s.uv[t[2]]), 0) << "flipped triangle";
  std::map<std::pair<int, int>, int> count;
  for (const auto& t : s.triangles)
    for (int k = 0; k < 3; ++k) ++count[std::minmax(t[k], t[(k + 1) % 3])];
  std::vector<std::pair<int, int>> border;
  for (const auto& [e, c] : count)
    if (c == 1) border.push_back(e);
  ASSERT_FALSE(border.empty());
  for (size_t i = 0; i < border.size(); ++i)
    for (size_t j = i + 1; j < border.size(); ++j) {
      const auto [a, b] = border[i];
      const auto [c, d] = border[j];
      if (a == c || a == d || b == c || b == d) continue;
      const int o1 = detail::orientation_exact(s.uv[a], s.uv[b], s.uv[c]), o2 = detail::orientation_exact(s.uv[a], s.uv[b], s.uv[d]);
      const int o3 = detail::orientation_exact(s.uv[c], s.uv[d], s.uv[a]), o4 = detail::orientation_exact(s.uv[c], s.uv[d], s.uv[b]);
      ASSERT_FALSE(o1 * o2 < 0 && o3 * o4 < 0) << "boundary edges cross";
    }
}

TEST(Topology, CountsComponentsBoundariesAndGenus) {
  const auto disk = grid(4, 4, paraboloid);
  MeshTopology t = mesh_topology(disk.positions.size(), disk.triangles);
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.boundary_loops, 1);
  EXPECT_EQ(t.genus, 0);
  EXPECT_EQ(t.vertices, 25u);
  const auto holes = grid(9, 9, paraboloid, [](int i, int j) { return (i == 2 && j == 2) || (i == 6 && j == 5); });
  t = mesh_topology(holes.positions.size(), holes.triangles);
  EXPECT_EQ(t.boundary_loops, 3);
  EXPECT_EQ(t.genus, 0);
  const auto ball = sphere(2);
  t = mesh_topology(ball.positions.size(), ball.triangles);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.genus, 0);
  const auto ring = torus(12);
  t = mesh_topology(ring.positions.size(), ring.triangles);
  EXPECT_EQ(t.genus, 1);
  EXPECT_EQ(t.describe(), "1 component, 0 boundary loops, genus 1");
}

TEST(Parameterize, DiskIsFlattenedConformallyAndToScale) {
  const Scan in = grid(20, 20, paraboloid);
  const ParameterizedScan p = parameterize_scan(in);
  expect_bijective(p.scan);
  EXPECT_EQ(p.report.method, "LSCM");
  EXPECT_TRUE(p.report.fallback_reason.empty());
  EXPECT_EQ(p.scan.positions.size(), in.positions.size());
  EXPECT_EQ(p.report.points_dropped, 0u);
  // A gently curved sheet flattens nearly without distortion.
  EXPECT_LT(p.report.distortion.angle_mean, 1.02);
  EXPECT_LT(p.report.distortion.area_mean, 1.1);
  // The parameters are scaled to the surface: their area is the surface's.
  double a3 = 0, a2 = 0;
  for (const auto& t : p.scan.triangles) {
    const auto& x = p.scan.positions;
    a3 += 0.5 * (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).norm();
    const Point2 &x0 = p.scan.uv[t[0]], &x1 = p.scan.uv[t[1]], &x2 = p.scan.uv[t[2]];
    a2 += 0.5 * ((x1 - x0).x() * (x2 - x0).y() - (x1 - x0).y() * (x2 - x0).x());
  }
  EXPECT_NEAR(a2, a3, 1e-9 * a3);
  // Each output point is its input point.
  for (size_t i = 0; i < p.scan.positions.size(); ++i) EXPECT_EQ(p.scan.positions[i], in.positions[p.source[i]]);
}

// A sphere opened at a small cap, with a hole: LSCM shrinks the far side against the cap's rim
// (area distortion 14 mean, 43 max); `auto` relaxes the map toward equal areas, and it stays bijective with its
// hole open.
TEST(Parameterize, NearClosedSurfaceIsRelaxedTowardEqualAreas) {
  Scan ball = sphere(5);
  auto removed = [&](const std::array<int, 3>& t) {
    const Point3 c = (ball.positions[t[0]] + ball.positions[t[1]] + ball.positions[t[2]]) / 3;
    if (c.z() > 0.95) return true;                                       // the opening
    return (c - Point3(1, 0, 0)).norm() < 0.15;                          // a hole
  };
  std::erase_if(ball.triangles, removed);
  Scan in;
  std::vector<int> id(ball.positions.size(), -1);
  for (auto t : ball.triangles) {
    for (int& v : t) {
      if (id[v] < 0) id[v] = int(in.positions.size()), in.positions.push_back(ball.positions[v]);
      v = id[v];
    }
    in.triangles.push_back(t);
  }
  ASSERT_EQ(mesh_topology(in.positions.size(), in.triangles).boundary_loops, 2);
  // The relaxed map still stretches more than the chart bound (the default then cuts the
  // surface into charts): here the one flattening is looked at, without a bound.
  ParameterizeOptions one;
  one.chart_stretch = std::numeric_limits<double>::infinity();
  const ParameterizedScan p = parameterize_scan(in, one);
  expect_bijective(p.scan);
  EXPECT_EQ(p.report.method, "LSCM, areas relaxed");
  EXPECT_TRUE(p.scan.atlas.empty());
  // At the default bound it is cut into charts that stretch less.
  const ParameterizedScan cut = parameterize_scan(in);
  EXPECT_GT(cut.report.charts, 1);
  EXPECT_LE(cut.report.stretch, ParameterizeOptions().chart_stretch);
  EXPECT_GT(p.report.stretch, cut.report.stretch);
  EXPECT_GT(p.report.conformal.area_mean, 10);
  // Halfway on a log scale: the area ratios fall to about their square roots (14 -> 3.6 mean,
  // 43 -> 18 max when written); angles stay within 5:1 (3.1).
  EXPECT_LT(p.report.distortion.area_mean, 0.3 * p.report.conformal.area_mean);
  EXPECT_LT(p.report.distortion.area_max, 0.5 * p.report.conformal.area_max);
  EXPECT_LT(p.report.distortion.angle_max, 5);
  EXPECT_EQ(mesh_topology(p.scan.positions.size(), p.scan.triangles).boundary_loops, 2);
  // `lscm` asks for the conformal map itself.
  ParameterizeOptions o;
  o.method = FlattenMethod::Lscm;
  const ParameterizedScan q = parameterize_scan(in, o);
  EXPECT_EQ(q.report.method, "LSCM");
  EXPECT_NEAR(q.report.distortion.area_mean, p.report.conformal.area_mean, 1e-9 * p.report.conformal.area_mean);
}

TEST(Parameterize, HolesStayHoles) {
  const Scan in = grid(24, 16, paraboloid, [](int i, int j) {
    return (i >= 4 && i < 8 && j >= 5 && j < 9) || (i >= 14 && i < 19 && j >= 3 && j < 12);
  });
  const ParameterizedScan p = parameterize_scan(in);
  expect_bijective(p.scan);
  EXPECT_EQ(p.report.used.boundary_loops, 3);
  EXPECT_EQ(p.report.method, "LSCM");
  // The mean-value method (holes filled while solving) is bijective too.
  ParameterizeOptions o;
  o.method = FlattenMethod::MeanValue;
  const ParameterizedScan q = parameterize_scan(in, o);
  expect_bijective(q.scan);
  EXPECT_EQ(q.report.method, "mean value (circular boundary)");
  EXPECT_EQ(mesh_topology(q.scan.positions.size(), q.scan.triangles).boundary_loops, 3);
}

// The atlas of a closed or higher-genus surface: every chart a disk (genus 0, at least one
// boundary loop) flattened bijectively, the seams gluing copies of the same mesh vertices, the
// seams and borders closing into the charts' outlines.
void expect_atlas(const Scan& in, const ParameterizedScan& p, int genus) {
  expect_bijective(p.scan);
  EXPECT_TRUE(p.scan.atlas.closed);
  EXPECT_EQ(p.scan.atlas.genus, genus);
  EXPECT_EQ(p.report.used.genus, genus);
  EXPECT_GE(p.report.charts, 1);
  EXPECT_EQ(p.report.seams, p.scan.atlas.seams.size());
  EXPECT_TRUE(p.scan.atlas.borders.empty());
  const MeshTopology t = mesh_topology(p.scan.positions.size(), p.scan.triangles);
  EXPECT_EQ(t.components, p.report.charts);
  EXPECT_EQ(t.genus, 0);  // summed over the charts: each is a disk, possibly with holes
  EXPECT_GE(t.boundary_loops, t.components);
  // Every seam point is a copy of one mesh vertex on both sides.
  std::map<std::pair<double, double>, Point3> at;
  for (size_t i = 0; i < p.scan.uv.size(); ++i) at[{p.scan.uv[i].x(), p.scan.uv[i].y()}] = p.scan.positions[i];
  size_t points = 0;
  for (const Seam& seam : p.scan.atlas.seams) {
    ASSERT_EQ(seam.a.size(), seam.b.size());
    for (size_t i = 0; i < seam.a.size(); ++i) {
      const auto a = at.find({seam.a[i].x(), seam.a[i].y()}), b = at.find({seam.b[i].x(), seam.b[i].y()});
      ASSERT_NE(a, at.end());
      ASSERT_NE(b, at.end());
      EXPECT_EQ(a->second, b->second);
      ++points;
    }
  }
  EXPECT_GT(points, 0u);
  // The outlines close and hold every chart's area.
  const auto loops = chart_outlines(p.scan.atlas);
  double area = 0, uv_area = 0;
  for (const auto& loop : loops)
    for (size_t i = 0; i < loop.size(); ++i)
      area += 0.5 * (loop[i].x() * loop[(i + 1) % loop.size()].y() - loop[(i + 1) % loop.size()].x() * loop[i].y());
  for (const auto& f : p.scan.triangles) {
    const Point2 &a = p.scan.uv[f[0]], &b = p.scan.uv[f[1]], &c = p.scan.uv[f[2]];
    uv_area += 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
  }
  EXPECT_NEAR(area, uv_area, 1e-9 * uv_area);
  // The flattening keeps the surface's area and stretches a chart little.
  double area3 = 0;
  for (const auto& f : in.triangles)
    area3 += 0.5 * (in.positions[f[1]] - in.positions[f[0]]).cross(in.positions[f[2]] - in.positions[f[0]]).norm();
  EXPECT_NEAR(uv_area, area3, 1e-6 * area3);
  EXPECT_LE(p.report.stretch, ParameterizeOptions().chart_stretch);
}

TEST(Parameterize, ClosedSurfaceIsCutIntoCharts) {
  const Scan in = sphere(3);
  const ParameterizedScan p = parameterize_scan(in);
  expect_atlas(in, p, 0);
  EXPECT_GE(p.report.charts, 2);  // a sphere is no disk
  ParameterizeOptions o;
  o.cut_closed = false;
  EXPECT_THROW(parameterize_scan(in, o), InvalidInput);
}

TEST(Parameterize, HandlesAreCutIntoChartsOfGenusZero) {
  Scan in = torus(24);
  in.source = "ring.off";
  const ParameterizedScan p = parameterize_scan(in);
  expect_atlas(in, p, 1);
  ParameterizeOptions o;
  o.cut_closed = false;
  try {
    parameterize_scan(in, o);
    FAIL() << "a torus was accepted with cut_closed = false";
  } catch (const InvalidInput& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("ring.off: component 1 of 1 has 576 vertices, 0 boundary loops, genus 1"), std::string::npos) << msg;
  }
}

TEST(Parameterize, ASharpEdgeLoopSeparatesCharts) {
  // A closed cylinder (a can): its two rims are sharp (90 degrees), so the side and the two
  // caps become charts of their own, glued by sharp seams.
  Scan can;
  const int n = 48, rings = 12;
  for (int j = 0; j <= rings; ++j)
    for (int i = 0; i < n; ++i)
      can.positions.emplace_back(std::cos(2 * M_PI * i / n), std::sin(2 * M_PI * i / n), 2.0 * j / rings);
  auto id = [&](int i, int j) { return j * n + (i % n); };
  for (int j = 0; j < rings; ++j)
    for (int i = 0; i < n; ++i) {
      can.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      can.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  for (int cap = 0; cap < 2; ++cap) {
    const int centre = static_cast<int>(can.positions.size());
    can.positions.emplace_back(0, 0, cap == 0 ? 0.0 : 2.0);
    for (int i = 0; i < n; ++i) {
      if (cap == 0)
        can.triangles.push_back({centre, id(i + 1, 0), id(i, 0)});
      else
        can.triangles.push_back({centre, id(i, rings), id(i + 1, rings)});
    }
  }
  const ParameterizedScan p = parameterize_scan(can);
  expect_atlas(can, p, 0);
  EXPECT_GE(p.report.charts, 3);
  size_t sharp = 0;
  for (const Seam& s : p.scan.atlas.seams) sharp += s.sharp;
  EXPECT_GE(sharp, 2u);  // the two rims
}

TEST(Parameterize, AnOpenSurfaceThatFlattensWellIsNotCut) {
  const ParameterizedScan p = parameterize_scan(grid(24, 16, paraboloid));
  EXPECT_TRUE(p.scan.atlas.empty());
  EXPECT_EQ(p.report.charts, 1);
  EXPECT_EQ(p.report.seam_edges, 0u);
  EXPECT_LE(p.report.stretch, 2);
}

TEST(Parameterize, ChoosesComponentsByDecreasingSize) {
  Scan a = grid(10, 10, paraboloid), b = grid(4, 4, [](double x, double y) { return Point3(x + 5, y, 0); });
  Scan in = a;
  const int off = int(in.positions.size());
  in.positions.insert(in.positions.end(), b.positions.begin(), b.positions.end());
  // The small one first in the file: the order of the file does not matter.
  std::vector<std::array<int, 3>> tris;
  for (auto t : b.triangles) tris.push_back({t[0] + off, t[1] + off, t[2] + off});
  tris.insert(tris.end(), a.triangles.begin(), a.triangles.end());
  in.triangles = tris;
  ParameterizedScan p = parameterize_scan(in);
  EXPECT_EQ(p.report.topology.components, 2);
  EXPECT_EQ(p.scan.positions.size(), a.positions.size());
  EXPECT_EQ(p.report.points_dropped, b.positions.size());
  ParameterizeOptions o;
  o.component = 2;
  p = parameterize_scan(in, o);
  EXPECT_EQ(p.scan.positions.size(), b.positions.size());
  expect_bijective(p.scan);
  o.component = 3;
  EXPECT_THROW(parameterize_scan(in, o), InvalidInput);
}

TEST(Parameterize, RepairsMessyMeshes) {
  const Scan clean = grid(8, 8, paraboloid);
  Scan messy;
  // Every face with its own three vertices (a soup, as STL has), one face flipped, one
  // duplicated, one with a repeated corner, and one unused vertex.
  for (size_t f = 0; f < clean.triangles.size(); ++f) {
    auto t = clean.triangles[f];
    if (f == 7) std::swap(t[1], t[2]);
    const int base = int(messy.positions.size());
    for (int v : t) messy.positions.push_back(clean.positions[v]);
    messy.triangles.push_back({base, base + 1, base + 2});
  }
  messy.triangles.push_back(messy.triangles[3]);
  messy.triangles.push_back({0, 0, 1});
  messy.positions.push_back(Point3(9, 9, 9));
  const ParameterizedScan p = parameterize_scan(messy);
  expect_bijective(p.scan);
  EXPECT_EQ(p.scan.positions.size(), clean.positions.size());
  EXPECT_EQ(p.scan.triangles.size(), clean.triangles.size());
  EXPECT_GT(p.report.vertices_merged, 0u);
  EXPECT_EQ(p.report.faces_removed, 2u);
  EXPECT_TRUE(p.report.reoriented);
  EXPECT_EQ(p.report.isolated_points, 1u);
}

TEST(Parameterize, NonManifoldEdgesAreSplit) {
  Scan in = grid(6, 6, paraboloid);
  // A fin: a third face on an inner edge.
  const auto t = in.triangles[20];
  in.positions.push_back(Point3(0.5, 0.5, 1.0));
  in.triangles.push_back({t[0], t[1], int(in.positions.size()) - 1});
  const ParameterizedScan p = parameterize_scan(in);
  EXPECT_GT(p.report.vertices_split, 0u);
  expect_bijective(p.scan);
}

TEST(Parameterize, PointCloudIsReconstructedAndProjected) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  Scan in;
  for (int i = 0; i < 3000; ++i) {
    const double y = u(rng);  // second argument first, as GCC drew them: the same for any compiler
    in.positions.push_back(paraboloid(u(rng), y));
  }
  const ParameterizedScan p = parameterize_scan(in);
  EXPECT_EQ(p.report.input, "point cloud");
  EXPECT_GT(p.report.reconstructed_faces, 5000u);
  EXPECT_EQ(p.report.points_projected + p.report.points_dropped, in.positions.size());
  EXPECT_GE(p.report.points_projected, in.positions.size() - 3);
  EXPECT_TRUE(p.scan.triangles.empty());
  // Parameters follow the surface: nearby points in space have nearby parameters, and the
  // parameter area is the surface's (about 1.06 for this paraboloid).
  for (size_t i = 0; i < p.scan.positions.size(); ++i) EXPECT_EQ(p.scan.positions[i], in.positions[p.source[i]]);
  Box2 box;
  for (const auto& q : p.scan.uv) box.extend(q);
  EXPECT_GT((box.max - box.min).prod(), 0.9);
  // And the fit reaches its tolerance on them.
  FitOptions fo;
  fo.tolerance = 1e-3;
  const FitResult r = fit(p.scan, fo);
  EXPECT_TRUE(r.report.converged) << r.report.stop_reason;
}

TEST(Parameterize, FacesSpanningAGapInACloudAreRemoved) {
  // A sheet of 40 x 40 points (spacing 1/39) and, 2 units beyond its edge, a patch of 5 x 5
  // (spacing 0.025): the reconstruction joins the two by faces 50 times longer than the
  // spacing. They are removed, the patch becomes a component of its own and the sheet, the
  // larger one, is flattened alone (before, one component: the map spanned both).
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0, 1e-4);
  Scan in;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) {
      const double x = i / 39.0, y = j / 39.0;
      const double dx = noise(rng), dy = noise(rng), dz = noise(rng);
      in.positions.push_back({x + dx, y + dy, 0.1 * std::sin(3 * x) + dz});
    }
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) in.positions.push_back({3 + 0.025 * i, 0.5 + 0.025 * j, 0});
  const ParameterizedScan p = parameterize_scan(in);
  EXPECT_GT(p.report.bridge_faces_removed, 0u);
  EXPECT_EQ(p.report.topology.components, 2);
  EXPECT_EQ(p.report.points_dropped, 25u);
  for (size_t i = 0; i < p.scan.positions.size(); ++i) EXPECT_LT(p.source[i], 1600u);
  EXPECT_NE(p.report.to_json().find("\"bridge_faces_removed\":" + std::to_string(p.report.bridge_faces_removed)), std::string::npos);
}

TEST(Parameterize, SubdivisionPutsNewPointsOnASmoothSurface) {
  // A coarse sphere (neighbouring faces turn by about 20 degrees, below the sharp angle): the
  // new points lie much closer to the sphere than the flat faces do.
  const Scan in = sphere(2);
  ParameterizeOptions o;
  o.min_points = 3000;
  const ParameterizedScan p = parameterize_scan(in, o);
  EXPECT_GE(p.report.subdivisions, 1);
  EXPECT_GE(p.scan.positions.size(), 3000u);
  expect_bijective(p.scan);
  double pn = 0;
  for (const auto& x : p.scan.positions) pn = std::max(pn, std::fabs(x.norm() - 1));
  double linear = 0;  // the flat faces' centroids
  for (const auto& t : in.triangles)
    linear = std::max(linear, std::fabs(((in.positions[t[0]] + in.positions[t[1]] + in.positions[t[2]]) / 3).norm() - 1));
  EXPECT_LT(pn, 0.5 * linear) << pn << " vs " << linear;
  // A cube's creases stay creases: every new point lies on the cube's faces.
  Scan cube;
  cube.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  cube.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                    {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  o.min_points = 500;
  const ParameterizedScan c = parameterize_scan(cube, o);
  EXPECT_GE(c.scan.positions.size(), 500u);
  for (const auto& x : c.scan.positions) {
    const double face = std::min(x.cwiseAbs().minCoeff(), (x - Point3(1, 1, 1)).cwiseAbs().minCoeff());
    ASSERT_LT(face, 1e-12) << x.transpose();
  }
}

TEST(Parameterize, RefusesTooLittle) {
  Scan two;
  two.positions = {{0, 0, 0}, {1, 0, 0}};
  EXPECT_THROW(parameterize_scan(two), InvalidInput);
  Scan line;
  for (int i = 0; i < 10; ++i) line.positions.emplace_back(i, 0, 0);
  EXPECT_THROW(parameterize_scan(line), InvalidInput);
}

// Scans built in code get the checks the readers make: each bad value is refused with a message
// naming the scan and the element.
TEST(Parameterize, RefusesInvalidScansBuiltInCode) {
  const Scan good = grid(6, 6, paraboloid);
  auto message = [](const Scan& s) {
    try {
      parameterize_scan(s);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  Scan s = good;
  s.source = "made.ply";
  s.positions[7].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(message(s).find("made.ply: point 7 is not finite"), std::string::npos) << message(s);
  s = good;
  s.positions[3].z() = 1e31;
  EXPECT_NE(message(s).find("point 3"), std::string::npos) << message(s);
  s = good;
  s.triangles[5][1] = static_cast<int>(s.positions.size());
  EXPECT_NE(message(s).find("triangle 5 refers to point 49"), std::string::npos) << message(s);
  s = good;
  s.triangles[2][0] = -1;
  EXPECT_NE(message(s).find("triangle 2 refers to point -1"), std::string::npos) << message(s);
  s = good;
  s.normals.assign(5, Vector3(0, 0, 1));
  EXPECT_NE(message(s).find("5 normals for 49 points"), std::string::npos) << message(s);
  s = good;
  s.normals.assign(s.positions.size(), Vector3(0, 0, 1));
  s.normals[4] = Vector3::Zero();
  EXPECT_NE(message(s).find("normal 4 is not"), std::string::npos) << message(s);
  s = good;
  s.normals.assign(s.positions.size(), Vector3(0, 0, 1));
  EXPECT_EQ(message(s), "(accepted)");
}

// Faces that all have (nearly) collinear corners pass the exact degeneracy test; they used to
// flatten onto a curve and hang the fitting domain's mesher. Refused, naming the slivers.
TEST(Parameterize, SliverOnlyMeshIsRefused) {
  Scan s;
  // Rows of a grid whose z is linear along the row: corners collinear up to rounding.
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) s.positions.emplace_back(j, i, 0.1 * i * j);
    for (int j = 0; j + 2 < 6; ++j) s.triangles.push_back({i * 6 + j, i * 6 + j + 1, i * 6 + j + 2});
  }
  try {
    parameterize_scan(s);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("almost no area"), std::string::npos) << e.what();
  }
}

// The meshes of the issue, from Debian's libcgal-demo: every one is flattened bijectively, as
// one chart or cut into charts (the closed one always) that stretch little.
TEST(Parameterize, CgalDemoMeshes) {
  const auto data = test::cgal_demo_data("tbs_parameterize_test_data", "data/meshes data/points_3/radar.xyz");
  if (!data) GTEST_SKIP() << "libcgal-demo is not installed";
  const std::filesystem::path dir = *data;
  struct Case {
    std::string file;
    int components, loops, genus;
  };
  for (const Case& c : std::vector<Case>{{"meshes/mask_cone.off", 2, 1, 0},
                                         {"meshes/mesh_with_border.off", 1, 1, 0},
                                         {"meshes/cylinder.off", 1, 1, 0},
                                         {"meshes/head.off", 1, 3, 0},
                                         {"meshes/lion.off", 1, 5, 0},
                                         {"meshes/patch-20.off", 1, 1, 0},
                                         {"meshes/sphere966.off", 1, 0, 0},
                                         // radar: 4 loops until its 9 faces spanning gaps were removed
                                         {"points_3/radar.xyz", 1, 5, 0}}) {
    SCOPED_TRACE(c.file);
    const Scan in = read_scan((dir / "data" / c.file).string());
    const ParameterizedScan p = parameterize_scan(in);
    EXPECT_EQ(p.report.topology.components, c.components);
    EXPECT_EQ(p.report.used.boundary_loops, c.loops);
    EXPECT_EQ(p.report.used.genus, c.genus);
    if (p.scan.triangles.empty()) {
      EXPECT_EQ(p.report.points_projected, in.positions.size());
    } else {
      expect_bijective(p.scan);
    }
    if (c.loops == 0) {
      EXPECT_GE(p.report.charts, 2);
    }
    EXPECT_EQ(p.scan.atlas.empty(), p.report.charts == 1);
    EXPECT_LE(p.report.stretch, ParameterizeOptions().chart_stretch);
  }
  // The radar dish's reconstruction folds under LSCM: one flattening falls back to mean-value
  // coordinates and says why; that map stretches more than the chart bound, so the default
  // cuts the dish into charts instead; LSCM alone refuses.
  const Scan radar = read_scan((dir / "data/points_3/radar.xyz").string());
  ParameterizeOptions one;
  one.chart_stretch = std::numeric_limits<double>::infinity();
  const ParameterizedScan p = parameterize_scan(radar, one);
  EXPECT_EQ(p.report.method, "mean value (circular boundary)");
  EXPECT_NE(p.report.fallback_reason.find("LSCM folds"), std::string::npos) << p.report.fallback_reason;
  EXPECT_GT(p.report.stretch, one.chart_stretch == 0 ? 0 : ParameterizeOptions().chart_stretch);
  const ParameterizedScan cut = parameterize_scan(radar);
  EXPECT_EQ(cut.report.method, "charts (LSCM)");
  EXPECT_GT(cut.report.charts, 1);
  EXPECT_LE(cut.report.stretch, ParameterizeOptions().chart_stretch);
  ParameterizeOptions o;
  o.method = FlattenMethod::Lscm;
  EXPECT_THROW(parameterize_scan(radar, o), InvalidInput);
}

}  // namespace
}  // namespace tbs
