#include <tbs/bezier.h>
#include <tbs/cad_export.h>
#include <tbs/cad_patches.h>
#include <tbs/cad_regions.h>
#include <tbs/errors.h>
#include <tbs/extract.h>
#include <tbs/io.h>

#include "cad_shapes.h"

#include <APIHeaderSection_MakeHeader.hxx>
#include <StepData_Protocol.hxx>
#include <StepData_StepModel.hxx>
#include <StepData_StepWriter.hxx>
#include <XSControl_TransferWriter.hxx>
#include <XSControl_WorkSession.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <BRepGProp.hxx>
#include <BRepLib.hxx>
#include <GProp_GProps.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <Geom_BSplineSurface.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <Transfer_FinderProcess.hxx>
#include <TColStd_HSequenceOfHAsciiString.hxx>
#include <TCollection_ExtendedString.hxx>
#include <IGESControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <STEPControl_Controller.hxx>
#include <STEPControl_Writer.hxx>
#include <ShapeAnalysis_FreeBounds.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Vertex.hxx>
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

// Every coordinate of the shape's geometry must be finite.
template <class Points>
void check_finite(const Points& points, const char* what) {
  for (const Point3& p : points)
    if (!p.allFinite()) throw InvalidInput(std::string("CAD export: a ") + what + " is not finite");
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

// Counts of the written shape: shells, edges, free edges and their connected chains.
void count_shape(const TopoDS_Shape& shape, CadExportReport& r) {
  for (TopExp_Explorer e(shape, TopAbs_SHELL); e.More(); e.Next()) ++r.shells;
  TopTools_IndexedDataMapOfShapeListOfShape faces_of;
  TopExp::MapShapesAndAncestors(shape, TopAbs_EDGE, TopAbs_FACE, faces_of);
  std::map<int, int> parent;  // union-find over vertex indices of free edges
  TopTools_IndexedMapOfShape vertices;
  auto find = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (int i = 1; i <= faces_of.Extent(); ++i) {
    const TopoDS_Edge& e = TopoDS::Edge(faces_of.FindKey(i));
    if (BRep_Tool::Degenerated(e)) continue;
    ++r.edges;
    if (faces_of(i).Extent() != 1) continue;
    ++r.free_edges;
    TopoDS_Vertex a, b;
    TopExp::Vertices(e, a, b);
    const int ia = vertices.Add(a), ib = vertices.Add(b);
    if (!parent.count(ia)) parent[ia] = ia;
    if (!parent.count(ib)) parent[ib] = ib;
    parent[find(ia)] = find(ib);
  }
  for (const auto& [v, up] : parent)
    if (find(v) == v) ++r.free_loops;
}

// The steps every CAD writer shares: check the unit, take OCCT's process-wide settings for
// this call, build and check the shell, let `write` translate it into the temporary file of
// an AtomicOutput (releasing the shape once translated: the text is built in memory, and the
// peak is the model and the text), commit, and turn OCCT's exceptions into ours.
template <class Build, class Write>
CadExportReport export_shape(const char* format, const std::string& path, const CadExportOptions& o, Build&& build,
                             Write&& write) {
  const auto t0 = std::chrono::steady_clock::now();
  const char* unit = occt_unit(o.units);
  std::lock_guard lock(occt_mutex);
  quiet_occt();
  auto say = [&](const std::string& line) {
    if (o.progress) o.progress(line);
  };
  try {
    CadExportReport r;
    detail::ShellResult shell = build();
    // A shell with no free edge bounds a volume: it becomes a solid, its faces turned to face
    // outward.
    if (shell.shell.ShapeType() == TopAbs_SHELL && BRep_Tool::IsClosed(shell.shell)) {
      TopoDS_Shell closed = TopoDS::Shell(shell.shell);
      closed.Closed(Standard_True);
      TopoDS_Solid solid;
      BRep_Builder builder;
      builder.MakeSolid(solid);
      builder.Add(solid, closed);
      BRepLib::OrientClosedSolid(solid);
      shell.shell = solid;
      r.solid = true;
    }
    r.faces = shell.faces;
    r.max_edge_tolerance = shell.max_edge_tolerance;
    r.build_seconds = seconds_since(t0);
    say("checking the shape (" + std::to_string(r.faces) + " faces)");
    const auto t1 = std::chrono::steady_clock::now();
    {
      // Scoped: its results for every sub-shape are not needed while writing (lion.off's
      // 202,473 exact pieces: 10.6 GB peak with them alive).
      BRepCheck_Analyzer check(shell.shell);
      if (!check.IsValid())
        throw Error("CAD export: the shape is not valid for OpenCASCADE (BRepCheck_Analyzer); nothing was written");
    }
    r.check_seconds = seconds_since(t1);
    count_shape(shell.shell, r);
    if (r.solid) {
      // Adaptive integration: the fixed Gauss rule, span by span of the trims, was 1.4 % off
      // on the egg's two faces of 130 x 130 poles (the adaptive one: 4e-4, as FreeCAD reads it).
      const auto tv = std::chrono::steady_clock::now();
      GProp_GProps props;
      BRepGProp::VolumeProperties(shell.shell, props, 1e-4);
      r.volume = props.Mass();
      r.volume_seconds = seconds_since(tv);
    }
    // The coordinates are already in `unit`: OCCT's session unit is set to the same, so it
    // writes them unscaled.
    Interface_Static::SetCVal("xstep.cascade.unit", unit);
    AtomicOutput out(path);
    write(shell.shell, unit, out.temp_path(), r);
    std::error_code ec;
    r.file_bytes = std::filesystem::file_size(out.temp_path(), ec);
    out.commit();
    r.seconds = seconds_since(t0);
    return r;
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

detail::ShellResult build(const CadRegions& r, const CadExportOptions& o) {
  if (r.faces.empty()) throw InvalidInput("CAD export: there are no faces to write");
  for (const RegionFace& f : r.faces) check_finite(f.surface.poles, "pole");
  for (const RegionEdge& e : r.edges) check_finite(e.curve.poles, "curve pole");
  if (o.progress) o.progress("building the shell of " + std::to_string(r.faces.size()) + " region faces");
  return detail::region_shell(r);
}

detail::ShellResult build(const CadPatches& c, const CadExportOptions& o) {
  if (c.degree < 1 || c.patches.empty()) throw InvalidInput("CAD export: there are no patches to write");
  check_finite(c.control_points, "control point");
  if (o.progress) o.progress("building the shell of " + std::to_string(c.patches.size()) + " patches");
  return detail::patch_shell(c, o.faces);
}

detail::ShellResult build(const Extraction& x, const CadExportOptions& o) {
  if (x.degree < 1 || x.pieces.empty()) throw InvalidInput("CAD export: there are no pieces to write");
  check_finite(x.control_points, "control point");
  if (o.progress) o.progress("building the shell of " + std::to_string(x.pieces.size()) + " exact pieces");
  return detail::patch_shell(detail::patches_of(x), o.faces);
}

void write_step_file(const std::string& path, TopoDS_Shape& shape, const char* unit, const std::string& temp,
                     const CadExportOptions& o, CadExportReport& r);
void write_iges_file(const std::string& path, TopoDS_Shape& shape, const char* unit, const std::string& temp,
                     const CadExportOptions& o, CadExportReport& r);

}  // namespace

namespace {

void write_step_file(const std::string& path, TopoDS_Shape& shape, const char* unit, const std::string& temp,
                     const CadExportOptions& o, CadExportReport& r) {
  {
    const auto t0 = std::chrono::steady_clock::now();
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
    // The map from shapes to STEP entities is not needed to write the model: freed first
    // (with the analyzer's results, a third of the peak on large shapes).
    writer.WS()->TransferWriter()->Clear(-1);
    shape.Nullify();
    r.translate_seconds = seconds_since(t0);
    if (o.progress) o.progress("writing the STEP file");
    const auto t1 = std::chrono::steady_clock::now();
    StepData_StepWriter step(model);
    step.SendModel(protocol);
    std::ofstream os(temp, std::ios::binary | std::ios::trunc);
    const bool printed = os && step.Print(os);
    os.close();
    if (!printed || !os) throw IoError(path + ": could not write the STEP file (disk full or no permission?)");
    r.write_seconds = seconds_since(t1);
  }
}

void write_iges_file(const std::string& path, TopoDS_Shape& shape, const char* unit, const std::string& temp,
                     const CadExportOptions& o, CadExportReport& r) {
  {
    const auto t0 = std::chrono::steady_clock::now();
    IGESControl_Controller::Init();
    Interface_Static::SetCVal("xstep.cascade.unit", unit);
    Interface_Static::SetCVal("write.iges.unit", unit);
    Interface_Static::SetIVal("write.iges.brep.mode", 1);
    if (o.progress) o.progress("translating to IGES");
    IGESControl_Writer writer(unit, 1);
    if (!writer.AddShape(shape)) throw Error("IGES export: OpenCASCADE could not translate the shape");
    writer.ComputeModel();
    // As for STEP: the map from shapes to IGES entities is not needed to write the model.
    writer.TransferProcess()->Clear();
    shape.Nullify();
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
    r.translate_seconds = seconds_since(t0);
    if (o.progress) o.progress("writing the IGES file");
    const auto t1 = std::chrono::steady_clock::now();
    std::ofstream os(temp, std::ios::binary | std::ios::trunc);
    const bool printed = os && writer.Write(os);
    os.close();
    if (!printed || !os) throw IoError(path + ": could not write the IGES file (disk full or no permission?)");
    r.write_seconds = seconds_since(t1);
  }
}

template <class Source>
CadExportReport step(const std::string& path, const Source& source, const CadExportOptions& o) {
  return export_shape(
      "STEP", path, o, [&] { return build(source, o); },
      [&](TopoDS_Shape& shape, const char* unit, const std::string& temp, CadExportReport& r) {
        write_step_file(path, shape, unit, temp, o, r);
      });
}

template <class Source>
CadExportReport iges(const std::string& path, const Source& source, const CadExportOptions& o) {
  return export_shape(
      "IGES", path, o, [&] { return build(source, o); },
      [&](TopoDS_Shape& shape, const char* unit, const std::string& temp, CadExportReport& r) {
        write_iges_file(path, shape, unit, temp, o, r);
      });
}

}  // namespace

CadExportReport write_step(const std::string& path, const CadRegions& r, const CadExportOptions& o) {
  return step(path, r, o);
}
CadExportReport write_step(const std::string& path, const CadPatches& c, const CadExportOptions& o) {
  return step(path, c, o);
}
CadExportReport write_step(const std::string& path, const Extraction& x, const CadExportOptions& o) {
  return step(path, x, o);
}
CadExportReport write_iges(const std::string& path, const CadRegions& r, const CadExportOptions& o) {
  return iges(path, r, o);
}
CadExportReport write_iges(const std::string& path, const CadPatches& c, const CadExportOptions& o) {
  return iges(path, c, o);
}
CadExportReport write_iges(const std::string& path, const Extraction& x, const CadExportOptions& o) {
  return iges(path, x, o);
}

}  // namespace tbs
