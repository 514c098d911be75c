// The Python module `tbs` (pybind11): fit, evaluate, tessellate and export with NumPy arrays.
// docs/python.md documents it; tests/python/ tests it in Debian's python3 and inside FreeCAD.
#include <tbs/convert.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/fit.h>
#include <tbs/io.h>
#include <tbs/mesh_export.h>
#include <tbs/parameterize.h>
#include <tbs/scan.h>
#include <tbs/tessellate.h>

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <stop_token>
#include <string>
#include <vector>

namespace py = pybind11;

namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

// An (N, k) array of doubles, checked.
Array checked(const Array& a, py::ssize_t columns, const char* what) {
  if (a.ndim() != 2 || a.shape(1) != columns) {
    std::string shape;
    for (py::ssize_t k = 0; k < a.ndim(); ++k) shape += (k ? ", " : "") + std::to_string(a.shape(k));
    throw tbs::InvalidInput(std::string(what) + " must be an array of shape (N, " + std::to_string(columns) +
                            "), got shape (" + shape + ")");
  }
  return a;
}

template <class V>
Array to_array(const std::vector<V>& v, py::ssize_t columns) {
  Array a({static_cast<py::ssize_t>(v.size()), columns});
  auto m = a.mutable_unchecked<2>();
  for (size_t i = 0; i < v.size(); ++i)
    for (py::ssize_t k = 0; k < columns; ++k) m(static_cast<py::ssize_t>(i), k) = v[i][k];
  return a;
}

py::array_t<int> faces_array(const std::vector<std::array<int, 3>>& faces) {
  py::array_t<int> a({static_cast<py::ssize_t>(faces.size()), py::ssize_t{3}});
  auto m = a.mutable_unchecked<2>();
  for (size_t i = 0; i < faces.size(); ++i)
    for (int k = 0; k < 3; ++k) m(static_cast<py::ssize_t>(i), k) = faces[i][k];
  return a;
}

py::object json_loads(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

std::vector<tbs::Point2> points2(const py::handle& h, const std::string& what) {
  const Array a = checked(py::cast<Array>(h), 2, what.c_str());
  auto r = a.unchecked<2>();
  std::vector<tbs::Point2> out;
  for (py::ssize_t i = 0; i < a.shape(0); ++i) out.emplace_back(r(i, 0), r(i, 1));
  return out;
}

// An atlas as a dict: closed, genus, seams (a, b, sharp), borders; and back.
py::dict atlas_dict(const tbs::Atlas& atlas) {
  py::list seams, borders;
  for (const tbs::Seam& s : atlas.seams) {
    py::dict d;
    d["a"] = to_array(s.a, 2);
    d["b"] = to_array(s.b, 2);
    d["sharp"] = s.sharp;
    seams.append(d);
  }
  for (const auto& b : atlas.borders) borders.append(to_array(b, 2));
  py::dict d;
  d["closed"] = atlas.closed;
  d["genus"] = atlas.genus;
  d["seams"] = seams;
  d["borders"] = borders;
  return d;
}

tbs::Atlas atlas_from(const py::dict& d) {
  tbs::Atlas atlas;
  if (d.contains("closed")) atlas.closed = d["closed"].cast<bool>();
  if (d.contains("genus")) atlas.genus = d["genus"].cast<int>();
  if (d.contains("seams"))
    for (const py::handle& h : d["seams"].cast<py::list>()) {
      const py::dict sd = h.cast<py::dict>();
      tbs::Seam s;
      s.a = points2(sd["a"], "atlas seam a");
      s.b = points2(sd["b"], "atlas seam b");
      if (sd.contains("sharp")) s.sharp = sd["sharp"].cast<bool>();
      atlas.seams.push_back(std::move(s));
    }
  if (d.contains("borders"))
    for (const py::handle& h : d["borders"].cast<py::list>()) atlas.borders.push_back(points2(h, "atlas border"));
  tbs::check_atlas_structure(atlas, "atlas");
  return atlas;
}

// A fitted or loaded spline with its evaluator (built on first use).
class PySpline {
 public:
  PySpline(tbs::Spline spline, std::string report_json, std::string units, tbs::Atlas atlas = {})
      : spline_(std::make_unique<tbs::Spline>(std::move(spline))), report_(std::move(report_json)),
        units_(std::move(units)), atlas_(std::move(atlas)) {}

  py::dict atlas() const { return atlas_dict(atlas_); }
  py::list outlines() const {
    py::list out;
    for (const auto& loop : tbs::chart_outlines(atlas_)) out.append(to_array(loop, 2));
    return out;
  }
  // The seams' agreement (check_seams): gap and normal angles, per seam too.
  py::dict check_seams(int samples) const {
    tbs::SeamCheck c;
    {
      py::gil_scoped_release release;
      c = tbs::check_seams(*spline_, evaluator(), atlas_, samples);
    }
    py::dict d;
    d["samples"] = c.samples;
    d["outside"] = c.outside;
    d["max_gap"] = c.max_gap;
    d["max_normal_jump"] = c.max_normal_jump;
    d["min_crease"] = c.min_crease;
    d["max_crease"] = c.max_crease;
    d["seam_gap"] = c.seam_gap;
    d["seam_angle"] = c.seam_angle;
    return d;
  }

  int degree() const { return spline_->degree(); }
  int triangle_count() const { return spline_->domain().triangle_count(); }
  Array control_points() const { return to_array(spline_->control_points(), 3); }
  py::object report() const { return report_.empty() ? py::none() : json_loads(report_); }
  const std::string& units() const { return units_; }

  // F(u) at every row of uv; with derivatives also F_u and F_v. Points outside the domain
  // raise OutsideDomain (naming the row) unless outside="nan".
  py::object evaluate(const Array& uv_in, bool derivatives, const std::string& outside) const {
    const Array uv = checked(uv_in, 2, "uv");
    if (outside != "raise" && outside != "nan")
      throw tbs::InvalidInput("outside must be 'raise' or 'nan', got '" + outside + "'");
    const size_t n = static_cast<size_t>(uv.shape(0));
    std::vector<tbs::Point2> u(n);
    auto r = uv.unchecked<2>();
    for (size_t i = 0; i < n; ++i) u[i] = tbs::Point2(r(i, 0), r(i, 1));
    std::vector<tbs::Point3> p(n);
    std::vector<tbs::Vector3> du(derivatives ? n : 0), dv(derivatives ? n : 0);
    std::vector<uint8_t> inside(n);
    {
      py::gil_scoped_release release;
      evaluator().evaluate_batch(u, p, du, dv, inside);
    }
    if (outside == "raise")
      for (size_t i = 0; i < n; ++i)
        if (!inside[i])
          throw tbs::OutsideDomain("uv[" + std::to_string(i) + "] = (" + std::to_string(u[i].x()) + ", " +
                                   std::to_string(u[i].y()) +
                                   ") is outside the spline's domain; pass outside='nan' to get NaN there");
    if (!derivatives) return to_array(p, 3);
    return py::make_tuple(to_array(p, 3), to_array(du, 3), to_array(dv, 3));
  }

  py::dict tessellate(double chordal_tolerance, int resolution) const {
    tbs::TessellateOptions o;
    if (resolution > 0) {
      o.resolution = resolution;
    } else {
      o.chordal_tolerance = chordal_tolerance;
    }
    tbs::Mesh m;
    {
      py::gil_scoped_release release;
      m = tbs::tessellate(*spline_, o);
    }
    py::dict d;
    d["positions"] = to_array(m.positions, 3);
    d["normals"] = to_array(m.normals, 3);
    d["uv"] = to_array(m.parameters, 2);
    d["faces"] = faces_array(m.faces);
    d["max_chordal_deviation"] = m.max_chordal_deviation;
    return d;
  }

  void save(const std::string& path) const {
    tbs::SplineFile f{*spline_, units_ == "" ? "unitless" : units_, report_.empty() ? "{}" : report_};
    f.atlas = atlas_;
    tbs::write_tbs(path, f);
  }

  // Any format `tbs convert` writes, through the same tbs::convert(); returns its report.
  py::dict export_file(const std::string& path, const std::string& faces, double cad_tolerance,
                       double angle_tolerance, int face_degree, long max_poles, int patch_degree, long max_patches,
                       bool exact, const std::string& units, double chordal_tolerance, int threads) const {
    tbs::ConvertOptions o;
    if (exact || faces == "exact") {
      o.faces = tbs::CadFaceForm::Exact;
    } else if (faces == "triangles") {
      o.faces = tbs::CadFaceForm::Triangles;
    } else if (faces != "regions") {
      throw tbs::InvalidInput("faces must be 'regions', 'triangles' or 'exact', not '" + faces + "'");
    }
    o.cad_tolerance = cad_tolerance;
    o.angle_tolerance = angle_tolerance;
    o.face_degree = face_degree;
    o.max_poles = max_poles;
    o.patch_degree = patch_degree;
    o.max_patches = max_patches;
    o.units = units;
    o.chordal_tolerance = chordal_tolerance;
    o.threads = threads;
    // A spline fitted here carries its fit report; convert() reads the fit's tolerance from
    // the metadata as `tbs fit` writes it, under "fit".
    std::string meta = report_.empty() ? "{}" : report_;
    {
      py::module_ json_module = py::module_::import("json");
      py::object d = json_module.attr("loads")(meta);
      if (py::isinstance<py::dict>(d) && !d.contains("fit") && d.contains("tolerance_abs")) {
        py::dict wrapped;
        wrapped["fit"] = d;
        meta = json_module.attr("dumps")(wrapped).cast<std::string>();
      }
    }
    tbs::SplineFile file{*spline_, units_.empty() ? "unitless" : units_, meta};
    file.atlas = atlas_;
    std::string json;
    {
      py::gil_scoped_release release;
      json = tbs::to_json(tbs::convert(file, path, o));
    }
    return py::module_::import("json").attr("loads")(json);
  }

 private:
  const tbs::Evaluator& evaluator() const {
    if (!evaluator_) evaluator_ = std::make_unique<tbs::Evaluator>(*spline_);
    return *evaluator_;
  }
  std::unique_ptr<tbs::Spline> spline_;  // on the heap: the evaluator keeps a reference to it
  std::string report_;
  std::string units_;
  tbs::Atlas atlas_;
  mutable std::unique_ptr<tbs::Evaluator> evaluator_;
};

using Faces = py::array_t<long long, py::array::c_style | py::array::forcecast>;

tbs::Scan scan_from(const Array& points, const std::optional<Array>& uv, const std::optional<Array>& normals,
                    const std::optional<Faces>& faces) {
  tbs::Scan s;
  const Array p = checked(points, 3, "points");
  auto pr = p.unchecked<2>();
  for (py::ssize_t i = 0; i < p.shape(0); ++i) s.positions.emplace_back(pr(i, 0), pr(i, 1), pr(i, 2));
  if (uv) {
    const Array a = checked(*uv, 2, "uv");
    if (a.shape(0) != p.shape(0)) throw tbs::InvalidInput("uv must have one row per point");
    auto r = a.unchecked<2>();
    for (py::ssize_t i = 0; i < a.shape(0); ++i) s.uv.emplace_back(r(i, 0), r(i, 1));
  }
  if (normals) {
    const Array a = checked(*normals, 3, "normals");
    if (a.shape(0) != p.shape(0)) throw tbs::InvalidInput("normals must have one row per point");
    auto r = a.unchecked<2>();
    for (py::ssize_t i = 0; i < a.shape(0); ++i) {
      // Normalised here (fit() wants unit normals); a zero normal stays and is refused there.
      const tbs::Vector3 n(r(i, 0), r(i, 1), r(i, 2));
      s.normals.push_back(n.stableNorm() > 0 ? tbs::Vector3(n.stableNormalized()) : n);
    }
  }
  if (faces) {
    if (faces->ndim() != 2 || faces->shape(1) != 3)
      throw tbs::InvalidInput("faces must be an integer array of shape (F, 3)");
    auto r = faces->unchecked<2>();
    for (py::ssize_t i = 0; i < faces->shape(0); ++i) {
      std::array<int, 3> t{};
      for (int k = 0; k < 3; ++k) {
        if (r(i, k) < 0 || r(i, k) >= p.shape(0))
          throw tbs::InvalidInput("faces[" + std::to_string(i) + "][" + std::to_string(k) + "] = " +
                                  std::to_string(r(i, k)) + " is not a point index (0 to " +
                                  std::to_string(p.shape(0) - 1) + ")");
        t[k] = static_cast<int>(r(i, k));
      }
      s.triangles.push_back(t);
    }
  }
  s.source = "points";
  return s;
}

PySpline fit(const Array& points, const std::optional<Array>& uv, const std::optional<Array>& normals,
             const std::optional<Faces>& faces, int degree,
             double tolerance, double tolerance_abs, double fairness, double bending, double smoothness, double feature_angle,
             bool features, int triangles, int knot_sweeps, int max_iterations, int threads,
             const std::optional<py::function>& progress, const std::optional<Array>& guide,
             const std::optional<py::dict>& atlas) {
  if (!uv)
    throw tbs::InvalidInput(
        "uv is required: the module fits points with parameters; tbs.parameterize(points, faces) "
        "computes them for a raw scan, as `tbs fit` does");
  tbs::Scan scan = scan_from(points, uv, normals, faces);
  if (atlas) scan.atlas = atlas_from(*atlas);
  if (guide) {
    const py::array_t<double, py::array::c_style | py::array::forcecast> g(*guide);
    if (g.ndim() != 1 || g.shape(0) != static_cast<py::ssize_t>(scan.positions.size()))
      throw tbs::InvalidInput("guide must have one entry per point");
    auto r = g.unchecked<1>();
    for (py::ssize_t i = 0; i < g.shape(0); ++i) scan.guide.push_back(r(i) != 0 ? 1 : 0);
  }
  tbs::FitOptions o;
  o.degree = degree;
  o.tolerance = tolerance;
  o.tolerance_abs = tolerance_abs;
  o.fairness = fairness;
  o.bending = bending;
  o.smoothness = smoothness;
  o.feature_angle = feature_angle;
  o.features = features;
  o.triangles = triangles;
  o.knot_sweeps = knot_sweeps;
  o.max_iterations = max_iterations;
  o.threads = threads;
  std::stop_source stop;
  o.stop = stop.get_token();
  // The callback runs on this thread with the GIL taken back. It returns False to cancel
  // (the fit then raises Cancelled); Ctrl-C cancels too.
  o.progress = [&](const tbs::FitProgress& p) {
    py::gil_scoped_acquire acquire;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (progress) {
      const py::object keep = (*progress)(p.stage, p.message, p.fraction);
      if (!keep.is_none() && !keep.cast<bool>()) stop.request_stop();
    }
  };
  tbs::FitResult r;
  {
    py::gil_scoped_release release;
    r = tbs::fit(scan, o);
  }
  return PySpline(std::move(r.spline), r.report.to_json(true), "unitless", std::move(r.atlas));
}

// Parameters for a raw scan, as `tbs fit` computes them before it fits: a mesh is repaired,
// one component chosen, a closed one cut open and flattened; a point cloud is meshed first.
py::dict parameterize(const Array& points, const std::optional<Faces>& faces, const std::optional<Array>& normals,
                      const std::string& method, int component, size_t min_points, double sharp_angle,
                      const std::optional<py::function>& progress) {
  const tbs::Scan scan = scan_from(points, std::nullopt, normals, faces);
  tbs::ParameterizeOptions o;
  if (method == "auto") {
    o.method = tbs::FlattenMethod::Auto;
  } else if (method == "lscm") {
    o.method = tbs::FlattenMethod::Lscm;
  } else if (method == "mean-value") {
    o.method = tbs::FlattenMethod::MeanValue;
  } else {
    throw tbs::InvalidInput("method must be 'auto', 'lscm' or 'mean-value', not '" + method + "'");
  }
  if (component < 0) throw tbs::InvalidInput("component must be 0 (the largest) or a component number from 1");
  if (!(sharp_angle > 0 && sharp_angle < 180)) throw tbs::InvalidInput("sharp_angle must be between 0 and 180 degrees");
  o.component = component;
  o.min_points = min_points;
  o.sharp_angle = sharp_angle;
  o.progress = [&](const std::string& line) {
    py::gil_scoped_acquire acquire;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (progress) (*progress)(line);
  };
  tbs::ParameterizedScan p;
  {
    py::gil_scoped_release release;
    p = tbs::parameterize_scan(scan, o);
  }
  py::dict d;
  d["points"] = to_array(p.scan.positions, 3);
  d["uv"] = to_array(p.scan.uv, 2);
  d["faces"] = p.scan.has_faces() ? py::object(faces_array(p.scan.triangles)) : py::none();
  d["normals"] = p.scan.has_normals() ? py::object(to_array(p.scan.normals, 3)) : py::none();
  py::array_t<long long> source(static_cast<py::ssize_t>(p.source.size()));
  auto sm = source.mutable_unchecked<1>();
  for (size_t i = 0; i < p.source.size(); ++i) sm(static_cast<py::ssize_t>(i)) = static_cast<long long>(p.source[i]);
  d["source"] = source;
  if (p.scan.guide.empty()) {
    d["guide"] = py::none();
  } else {
    py::array_t<bool> guide(static_cast<py::ssize_t>(p.scan.guide.size()));
    auto gm = guide.mutable_unchecked<1>();
    for (size_t i = 0; i < p.scan.guide.size(); ++i) gm(static_cast<py::ssize_t>(i)) = p.scan.guide[i] != 0;
    d["guide"] = guide;
  }
  d["report"] = json_loads(p.report.to_json());
  d["atlas"] = p.scan.atlas.empty() ? py::object(py::none()) : py::object(atlas_dict(p.scan.atlas));
  return d;
}

PySpline load(const std::string& path) {
  tbs::SplineFile f = tbs::read_tbs(path);
  return PySpline(std::move(f.spline), f.metadata_json, f.units, std::move(f.atlas));
}

py::dict read_scan(const std::string& path, size_t max_points) {
  tbs::ScanReadOptions o;
  o.max_points = max_points;
  tbs::Scan s;
  {
    py::gil_scoped_release release;
    s = tbs::read_scan(path, o);
  }
  py::dict d;
  d["points"] = to_array(s.positions, 3);
  d["uv"] = s.has_uv() ? py::object(to_array(s.uv, 2)) : py::none();
  d["normals"] = s.has_normals() ? py::object(to_array(s.normals, 3)) : py::none();
  d["faces"] = s.has_faces() ? py::object(faces_array(s.triangles)) : py::none();
  return d;
}

}  // namespace

PYBIND11_MODULE(tbs, m) {
  m.doc() = "Triangular B-spline (DMS spline) surfaces from scans, for CAD: fit, evaluate, tessellate, export.";
  m.attr("__version__") = TBS_VERSION;

  // Exceptions: pybind11 tries translators newest first, so the base class comes first.
  static py::exception<tbs::Error> error(m, "Error", PyExc_RuntimeError);
  static py::exception<tbs::InvalidInput> invalid(m, "InvalidInput", PyExc_ValueError);
  static py::exception<tbs::OutsideDomain> outside(m, "OutsideDomain", invalid.ptr());
  static py::exception<tbs::IoError> io(m, "IoError", PyExc_OSError);
  static py::exception<tbs::SolverError> solver(m, "SolverError", error.ptr());
  static py::exception<tbs::Cancelled> cancelled(m, "Cancelled", error.ptr());
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const tbs::Cancelled& e) {
      cancelled(e.what());
    } catch (const tbs::SolverError& e) {
      solver(e.what());
    } catch (const tbs::IoError& e) {
      io(e.what());
    } catch (const tbs::OutsideDomain& e) {
      outside(e.what());
    } catch (const tbs::InvalidInput& e) {
      invalid(e.what());
    } catch (const tbs::Error& e) {
      error(e.what());
    }
  });

  py::class_<PySpline>(m, "Spline", "A triangular B-spline surface (fitted, or loaded from a .tbs file).")
      .def_property_readonly("degree", &PySpline::degree)
      .def_property_readonly("triangle_count", &PySpline::triangle_count, "Domain triangles.")
      .def_property_readonly("control_points", &PySpline::control_points, "(K, 3) array.")
      .def_property_readonly("report", &PySpline::report, "The fit report (dict), or the .tbs metadata.")
      .def_property_readonly("units", &PySpline::units)
      .def("evaluate", &PySpline::evaluate, py::arg("uv"), py::arg("derivatives") = false,
           py::arg("outside") = "raise",
           "F(u) for an (N, 2) array of parameters: an (N, 3) array, or (F, F_u, F_v) with "
           "derivatives=True. Parameters outside the domain raise OutsideDomain, or give NaN with "
           "outside='nan'.")
      .def("tessellate", &PySpline::tessellate, py::arg("chordal_tolerance") = 1e-4, py::arg("resolution") = 0,
           "A watertight triangle mesh: dict of positions (V, 3), normals (V, 3), uv (V, 2), faces "
           "(F, 3) and max_chordal_deviation. Adaptive to chordal_tolerance (of the model size), "
           "or uniform with resolution > 0.")
      .def_property_readonly("atlas", &PySpline::atlas,
                             "The atlas: dict of closed, genus, seams (list of dicts: a, b (N, 2) glued point "
                             "for point, sharp) and borders (list of (N, 2) arrays); no seams for a spline over "
                             "one planar domain.")
      .def("outlines", &PySpline::outlines,
           "The charts' outlines: closed loops ((N, 2) arrays, first point not repeated) of seam sides and "
           "borders, each chart on the left; the trimmed surface is inside them (even-odd rule).")
      .def("check_seams", &PySpline::check_seams, py::arg("samples") = 1000,
           "How well the seams' two sides agree, at `samples` points per seam: dict of max_gap (model "
           "units), max_normal_jump (degrees, smooth seams), min_crease and max_crease (sharp seams), "
           "and per seam seam_gap and seam_angle.")
      .def("save", &PySpline::save, py::arg("path"), "Writes a .tbs file (atomically).")
      .def("export", &PySpline::export_file, py::arg("path"), py::arg("faces") = "regions",
           py::arg("cad_tolerance") = 0.0, py::arg("angle_tolerance") = 1.0, py::arg("face_degree") = 5,
           py::arg("max_poles") = 20000, py::arg("patch_degree") = 0, py::arg("max_patches") = 50000,
           py::arg("exact") = false, py::arg("units") = "", py::arg("chordal_tolerance") = 1e-4,
           py::arg("threads") = 0,
           "Writes STEP/IGES (.step .stp .iges .igs: faces='regions', one trimmed B-spline face per "
           "smooth region; 'triangles', Bezier patches per domain triangle; 'exact', the exact "
           "pieces) or a mesh (.glb .gltf .obj .ply), through the same conversion as `tbs convert`, "
           "with its defaults (cad_tolerance 0: 1/20 of the fit's tolerance). Returns the report "
           "of `tbs convert --report` as a dict.");

  m.def("fit", &fit, py::arg("points"), py::arg("uv"), py::arg("normals") = py::none(),
        py::arg("faces") = py::none(), py::arg("degree") = 3,
        py::arg("tolerance") = 1e-3, py::arg("tolerance_abs") = 0.0, py::arg("fairness") = 1e-3,
        py::arg("bending") = 1e-4, py::arg("smoothness") = 3e-6, py::arg("feature_angle") = 40.0, py::arg("features") = true,
        py::arg("triangles") = 0, py::arg("knot_sweeps") = 3, py::arg("max_iterations") = 25,
        py::arg("threads") = 0, py::arg("progress") = py::none(), py::arg("guide") = py::none(),
        py::arg("atlas") = py::none(),
        "Fits one spline to points (N, 3) with parameters uv (N, 2), as `tbs fit` does (the "
        "options and defaults are the same). faces (F, 3), the scan's triangles when it is a "
        "mesh, let the fit find sharp edges from the dihedral angles, as the command does. guide (N,), "
        "nonzero for guide points (parameterize() returns it for a subdivided mesh): held with a "
        "tenth of the weight, their errors not measured. atlas, as parameterize() returns it for a closed "
        "or cut surface, ties the charts' seams. progress(stage, message, fraction) is called "
        "between steps; returning False cancels the fit (raises Cancelled), as does Ctrl-C.");
  m.def("parameterize", &parameterize, py::arg("points"), py::arg("faces") = py::none(),
        py::arg("normals") = py::none(), py::arg("method") = "auto", py::arg("component") = 0,
        py::arg("min_points") = 0, py::arg("sharp_angle") = 40.0, py::arg("progress") = py::none(),
        "Parameters (u, v) for a scan without them, as `tbs fit` computes them: a mesh (faces (F, "
        "3)) is repaired, its component `component` (1 = the largest; 0 the same) chosen, cut into "
        "charts (an atlas) if closed, with handles or too stretched by one flattening, and flattened (method 'auto': LSCM, relaxed toward equal areas where it shrinks parts "
        "of the surface tenfold on average, or mean-value coordinates if LSCM folds; 'lscm', the "
        "conformal map alone; 'mean-value'); a point cloud (faces None) is meshed first. min_points > 0 subdivides a coarse "
        "mesh 1-to-4 until it has that many points. Returns a dict: points (M, 3), uv (M, 2), faces "
        "(F, 3) or None, normals (M, 3) or None, guide (M,) or None (True for the points the "
        "subdivision added), atlas (a dict as Spline.atlas, or None: the charts' seams when the surface was cut into charts), which fit() takes as they are; source (M,), the input point of each point; report, as `tbs fit --report` gives it under parameterization. "
        "progress(line) is called between steps.");
  m.def("load", &load, py::arg("path"), "Reads a .tbs file.");
  m.def("read_scan", &read_scan, py::arg("path"), py::arg("max_points") = 50'000'000,
        "Reads a scan (PLY, OBJ, OFF, STL, XYZ): dict of points (N, 3) and uv, normals, faces "
        "(arrays, or None when the file has none).");
}
