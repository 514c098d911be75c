// STEP and IGES files read back by OpenCASCADE: valid, one shell with shared edges, the faces
// we wrote, the boundary loops as free edges, and the surface within the CAD tolerance of our
// own evaluation. Region faces, triangle patches and exact pieces.
#include <tbs/cad_export.h>
#include <tbs/cad_patches.h>
#include <tbs/cad_regions.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/extract.h>
#include <tbs/io.h>
#include <tbs/knots.h>

#include "random_spline.h"

#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
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

// A 40 x 40 mm height field with a crease along x = 10 and a hole: the cases a scan has.
Spline sample_spline(int degree) {
  test::GridOptions o;
  o.nx = o.ny = 8;
  o.hole = true;
  o.feature_column = 2;
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

// Largest distance from our surface (at random parameters) to the read-back shape (to its
// trimmed faces, as OCCT measures it).
double surface_distance(const Spline& s, const TopoDS_Shape& shape, size_t points) {
  const Evaluator ev(s);
  double worst = 0;
  for (const Point2& u : test::random_domain_points(s.domain(), points, 5)) {
    const Point3 p = ev.value(u);
    BRepExtrema_DistShapeShape d(BRepBuilderAPI_MakeVertex(gp_Pnt(p.x(), p.y(), p.z())).Vertex(), shape);
    EXPECT_TRUE(d.IsDone());
    worst = std::max(worst, d.Value());
  }
  return worst;
}

// Edges with one face and with two faces.
std::pair<size_t, size_t> edge_faces(const TopoDS_Shape& shape) {
  TopTools_IndexedDataMapOfShapeListOfShape faces_of;
  TopExp::MapShapesAndAncestors(shape, TopAbs_EDGE, TopAbs_FACE, faces_of);
  size_t free = 0, shared = 0;
  for (int i = 1; i <= faces_of.Extent(); ++i) {
    if (BRep_Tool::Degenerated(TopoDS::Edge(faces_of.FindKey(i)))) continue;
    if (faces_of(i).Extent() == 1) ++free;
    if (faces_of(i).Extent() == 2) ++shared;
  }
  return {free, shared};
}

enum class Form { Regions, Triangles, Exact };

struct Case {
  std::string ext;
  Form form;
};

class CadExport : public ::testing::TestWithParam<Case> {};

std::string case_name(const ::testing::TestParamInfo<Case>& i) {
  const char* form[] = {"Regions", "Triangles", "Exact"};
  return std::string(i.param.ext == ".step" ? "Step" : "Iges") + form[static_cast<int>(i.param.form)];
}

TEST_P(CadExport, ReadsBackAsOneValidShellWithinTheCadTolerance) {
  const Form form = GetParam().form;
  // Degree 2 for the exact pieces keeps the face count (and OCCT's time) small.
  const Spline s = sample_spline(form == Form::Exact ? 2 : 3);
  TempDir dir;
  const fs::path file = dir.path / ("surface" + GetParam().ext);
  CadExportOptions o;
  o.product_name = "test bracket";
  o.description = "fit: max error 1.0e-03";
  const bool step = GetParam().ext == ".step";
  double tol = 0;
  size_t faces = 0;
  CadExportReport r;
  if (form == Form::Regions) {
    const CadRegions c = make_cad_regions(s, {.tolerance = 1e-4});
    ASSERT_TRUE(c.within_tolerance);
    ASSERT_EQ(c.faces.size(), 2u);  // the two flanks of the crease
    r = step ? write_step(file, c, o) : write_iges(file, c, o);
    tol = c.tolerance;
    faces = c.faces.size();
  } else if (form == Form::Triangles) {
    // A loose tolerance keeps the face count, and OCCT's time, small; the tight default is
    // checked against the spline in the converter tests.
    const CadPatches c = make_cad_patches(s, {.tolerance = 1e-3, .angle_tolerance = 3});
    RecordProperty("patches", static_cast<int>(c.patches.size()));
    ASSERT_TRUE(c.within_tolerance);
    r = step ? write_step(file, c, o) : write_iges(file, c, o);
    tol = c.tolerance;
    faces = 3 * c.patches.size();
  } else {
    const Extraction x = extract_bezier(s);
    r = step ? write_step(file, x, o) : write_iges(file, x, o);
    tol = 1e-9 * 60;
    faces = 3 * x.pieces.size();
  }
  EXPECT_EQ(r.faces, faces);
  EXPECT_EQ(r.shells, 1u);
  EXPECT_EQ(r.free_loops, s.domain().boundary_loops().size()) << "the outer boundary and the hole";
  EXPECT_GT(r.file_bytes, 0u);
  const TopoDS_Shape shape = read_back(file);
  ASSERT_FALSE(shape.IsNull());
  EXPECT_TRUE(BRepCheck_Analyzer(shape).IsValid());
  EXPECT_EQ(count(shape, TopAbs_FACE), r.faces);
  EXPECT_EQ(count(shape, TopAbs_SHELL), 1u);
  const auto [free, shared] = edge_faces(shape);
  EXPECT_EQ(free, r.free_edges);
  if (form == Form::Regions) {
    EXPECT_EQ(shared, 1u) << "the crease is one edge of both flanks";
  }
  const double d = surface_distance(s, shape, form == Form::Exact ? 40 : 150);
  EXPECT_LE(d, tol + 1e-7) << "largest distance " << d;
  // The names travel in the file.
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (step) {
    EXPECT_NE(text.find("test bracket"), std::string::npos);
    EXPECT_NE(text.find("fit: max error 1.0e-03"), std::string::npos);
    EXPECT_NE(text.find("AUTOMOTIVE_DESIGN"), std::string::npos);  // AP214
    if (form == Form::Regions) {
      EXPECT_NE(text.find("ADVANCED_FACE"), std::string::npos);
      EXPECT_NE(text.find("B_SPLINE_SURFACE_WITH_KNOTS"), std::string::npos);
      EXPECT_NE(text.find("EDGE_LOOP"), std::string::npos);
    }
  } else {
    EXPECT_NE(text.find("12Htest bracket"), std::string::npos);     // global section
    EXPECT_NE(text.find("fit: max error 1.0e-03"), std::string::npos);  // start section
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, CadExport,
                         ::testing::Values(Case{".step", Form::Regions}, Case{".iges", Form::Regions},
                                           Case{".step", Form::Triangles}, Case{".iges", Form::Triangles},
                                           Case{".step", Form::Exact}, Case{".iges", Form::Exact}),
                         case_name);

TEST(CadExport, CollapsedFacesAndAp242AndInches) {
  const Spline s = sample_spline(3);
  const CadPatches c = make_cad_patches(s, {.tolerance = 1e-4});
  TempDir dir;
  const fs::path file = dir.path / "collapsed.step";
  CadExportOptions o;
  o.faces = TriangleFaces::Collapsed;
  o.schema = StepSchema::AP242;
  o.units = "in";
  const CadExportReport r = write_step(file, c, o);
  EXPECT_EQ(r.faces, c.patches.size());
  EXPECT_EQ(r.shells, 1u);
  EXPECT_TRUE(BRepCheck_Analyzer(read_back(file)).IsValid());
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("AP242"), std::string::npos);
  EXPECT_NE(text.find("INCH"), std::string::npos);
}

TEST(CadExport, AFailedExportLeavesNoFileAndKeepsAnOldOne) {
  TempDir dir;
  const fs::path good = dir.path / "good.step";
  { std::ofstream(good) << "old contents"; }
  const Spline s = sample_spline(2);
  const CadPatches one = make_cad_patches(s, {.tolerance = 1e-2, .angle_tolerance = 20});
  EXPECT_THROW(write_step(good, CadPatches{}), InvalidInput);
  EXPECT_THROW(write_step(good, CadRegions{}), InvalidInput);
  EXPECT_THROW(write_step(good, Extraction{}), InvalidInput);
  CadExportOptions furlong;
  furlong.units = "furlong";
  EXPECT_THROW(write_step(good, one, furlong), InvalidInput);
  CadPatches nan = one;
  nan.control_points[1].x() = std::nan("");
  EXPECT_THROW(write_iges(good, nan), InvalidInput);
  CadRegions regions = make_cad_regions(s, {.tolerance = 1e-3});
  regions.faces[0].surface.poles[0].y() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(write_step(good, regions), InvalidInput);
  std::ifstream in(good);
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "old contents");
  EXPECT_THROW(write_iges(dir.path / "missing" / "x.igs", one), IoError);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path), fs::directory_iterator()), 1);
  // And the same patches write fine where they can.
  EXPECT_EQ(write_step(dir.path / "one.step", one).faces, 3 * one.patches.size());
}

}  // namespace
}  // namespace tbs
