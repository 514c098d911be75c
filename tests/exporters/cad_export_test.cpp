// STEP and IGES files read back by OpenCASCADE: valid, one shell, the faces we wrote, and the
// surface within the CAD tolerance of our own evaluation.
#include <tbs/cad_export.h>
#include <tbs/cad_patches.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/extract.h>
#include <tbs/io.h>
#include <tbs/knots.h>

#include "random_spline.h"

#include <BRepBndLib.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <Geom_Surface.hxx>
#include <TopoDS.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <IGESControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS_Shape.hxx>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace tbs {
namespace {

namespace fs = std::filesystem;

// A 40 x 40 mm height field with a crease along x = 20 and a hole: the cases a scan has.
Spline sample_spline(int degree) {
  test::GridOptions o;
  o.nx = o.ny = 4;
  o.hole = true;
  o.feature_column = 1;
  const Spline r = test::random_spline(degree, o, 61);
  Spline s(degree, r.domain(), default_knots(r.domain(), degree), r.control_points(), r.control_point_map());
  for (int t = 0; t < s.domain().triangle_count(); ++t)
    for (int i = 0; i < beta_count(degree); ++i) {
      const Point2 b = s.blossom_point(t, beta_at(degree, i));
      const double z = 4 * std::sin(3 * b.x()) * std::cos(2 * b.y()) + 10 * std::fabs(b.x() - 0.25);
      s.control_points()[s.control_point_index(t, i)] = Point3(40 * b.x(), 40 * b.y(), z);
    }
  return s;
}

struct TempDir {
  fs::path path = fs::temp_directory_path() / ("tbs_export_test_" + std::to_string(::getpid()));
  TempDir() { fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
};

TopoDS_Shape read_back(const fs::path& file) {
  if (file.extension() == ".step") {
    STEPControl_Reader r;
    EXPECT_EQ(r.ReadFile(file.c_str()), IFSelect_RetDone);
    r.TransferRoots();
    return r.OneShape();
  }
  IGESControl_Reader r;
  EXPECT_EQ(r.ReadFile(file.c_str()), IFSelect_RetDone);
  r.TransferRoots();
  return r.OneShape();
}

size_t count(const TopoDS_Shape& s, TopAbs_ShapeEnum kind) {
  size_t n = 0;
  for (TopExp_Explorer e(s, kind); e.More(); e.Next()) ++n;
  return n;
}

// Largest distance from our surface (at random parameters) to the read-back shape: the
// nearest projection onto the surfaces of the faces whose boxes are near the point (the faces
// have natural bounds, so the projection onto the surface is onto the face).
double surface_distance(const Spline& s, const TopoDS_Shape& shape, size_t points) {
  const Evaluator ev(s);
  std::vector<std::pair<Bnd_Box, Handle(Geom_Surface)>> faces;
  for (TopExp_Explorer e(shape, TopAbs_FACE); e.More(); e.Next()) {
    Bnd_Box box;
    BRepBndLib::Add(e.Current(), box);
    box.Enlarge(1e-3);
    faces.emplace_back(box, BRep_Tool::Surface(TopoDS::Face(e.Current())));
  }
  double worst = 0;
  for (const Point2& u : test::random_domain_points(s.domain(), points, 5)) {
    const Point3 p = ev.value(u);
    const gp_Pnt q(p.x(), p.y(), p.z());
    double best = 1e300;
    for (const auto& [box, surface] : faces) {
      if (box.IsOut(q)) continue;
      GeomAPI_ProjectPointOnSurf proj(q, surface);
      if (proj.NbPoints() > 0) best = std::min(best, proj.LowerDistance());
    }
    worst = std::max(worst, best);
  }
  return worst;
}

struct Case {
  std::string ext;
  bool exact;
};

class CadExport : public ::testing::TestWithParam<Case> {};

TEST_P(CadExport, ReadsBackAsOneValidShellWithinTheCadTolerance) {
  const bool exact = GetParam().exact;
  // Degree 2 for the exact pieces keeps the face count (and OCCT's sewing time) small.
  const Spline s = sample_spline(exact ? 2 : 3);
  TrianglePatchSet ps;
  double tol = 0;
  if (exact) {
    ps = patch_set(extract_bezier(s));
    tol = 1e-9 * 60;
  } else {
    // A loose tolerance keeps the face count, and OCCT's time, small; the tight default is
    // checked against the spline in the converter tests.
    const CadPatches c = make_cad_patches(s, {.tolerance = 1e-3, .angle_tolerance = 3});
    RecordProperty("patches", static_cast<int>(c.patches.size()));
    ASSERT_TRUE(c.within_tolerance);
    ps = patch_set(c);
    tol = c.tolerance;
  }
  TempDir dir;
  const fs::path file = dir.path / ("surface" + GetParam().ext);
  CadExportOptions o;
  o.product_name = "test bracket";
  o.description = "fit: max error 1.0e-03";
  const CadExportReport r = GetParam().ext == ".step" ? write_step(file, ps, o) : write_iges(file, ps, o);
  EXPECT_EQ(r.faces, 3 * ps.size());
  EXPECT_EQ(r.shells, 1u);
  const TopoDS_Shape shape = read_back(file);
  ASSERT_FALSE(shape.IsNull());
  EXPECT_TRUE(BRepCheck_Analyzer(shape).IsValid());
  EXPECT_EQ(count(shape, TopAbs_FACE), r.faces);
  EXPECT_EQ(count(shape, TopAbs_SHELL), 1u);
  const double d = surface_distance(s, shape, 300);
  EXPECT_LE(d, tol + r.sewing_tolerance) << "largest distance " << d;
  // The names travel in the file.
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (GetParam().ext == ".step") {
    EXPECT_NE(text.find("test bracket"), std::string::npos);
    EXPECT_NE(text.find("fit: max error 1.0e-03"), std::string::npos);
    EXPECT_NE(text.find("AUTOMOTIVE_DESIGN"), std::string::npos);  // AP214
  } else {
    EXPECT_NE(text.find("12Htest bracket"), std::string::npos);     // global section
    EXPECT_NE(text.find("fit: max error 1.0e-03"), std::string::npos);  // start section
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, CadExport,
                         ::testing::Values(Case{".step", false}, Case{".iges", false}, Case{".step", true},
                                           Case{".iges", true}),
                         [](const auto& i) { return std::string(i.param.ext == ".step" ? "Step" : "Iges") + (i.param.exact ? "Exact" : "Compact"); });

TEST(CadExport, CollapsedFacesAndAp242AndInches) {
  const Spline s = sample_spline(3);
  const CadPatches c = make_cad_patches(s, {.tolerance = 1e-4});
  TempDir dir;
  const fs::path file = dir.path / "collapsed.step";
  CadExportOptions o;
  o.faces = TriangleFaces::Collapsed;
  o.schema = StepSchema::AP242;
  o.units = "in";
  const CadExportReport r = write_step(file, patch_set(c), o);
  EXPECT_EQ(r.faces, c.patches.size());
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("AP242"), std::string::npos);
  EXPECT_NE(text.find("INCH"), std::string::npos);
}

TEST(CadExport, AFailedExportLeavesNoFileAndKeepsAnOldOne) {
  TempDir dir;
  const fs::path good = dir.path / "good.step";
  { std::ofstream(good) << "old contents"; }
  // One flat degree-1 triangle is enough to reach the writers.
  const TrianglePatchSet one{1, {Point3(0, 0, 0), Point3(1, 0, 0), Point3(0, 1, 0)}};
  EXPECT_THROW(write_step(good, TrianglePatchSet{3, {}}), InvalidInput);
  CadExportOptions furlong;
  furlong.units = "furlong";
  EXPECT_THROW(write_step(good, one, furlong), InvalidInput);
  const TrianglePatchSet nan{1, {Point3(0, 0, 0), Point3(std::nan(""), 0, 0), Point3(0, 1, 0)}};
  EXPECT_THROW(write_iges(good, nan), InvalidInput);
  std::ifstream in(good);
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "old contents");
  EXPECT_THROW(write_iges(dir.path / "missing" / "x.igs", one), IoError);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path), fs::directory_iterator()), 1);
  // And the same patch writes fine where it can.
  EXPECT_EQ(write_step(dir.path / "one.step", one).faces, 3u);
}

}  // namespace
}  // namespace tbs
