#include <tbs/bezier.h>
#include <tbs/cad_export.h>
#include <tbs/cad_patches.h>
#include <tbs/errors.h>
#include <tbs/extract.h>
#include <tbs/io.h>

#include <APIHeaderSection_MakeHeader.hxx>
#include <StepData_Protocol.hxx>
#include <StepData_StepModel.hxx>
#include <StepData_StepWriter.hxx>
#include <XSControl_WorkSession.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <Geom_BSplineSurface.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <TColStd_HSequenceOfHAsciiString.hxx>
#include <TCollection_ExtendedString.hxx>
#include <IGESControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_ProgressIndicator.hxx>
#include <Message_ProgressScope.hxx>
#include <STEPControl_Controller.hxx>
#include <STEPControl_Writer.hxx>
#include <ShapeAnalysis_FreeBounds.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>

#include <chrono>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <typeinfo>

namespace tbs {

size_t TrianglePatchSet::size() const {
  return degree >= 0 ? control_points.size() / static_cast<size_t>(beta_count(degree)) : 0;
}

TrianglePatchSet patch_set(const CadPatches& p) { return {p.degree, p.control_points}; }
TrianglePatchSet patch_set(const Extraction& x) { return {x.degree, x.control_points}; }

namespace {

// OCCT's static parameters are process-wide: one export at a time.
std::mutex occt_mutex;

// Our unit names -> the names OCCT's STEP and IGES writers use.
const char* occt_unit(const std::string& u) {
  static const std::map<std::string, const char*> names = {
      {"mm", "MM"}, {"cm", "CM"}, {"m", "M"}, {"um", "UM"}, {"in", "INCH"}, {"ft", "FT"}};
  const auto it = names.find(u);
  if (it == names.end())
    throw InvalidInput("unit '" + u + "' cannot be written to STEP or IGES: use mm, cm, m, um, in or ft");
  return it->second;
}

Handle(Geom_BSplineSurface) bspline(std::span<const Point3> cps, int m) {
  TColgp_Array2OfPnt poles(1, m + 1, 1, m + 1);
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i <= m; ++i) {
      const Point3& p = cps[static_cast<size_t>(i + (m + 1) * j)];
      poles.SetValue(i + 1, j + 1, gp_Pnt(p.x(), p.y(), p.z()));
    }
  TColStd_Array1OfReal knots(1, 2);
  knots.SetValue(1, 0.0);
  knots.SetValue(2, 1.0);
  TColStd_Array1OfInteger mults(1, 2);
  mults.SetValue(1, m + 1);
  mults.SetValue(2, m + 1);
  return new Geom_BSplineSurface(poles, knots, knots, mults, mults, m, m);
}

// OCCT's progress (sewing) as lines "<what>: N %", every 10 %. An exception from the callback
// must not unwind through OCCT (its scopes report again while unwinding): it is kept, the
// operation is asked to stop (UserBreak), and rethrow() raises it afterwards.
class SayProgress : public Message_ProgressIndicator {
 public:
  SayProgress(std::function<void(const std::string&)> say, std::string what)
      : say_(std::move(say)), what_(std::move(what)) {}
  void Show(const Message_ProgressScope&, const Standard_Boolean) override {
    const int percent = static_cast<int>(GetPosition() * 100);
    if (percent < next_ || error_) return;
    next_ = percent / 10 * 10 + 10;
    try {
      say_(what_ + ": " + std::to_string(percent / 10 * 10) + " %");
    } catch (...) {
      error_ = std::current_exception();
    }
  }
  Standard_Boolean UserBreak() override { return error_ != nullptr; }
  void rethrow() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  std::function<void(const std::string&)> say_;
  std::string what_;
  int next_ = 10;
  std::exception_ptr error_;
};

struct Built {
  TopoDS_Shape shape;
  CadExportReport report;
};

Built build_shape(const TrianglePatchSet& ps, const CadExportOptions& o) {
  const int m = ps.degree;
  if (m < 1 || ps.size() == 0) throw InvalidInput("CAD export: there are no patches to write");
  Box3 box;
  for (const Point3& p : ps.control_points) {
    if (!p.allFinite()) throw InvalidInput("CAD export: a control point is not finite");
    box.extend(p);
  }
  const double size = std::max((box.max - box.min).norm(), 1e-300);
  Built b;
  b.report.sewing_tolerance = o.sewing_tolerance > 0 ? o.sewing_tolerance : 1e-7 * size;
  BRepBuilderAPI_Sewing sewing(b.report.sewing_tolerance);
  const size_t nb = static_cast<size_t>(beta_count(m));
  auto say = [&](const std::string& line) {
    if (o.progress) o.progress(line);
  };
  say("making the B-spline faces of " + std::to_string(ps.size()) + " patches");
  for (size_t p = 0; p < ps.size(); ++p) {
    const std::span<const Point3> net(ps.control_points.data() + p * nb, nb);
    std::vector<std::vector<Point3>> quads;
    if (o.faces == TriangleFaces::Quads) {
      const auto q = bezier_triangle_to_quads(net, m);
      quads.assign(q.begin(), q.end());
    } else {
      quads.push_back(bezier_triangle_to_collapsed_quad(net, m));
    }
    for (const auto& q : quads) {
      BRepBuilderAPI_MakeFace face(bspline(q, m), Precision::Confusion());
      if (!face.IsDone()) throw Error("CAD export: OpenCASCADE could not make a face of patch " + std::to_string(p));
      sewing.Add(face.Face());
      ++b.report.faces;
    }
  }
  say("sewing " + std::to_string(b.report.faces) + " faces");
  if (o.progress) {
    Handle(SayProgress) indicator = new SayProgress(o.progress, "sewing");
    sewing.Perform(indicator->Start());
    indicator->rethrow();
  } else {
    sewing.Perform();
  }
  b.shape = sewing.SewedShape();
  for (TopExp_Explorer e(b.shape, TopAbs_SHELL); e.More(); e.Next()) ++b.report.shells;
  b.report.free_edges = static_cast<size_t>(sewing.NbFreeEdges());
  say("checking the shape");
  BRepCheck_Analyzer check(b.shape);
  if (!check.IsValid())
    throw Error("CAD export: the sewn shape is not valid for OpenCASCADE (BRepCheck_Analyzer); nothing was written");
  return b;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void quiet_occt() {
  // OCCT prints translation chatter to stdout; tbs keeps stdout for its own results.
  static std::once_flag once;
  std::call_once(once, [] { Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer)); });
}

}  // namespace

namespace {

// A name for STEP and IGES text fields, which OCCT writes byte for byte although both formats
// want plain ASCII there: each other character (UTF-8 decoded by OCCT; invalid bytes become
// U+FFFD first) is replaced by '_', control characters included.
std::string ascii_name(const std::string& text) {
  const TCollection_ExtendedString wide(valid_utf8(text).c_str(), Standard_True);
  std::string out;
  for (int i = 1; i <= wide.Length(); ++i) {
    const Standard_ExtCharacter c = wide.Value(i);
    if (c >= 0xDC00 && c <= 0xDFFF) continue;  // second half of a surrogate pair
    out += c >= 0x20 && c < 0x7F ? static_cast<char>(c) : '_';
  }
  return out;
}

// The steps every CAD writer shares: check the unit, take OCCT's process-wide settings for
// this call, build and check the shape, let `write` translate it into the temporary file of
// an AtomicOutput, commit, and turn OCCT's exceptions into ours.
template <class Write>
CadExportReport export_shape(const char* format, const std::string& path, const TrianglePatchSet& ps,
                             const CadExportOptions& o, Write&& write) {
  const auto t0 = std::chrono::steady_clock::now();
  const char* unit = occt_unit(o.units);
  std::lock_guard lock(occt_mutex);
  quiet_occt();
  try {
    Built b = build_shape(ps, o);
    // The coordinates are already in `unit`: OCCT's session unit is set to the same, so it
    // writes them unscaled.
    Interface_Static::SetCVal("xstep.cascade.unit", unit);
    AtomicOutput out(path);
    write(b.shape, unit, out.temp_path());
    out.commit();
    b.report.seconds = seconds_since(t0);
    return b.report;
  } catch (const Standard_Failure& e) {
    throw Error(path + ": " + format + " export: OpenCASCADE failed: " + e.GetMessageString());
  } catch (const IoError&) {
    throw;
  } catch (const Error& e) {
    // Shape building and translation name no file.
    if (typeid(e) != typeid(Error)) throw;
    throw Error(path + ": " + e.what());
  }
}

}  // namespace

CadExportReport write_step(const std::string& path, const TrianglePatchSet& ps, const CadExportOptions& o) {
  return export_shape("STEP", path, ps, o, [&](const TopoDS_Shape& shape, const char* unit, const std::string& temp) {
    STEPControl_Controller::Init();
    Interface_Static::SetCVal("xstep.cascade.unit", unit);
    Interface_Static::SetCVal("write.step.unit", unit);
    Interface_Static::SetCVal("write.step.schema", o.schema == StepSchema::AP242 ? "AP242DIS" : "AP214IS");
    const std::string product = ascii_name(o.product_name), description = ascii_name(o.description);
    Interface_Static::SetCVal("write.step.product.name", product.c_str());
    STEPControl_Writer writer;
    if (o.progress) o.progress("translating to STEP");
    if (writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone)
      throw Error("STEP export: OpenCASCADE could not translate the shape");
    APIHeaderSection_MakeHeader header(writer.Model());
    header.SetName(new TCollection_HAsciiString(product.c_str()));
    header.SetOriginatingSystem(new TCollection_HAsciiString("tbs"));
    header.SetAuthorValue(1, new TCollection_HAsciiString("tbs"));
    header.SetOrganizationValue(1, new TCollection_HAsciiString(""));
    header.SetAuthorisation(new TCollection_HAsciiString(""));
    if (!description.empty()) header.SetDescriptionValue(1, new TCollection_HAsciiString(description.c_str()));
    // Written through our own stream: OCCT's Write(filename) decodes the path as UTF-8, so a
    // name with other bytes (legal on Linux) went to a different file.
    const Handle(StepData_StepModel) model = writer.Model();
    const Handle(StepData_Protocol) protocol = Handle(StepData_Protocol)::DownCast(writer.WS()->Protocol());
    if (model.IsNull() || protocol.IsNull()) throw Error("STEP export: OpenCASCADE has no STEP model to write");
    if (o.progress) o.progress("writing the STEP file");
    StepData_StepWriter step(model);
    step.SendModel(protocol);
    std::ofstream os(temp, std::ios::binary | std::ios::trunc);
    const bool printed = os && step.Print(os);
    os.close();
    if (!printed || !os) throw IoError(path + ": could not write the STEP file (disk full or no permission?)");
  });
}

CadExportReport write_iges(const std::string& path, const TrianglePatchSet& ps, const CadExportOptions& o) {
  return export_shape("IGES", path, ps, o, [&](const TopoDS_Shape& shape, const char* unit, const std::string& temp) {
    IGESControl_Controller::Init();
    Interface_Static::SetCVal("xstep.cascade.unit", unit);
    Interface_Static::SetCVal("write.iges.unit", unit);
    Interface_Static::SetIVal("write.iges.brep.mode", 1);
    if (o.progress) o.progress("translating to IGES");
    IGESControl_Writer writer(unit, 1);
    if (!writer.AddShape(shape)) throw Error("IGES export: OpenCASCADE could not translate the shape");
    writer.ComputeModel();
    // Global section: product, file name, sender; the description goes into the start
    // section, in lines of at most 72 characters.
    IGESData_GlobalSection& g = writer.Model()->ChangeGlobalSection();
    const std::string product = ascii_name(o.product_name), description = ascii_name(o.description);
    g.SetSendName(new TCollection_HAsciiString(product.c_str()));
    g.SetFileName(new TCollection_HAsciiString(ascii_name(std::filesystem::path(path).filename().string()).c_str()));
    g.SetSystemId(new TCollection_HAsciiString("tbs"));
    g.SetAuthorName(new TCollection_HAsciiString("tbs"));
    Handle(TColStd_HSequenceOfHAsciiString) start = new TColStd_HSequenceOfHAsciiString;
    const std::string text = product + (description.empty() ? "" : ": " + description);
    for (size_t i = 0; i < text.size(); i += 72)
      start->Append(new TCollection_HAsciiString(text.substr(i, 72).c_str()));
    writer.Model()->SetStartSection(start);
    if (o.progress) o.progress("writing the IGES file");
    std::ofstream os(temp, std::ios::binary | std::ios::trunc);
    const bool printed = os && writer.Write(os);
    os.close();
    if (!printed || !os) throw IoError(path + ": could not write the IGES file (disk full or no permission?)");
  });
}

}  // namespace tbs
