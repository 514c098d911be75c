// Atlases (atlas.h): the charts of a domain, the outlines that seams and borders make, the .tbs
// round trip of an atlas, and the seam check on splines built in code whose seams are known.
#include <gtest/gtest.h>
#include <tbs/atlas.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/io.h>
#include <tbs/knots.h>
#include <tbs/shape_check.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

namespace tbs {
namespace {

// Two charts side by side: [0,1]^2 and [2,3] x [0,1], each a 4 x 4 grid of squares cut into
// triangles. Vertices are numbered chart by chart.
Domain two_squares() {
  std::vector<Point2> v;
  std::vector<std::array<int, 3>> t;
  for (int c = 0; c < 2; ++c) {
    const int base = static_cast<int>(v.size());
    for (int j = 0; j <= 4; ++j)
      for (int i = 0; i <= 4; ++i) v.emplace_back(2 * c + i / 4.0, j / 4.0);
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        const int a = base + j * 5 + i;
        t.push_back({a, a + 1, a + 6});
        t.push_back({a, a + 6, a + 5});
      }
  }
  return Domain(std::move(v), std::move(t));
}

// A cubic spline over two_squares() that is the affine map `left` on the first chart and
// `right` on the second (linear precision: control points at the blossoms of the identity).
Spline two_maps(const std::function<Point3(const Point2&)>& left,
                const std::function<Point3(const Point2&)>& right) {
  const Domain d = two_squares();
  Spline s = Spline::with_canonical_map(3, d, default_knots(d, 3));
  const Charts charts = domain_charts(d);
  for (int t = 0; t < d.triangle_count(); ++t)
    for (int i = 0; i < beta_count(3); ++i) {
      const Point2 b = s.blossom_point(t, beta_at(3, i));
      s.control_points()[static_cast<size_t>(s.control_point_index(t, i))] =
          charts.of_triangle[static_cast<size_t>(t)] == 0 ? left(b) : right(b);
    }
  return s;
}

// Chart 0's column u = 0.75 glued to chart 1's column u = 2.25, and the maps that make them one
// flat sheet (chart 1 moved left by 1.5).
Atlas sheet_atlas() {
  Atlas a;
  Seam s;
  for (double v : {0.1, 0.35, 0.6, 0.9}) {
    s.a.emplace_back(0.75, v);
    s.b.emplace_back(2.25, v);
  }
  a.seams.push_back(s);
  return a;
}

Point3 flat_left(const Point2& u) { return {u.x(), u.y(), 0}; }
Point3 flat_right(const Point2& u) { return {u.x() - 1.5, u.y(), 0}; }

TEST(Atlas, ChartsAreTheDomainsComponents) {
  const Domain d = two_squares();
  const Charts c = domain_charts(d);
  ASSERT_EQ(c.count, 2);
  for (int t = 0; t < d.triangle_count(); ++t)
    EXPECT_EQ(c.of_triangle[static_cast<size_t>(t)], t < 32 ? 0 : 1);
}

TEST(Atlas, AMatchingSeamHasNoGapAndNoNormalJump) {
  const Spline s = two_maps(flat_left, flat_right);
  const Evaluator ev(s);
  const SeamCheck c = check_seams(s, ev, sheet_atlas(), 1000, 1);
  EXPECT_EQ(c.samples, 1000u);
  EXPECT_LE(c.max_gap, 1e-12);
  EXPECT_LE(c.max_normal_jump, 1e-6);
  EXPECT_EQ(c.min_crease, 0);
  EXPECT_EQ(c.max_crease, 0);
}

TEST(Atlas, TheSeamCheckMeasuresGapsAndCreases) {
  // Chart 1 lifted by 0.01: the gap is 0.01 everywhere.
  {
    const Spline s =
        two_maps(flat_left, [](const Point2& u) { return Point3(u.x() - 1.5, u.y(), 0.01); });
    const Evaluator ev(s);
    const SeamCheck c = check_seams(s, ev, sheet_atlas(), 100);
    EXPECT_NEAR(c.max_gap, 0.01, 1e-12);
    ASSERT_EQ(c.seam_gap.size(), 1u);
    EXPECT_NEAR(c.seam_gap[0], 0.01, 1e-12);
  }
  // Chart 1 bent up by 30 degrees about the seam: a crease of 30 degrees, reported as a normal
  // jump on a smooth seam and as the crease on a sharp one.
  const double a = 30 * M_PI / 180;
  auto bent = [a](const Point2& u) {
    return Point3(0.75 + std::cos(a) * (u.x() - 2.25), u.y(), std::sin(a) * (u.x() - 2.25));
  };
  const Spline s = two_maps(flat_left, bent);
  const Evaluator ev(s);
  Atlas atlas = sheet_atlas();
  SeamCheck c = check_seams(s, ev, atlas, 100);
  EXPECT_LE(c.max_gap, 1e-12);
  EXPECT_NEAR(c.max_normal_jump, 30, 1e-6);
  atlas.seams[0].sharp = true;
  c = check_seams(s, ev, atlas, 100);
  EXPECT_EQ(c.max_normal_jump, 0);
  EXPECT_NEAR(c.min_crease, 30, 1e-6);
  EXPECT_NEAR(c.max_crease, 30, 1e-6);
}

TEST(Atlas, TheSeamCheckCountsSamplesOutsideTheDomainOrTheirChart) {
  const Spline s = two_maps(flat_left, flat_right);
  const Evaluator ev(s);
  Atlas atlas = sheet_atlas();
  EXPECT_EQ(check_seams(s, ev, atlas, 300).outside, 0u);
  atlas.seams[0].b.back() = Point2(1.5, 0.9);  // the last segment's far end between the charts
  SeamCheck c = check_seams(s, ev, atlas, 300);
  EXPECT_GT(c.outside, 0u);
  EXPECT_LT(c.outside, 100u);  // in the last of three segments, and only its far part
  atlas = sheet_atlas();
  atlas.seams[0].b.back() = Point2(0.5, 0.9);  // the last point in the other chart
  c = check_seams(s, ev, atlas, 300);
  EXPECT_GT(c.outside, 0u);
  EXPECT_THROW(check_seams(s, ev, sheet_atlas(), 0), InvalidInput);
}

TEST(Atlas, SeamsAndBordersCloseIntoOutlines) {
  // Chart 0 is the square [0.25, 0.75]^2: its right side a seam (to chart 1's square
  // [2.25, 2.75]^2, glued along that one's left side), the rest borders.
  Atlas atlas;
  Seam s;
  s.a = {{0.75, 0.25}, {0.75, 0.75}};
  s.b = {{2.25, 0.25}, {2.25, 0.75}};
  atlas.seams.push_back(s);
  atlas.borders.push_back({{0.75, 0.75}, {0.25, 0.75}, {0.25, 0.25}, {0.75, 0.25}});
  atlas.borders.push_back({{2.25, 0.25}, {2.75, 0.25}, {2.75, 0.75}, {2.25, 0.75}});
  const auto loops = chart_outlines(atlas);
  ASSERT_EQ(loops.size(), 2u);
  for (const auto& loop : loops) {
    EXPECT_EQ(loop.size(), 4u);
    double area = 0;
    for (size_t i = 0; i < loop.size(); ++i)
      area += loop[i].x() * loop[(i + 1) % loop.size()].y() -
              loop[(i + 1) % loop.size()].x() * loop[i].y();
    EXPECT_NEAR(area / 2, 0.25, 1e-15);  // counter-clockwise: the chart on the left
  }
  EXPECT_TRUE(inside_outlines(loops, {0.5, 0.5}));
  EXPECT_TRUE(inside_outlines(loops, {2.5, 0.3}));
  EXPECT_FALSE(inside_outlines(loops, {0.8, 0.5}));
  EXPECT_FALSE(inside_outlines(loops, {1.5, 0.5}));
  // The fast index agrees with the plain test.
  const OutlineIndex index(loops);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> x(-0.5, 3.5), y(-0.5, 1.5);
  for (int k = 0; k < 2000; ++k) {
    const Point2 p(x(rng), y(rng));
    ASSERT_EQ(index.inside(p), inside_outlines(loops, p)) << p.transpose();
  }
  // A border that stops short leaves the outline open.
  atlas.borders[0].pop_back();
  EXPECT_THROW(chart_outlines(atlas), InvalidInput);
}

TEST(Atlas, RoundTripsThroughTbsFilesAsVersion2) {
  SplineFile f{two_maps(flat_left, flat_right), "mm", "{}"};
  f.atlas = sheet_atlas();
  f.atlas.seams[0].sharp = true;
  f.atlas.closed = false;
  f.atlas.genus = 0;
  f.atlas.borders.push_back({{0.1, 0.1}, {0.2, 0.1}});
  const std::string text = format_tbs(f);
  EXPECT_EQ(nlohmann::json::parse(text)["version"], 2);
  const SplineFile g = parse_tbs(text, "a.tbs");
  ASSERT_EQ(g.atlas.seams.size(), 1u);
  EXPECT_EQ(g.atlas.seams[0].a, f.atlas.seams[0].a);
  EXPECT_EQ(g.atlas.seams[0].b, f.atlas.seams[0].b);
  EXPECT_TRUE(g.atlas.seams[0].sharp);
  EXPECT_EQ(g.atlas.borders, f.atlas.borders);
  EXPECT_EQ(format_tbs(g), text);
  // Without an atlas the file stays version 1, as before atlases.
  f.atlas = {};
  EXPECT_EQ(nlohmann::json::parse(format_tbs(f))["version"], 1);
}

TEST(Atlas, MalformedAtlasesAreRefusedNamingTheField) {
  SplineFile f{two_maps(flat_left, flat_right), "mm", "{}"};
  f.atlas = sheet_atlas();
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(format_tbs(f));
  auto refused = [&](const nlohmann::ordered_json& k, const std::string& what) {
    try {
      parse_tbs(k.dump(), "bad.tbs");
      ADD_FAILURE() << "accepted: " << what;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  auto k = j;
  k["atlas"]["seams"][0]["b"].erase(0);
  refused(k, "bad.tbs: atlas.seams[0].b: expected 4 entries, got 3");
  k = j;
  k["atlas"]["seams"][0]["a"] = nlohmann::ordered_json::array({{0.75, 0.1}});
  k["atlas"]["seams"][0]["b"] = nlohmann::ordered_json::array({{2.25, 0.1}});
  refused(k, "bad.tbs: atlas.seams[0].a: a seam side needs at least 2 points");
  k = j;
  k["version"] = 1;
  refused(k, "bad.tbs: atlas: an atlas needs version 2");
  k = j;
  k["atlas"]["genus"] = -1;
  refused(k, "atlas.genus: -1 is negative");
  k = j;
  k["atlas"]["seams"][0]["sharp"] = "yes";
  refused(k, "atlas.seams[0].sharp: expected true or false");
  k = j;
  k["atlas"]["borders"] =
      nlohmann::ordered_json::array({nlohmann::ordered_json::array({{0.1, 0.1}})});
  refused(k, "atlas.borders[0]: a border needs at least 2 points");
}

TEST(Atlas, TheShapeCheckMeasuresEachTrimmedChartOnItsOwn) {
  // Chart 1 runs at speed 4 in u. Untrimmed, each chart's diameter (sqrt 2) is measured against
  // its own size; trimmed to the outlines, chart 1 is the part u in [2.25, 2.5], whose diameter
  // in (u, v) is the rectangle's, and whose size is 4 times as long in u.
  const Spline s =
      two_maps(flat_left, [](const Point2& u) { return Point3(4 * (u.x() - 2), u.y(), 0); });
  const Evaluator ev(s);
  Atlas atlas = sheet_atlas();
  atlas.seams[0].a = {{0.75, 0.25}, {0.75, 0.75}};
  atlas.seams[0].b = {{2.25, 0.25}, {2.25, 0.75}};
  atlas.borders.push_back({{0.75, 0.75}, {0.25, 0.75}, {0.25, 0.25}, {0.75, 0.25}});
  atlas.borders.push_back({{2.25, 0.25}, {2.5, 0.25}, {2.5, 0.75}, {2.25, 0.75}});
  const ShapeCheck whole = check_shape(s, ev), trimmed = check_shape(s, ev, 16, 0, 0, atlas);
  EXPECT_TRUE(whole.folded_triangles.empty());
  EXPECT_TRUE(trimmed.folded_triangles.empty());
  // Untrimmed: chart 1 spans 1 x 1 in (u, v) and 4 x 1 in space: 4 sqrt(2) / sqrt(17).
  EXPECT_NEAR(whole.max_stretch, 4 * std::sqrt(2.0) / std::sqrt(17.0), 1e-3);
  // Trimmed: chart 1 spans 0.25 x 0.5 in (u, v) and 1 x 0.5 in space: 4 sqrt(0.3125) / sqrt(1.25).
  EXPECT_NEAR(trimmed.max_stretch, 4 * std::sqrt(0.3125) / std::sqrt(1.25), 0.05);
}

}  // namespace
}  // namespace tbs
