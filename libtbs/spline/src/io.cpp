// .tbs files (io.h): parsing with a message that names the JSON field, writing in canonical
// form, and the atomic output every writer of tbs goes through.

#include <tbs/errors.h>
#include <tbs/io.h>
#include <tbs/knots.h>
#include <tbs/tolerances.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <mutex>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

namespace tbs {
namespace {

using json = nlohmann::ordered_json;

const char* const kUnits[] = {"mm", "cm", "m", "um", "in", "ft", "unitless"};

bool known_unit(const std::string& u) {
  return std::find(std::begin(kUnits), std::end(kUnits), u) != std::end(kUnits);
}

std::string unit_list() {
  std::string s;
  for (const char* u : kUnits) s += (s.empty() ? "" : ", ") + std::string(u);
  return s;
}

struct Reader {
  std::string name;

  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw InvalidInput(name + ": " + path + ": " + what);
  }

  const json& field(const json& obj, const char* key, const std::string& path) const {
    auto it = obj.find(key);
    if (it == obj.end())
      fail(path.empty() ? key : path + "." + key, "missing field");
    return *it;
  }

  const json& array(const json& v, const std::string& path, size_t expected = SIZE_MAX) const {
    if (!v.is_array()) fail(path, std::string("expected an array, got ") + v.type_name());
    if (expected != SIZE_MAX && v.size() != expected)
      fail(path, "expected " + std::to_string(expected) + " entries, got " + std::to_string(v.size()));
    return v;
  }

  int integer(const json& v, const std::string& path) const {
    if (!v.is_number_integer())
      fail(path, std::string("expected an integer, got ") +
                     (v.is_number() ? "the number " + v.dump() : std::string(v.type_name())));
    const auto x = v.get<int64_t>();
    if (v.is_number_unsigned() && v.get<uint64_t>() > static_cast<uint64_t>(INT32_MAX))
      fail(path, "integer " + v.dump() + " is too large");
    if (x < INT32_MIN || x > INT32_MAX) fail(path, "integer " + v.dump() + " is out of range");
    return static_cast<int>(x);
  }

  double number(const json& v, const std::string& path) const {
    if (!v.is_number())
      fail(path, std::string("expected a number, got ") + v.type_name() +
                     (v.is_null() ? " (NaN and infinity are not allowed)" : ""));
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(path, "number is not finite");
    // As for scans: beyond this, products in the knot checks and the evaluator overflow
    // (a sub-knot at 1e308 passed the checks and evaluated to infinity; found by fuzzing).
    if (std::abs(x) > 1e30) fail(path, "the number " + v.dump() + " is larger than 1e30 in magnitude");
    return x;
  }

  Point2 point2(const json& v, const std::string& path) const {
    array(v, path, 2);
    return {number(v[0], path + "[0]"), number(v[1], path + "[1]")};
  }

  Point3 point3(const json& v, const std::string& path) const {
    array(v, path, 3);
    return {number(v[0], path + "[0]"), number(v[1], path + "[1]"), number(v[2], path + "[2]")};
  }
};

}  // namespace

std::string valid_utf8(std::string_view text) {
  return json::parse(json(std::string(text)).dump(-1, ' ', false, json::error_handler_t::replace))
      .get<std::string>();
}

namespace {

// Error text may quote bytes of a binary file: keep messages printable on any terminal.
std::string printable(std::string s) {
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return s;
}

std::string idx(const std::string& path, size_t i) { return path + "[" + std::to_string(i) + "]"; }

void pretty(const json& j, std::string& out, int indent) {
  const std::string pad(static_cast<size_t>(indent) + 2, ' ');
  if (j.is_object() && !j.empty()) {
    out += "{\n";
    size_t i = 0;
    for (auto it = j.begin(); it != j.end(); ++it, ++i) {
      out += pad + json(it.key()).dump(-1, ' ', false, json::error_handler_t::replace) + ": ";
      pretty(it.value(), out, indent + 2);
      out += i + 1 < j.size() ? ",\n" : "\n";
    }
    out += std::string(static_cast<size_t>(indent), ' ') + "}";
  } else if (j.is_array() && !j.empty() && (j[0].is_array() || j[0].is_object())) {
    out += "[\n";
    for (size_t i = 0; i < j.size(); ++i) {
      out += pad;
      if (j[i].is_object())
        pretty(j[i], out, indent + 2);
      else
        out += j[i].dump(-1, ' ', false, json::error_handler_t::replace);
      out += i + 1 < j.size() ? ",\n" : "\n";
    }
    out += std::string(static_cast<size_t>(indent), ' ') + "]";
  } else {
    out += j.dump(-1, ' ', false, json::error_handler_t::replace);
  }
}

}  // namespace

SplineFile parse_tbs(std::string_view text, const std::string& name, const ReadOptions& options) {
  const Reader r{name};
  json j;
  try {
    j = json::parse(text.begin(), text.end());
  } catch (const json::exception& e) {
    // nlohmann prefixes "[json.exception.<kind>.<id>] "; keep the readable part.
    std::string what = e.what();
    if (auto p = what.find("] "); p != std::string::npos) what = what.substr(p + 2);
    const auto* pe = dynamic_cast<const json::parse_error*>(&e);
    // A scan handed to a command that reads splines (tbs info, tbs convert).
    std::string ext = std::filesystem::path(name).extension().string();
    for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    for (const char* scan : {".ply", ".obj", ".off", ".stl", ".xyz", ".txt"})
      if (ext == scan)
        throw InvalidInput(name + ": not a .tbs spline but a scan (" + ext.substr(1) +
                           "), it seems; fit it first (tbs fit " + name + " -o OUT.tbs), then use OUT.tbs");
    throw InvalidInput(name + ": not valid JSON: " + printable(what) +
                       (pe && pe->byte >= text.size() ? " (the file looks truncated)" : ""));
  }
  if (!j.is_object()) r.fail("(top level)", std::string("expected a JSON object, got ") + j.type_name());

  const json& format = r.field(j, "format", "");
  if (!format.is_string() || format.get<std::string>() != "tbs")
    r.fail("format", "expected the string \"tbs\"; this is not a tbs spline file");
  const int version = r.integer(r.field(j, "version", ""), "version");
  if (version < 1 || version > kTbsFormatVersion)
    r.fail("version", "version " + std::to_string(version) + " is not supported (this tbs reads 1 to " +
                          std::to_string(kTbsFormatVersion) + "; upgrade tbs)");
  const int n = r.integer(r.field(j, "degree", ""), "degree");
  if (n < 1 || n > tol::kMaxDegree)
    r.fail("degree", "degree " + std::to_string(n) + " is not supported (1 to " +
                         std::to_string(tol::kMaxDegree) + ")");

  SplineFile out;
  if (auto it = j.find("units"); it != j.end()) {
    if (!it->is_string()) r.fail("units", "expected a string");
    out.units = it->get<std::string>();
    if (!known_unit(out.units)) r.fail("units", "unknown unit \"" + out.units + "\" (use one of " + unit_list() + ")");
  }
  if (auto it = j.find("metadata"); it != j.end()) {
    if (!it->is_object()) r.fail("metadata", std::string("expected an object, got ") + it->type_name());
    out.metadata_json = it->dump();
  }

  if (auto it = j.find("points"); it != j.end()) {
    if (!it->is_object()) r.fail("points", std::string("expected an object, got ") + it->type_name());
    const json& jp = r.array(r.field(*it, "positions", "points"), "points.positions");
    const json& ju = r.array(r.field(*it, "parameters", "points"), "points.parameters", jp.size());
    out.points.resize(jp.size());
    out.point_parameters.resize(jp.size());
    for (size_t i = 0; i < jp.size(); ++i) {
      out.points[i] = r.point3(jp[i], idx("points.positions", i));
      out.point_parameters[i] = r.point2(ju[i], idx("points.parameters", i));
    }
  }

  if (auto it = j.find("atlas"); it != j.end()) {
    if (version < 2) r.fail("atlas", "an atlas needs version 2 of the format, the file says " + std::to_string(version));
    if (!it->is_object()) r.fail("atlas", std::string("expected an object, got ") + it->type_name());
    if (auto c = it->find("closed"); c != it->end()) {
      if (!c->is_boolean()) r.fail("atlas.closed", "expected true or false");
      out.atlas.closed = c->get<bool>();
    }
    if (auto g = it->find("genus"); g != it->end()) out.atlas.genus = r.integer(*g, "atlas.genus");
    const json& js = r.array(r.field(*it, "seams", "atlas"), "atlas.seams");
    for (size_t s = 0; s < js.size(); ++s) {
      const std::string p = idx("atlas.seams", s);
      if (!js[s].is_object()) r.fail(p, std::string("expected an object, got ") + js[s].type_name());
      Seam seam;
      if (auto sh = js[s].find("sharp"); sh != js[s].end()) {
        if (!sh->is_boolean()) r.fail(p + ".sharp", "expected true or false");
        seam.sharp = sh->get<bool>();
      }
      const json& ja = r.array(r.field(js[s], "a", p), p + ".a");
      const json& jb = r.array(r.field(js[s], "b", p), p + ".b", ja.size());
      for (size_t i = 0; i < ja.size(); ++i) {
        seam.a.push_back(r.point2(ja[i], idx(p + ".a", i)));
        seam.b.push_back(r.point2(jb[i], idx(p + ".b", i)));
      }
      out.atlas.seams.push_back(std::move(seam));
    }
    if (auto b = it->find("borders"); b != it->end()) {
      r.array(*b, "atlas.borders");
      for (size_t i = 0; i < b->size(); ++i) {
        const std::string p = idx("atlas.borders", i);
        const json& line = r.array((*b)[i], p);
        std::vector<Point2> border;
        for (size_t k = 0; k < line.size(); ++k) border.push_back(r.point2(line[k], idx(p, k)));
        out.atlas.borders.push_back(std::move(border));
      }
    }
    check_atlas_structure(out.atlas, name);
  }

  const json& dom = r.field(j, "domain", "");
  if (!dom.is_object()) r.fail("domain", "expected an object");
  const json& jv = r.array(r.field(dom, "vertices", "domain"), "domain.vertices");
  std::vector<Point2> vertices(jv.size());
  for (size_t i = 0; i < jv.size(); ++i) vertices[i] = r.point2(jv[i], idx("domain.vertices", i));
  const json& jt = r.array(r.field(dom, "triangles", "domain"), "domain.triangles");
  std::vector<std::array<int, 3>> triangles(jt.size());
  for (size_t t = 0; t < jt.size(); ++t) {
    const std::string p = idx("domain.triangles", t);
    r.array(jt[t], p, 3);
    for (int k = 0; k < 3; ++k) {
      const int v = r.integer(jt[t][k], idx(p, k));
      if (v < 0 || v >= static_cast<int>(vertices.size()))
        r.fail(idx(p, k), "vertex index " + std::to_string(v) + " out of range [0, " +
                              std::to_string(vertices.size()) + ")");
      triangles[t][k] = v;
    }
  }
  std::vector<std::array<int, 2>> features;
  if (auto it = dom.find("feature_edges"); it != dom.end()) {
    r.array(*it, "domain.feature_edges");
    for (size_t e = 0; e < it->size(); ++e) {
      const std::string p = idx("domain.feature_edges", e);
      r.array((*it)[e], p, 2);
      features.push_back({r.integer((*it)[e][0], p + "[0]"), r.integer((*it)[e][1], p + "[1]")});
    }
  }
  Domain domain;
  try {
    domain = Domain(std::move(vertices), std::move(triangles), std::move(features));
  } catch (const InvalidInput& e) {
    r.fail("domain", e.what());
  }
  if (auto it = dom.find("boundary_loops"); it != dom.end()) {
    r.array(*it, "domain.boundary_loops");
    std::vector<std::vector<int>> loops;
    for (size_t l = 0; l < it->size(); ++l) {
      const std::string p = idx("domain.boundary_loops", l);
      r.array((*it)[l], p);
      std::vector<int> loop;
      for (size_t i = 0; i < (*it)[l].size(); ++i) loop.push_back(r.integer((*it)[l][i], idx(p, i)));
      if (!loop.empty()) std::rotate(loop.begin(), std::min_element(loop.begin(), loop.end()), loop.end());
      loops.push_back(std::move(loop));
    }
    std::sort(loops.begin(), loops.end());
    if (loops != domain.boundary_loops())
      r.fail("domain.boundary_loops",
             "does not match the boundary of the triangles (expected " +
                 std::to_string(domain.boundary_loops().size()) +
                 " loops, each with the domain on its left: outer loops counter-clockwise, holes "
                 "clockwise)");
  }

  const size_t nv = static_cast<size_t>(domain.vertex_count());
  const json& jk = r.array(r.field(j, "sub_knots", ""), "sub_knots", nv);
  std::vector<Point2> knots(nv * (n + 1));
  for (size_t v = 0; v < nv; ++v) {
    const std::string p = idx("sub_knots", v);
    r.array(jk[v], p, static_cast<size_t>(n));
    knots[v * (n + 1)] = domain.vertex(static_cast<int>(v));
    for (int k = 0; k < n; ++k) knots[v * (n + 1) + k + 1] = r.point2(jk[v][k], idx(p, k));
  }

  const json& jc = r.array(r.field(j, "control_points", ""), "control_points",
                           static_cast<size_t>(control_point_count(domain, n)));
  std::vector<Point3> cps(jc.size());
  for (size_t i = 0; i < jc.size(); ++i) cps[i] = r.point3(jc[i], idx("control_points", i));

  const int nb = beta_count(n);
  const json& jm = r.array(r.field(j, "control_point_map", ""), "control_point_map",
                           static_cast<size_t>(domain.triangle_count()));
  std::vector<int> map(static_cast<size_t>(domain.triangle_count()) * nb);
  for (size_t t = 0; t < jm.size(); ++t) {
    const std::string p = idx("control_point_map", t);
    r.array(jm[t], p, static_cast<size_t>(nb));
    for (int i = 0; i < nb; ++i) map[t * nb + i] = r.integer(jm[t][i], idx(p, i));
  }

  try {
    out.spline = Spline(n, std::move(domain), std::move(knots), std::move(cps), std::move(map));
  } catch (const InvalidInput& e) {
    throw InvalidInput(name + ": " + e.what());
  }
  if (options.check_knots) {
    const KnotCheck check =
        check_knot_conditions(out.spline.domain(), n, out.spline.knots());
    if (!check.ok())
      throw InvalidInput(name + ": sub_knots violate the knot conditions: " + check.issues[0].message +
                         (check.issues.size() > 1
                              ? " (and " + std::to_string(check.issues.size() - 1) +
                                    " more; run 'tbs info' for all)"
                              : ""));
  }
  return out;
}

SplineFile read_tbs(const std::string& path, const ReadOptions& options) {
  return parse_tbs(read_file(path), path, options);
}

std::string format_tbs(const SplineFile& f) {
  const Spline& s = f.spline;
  const int n = s.degree();
  if (!known_unit(f.units)) throw InvalidInput("unknown unit \"" + f.units + "\" (use one of " + unit_list() + ")");
  json meta;
  try {
    meta = json::parse(f.metadata_json);
  } catch (const json::parse_error& e) {
    throw InvalidInput(std::string("metadata is not valid JSON: ") + e.what());
  }
  if (!meta.is_object()) throw InvalidInput("metadata must be a JSON object");

  check_atlas_structure(f.atlas, "atlas");

  json j = json::object();
  j["format"] = "tbs";
  j["version"] = f.atlas.empty() ? 1 : kTbsFormatVersion;
  j["degree"] = n;
  j["units"] = f.units;
  json dom = json::object();
  json verts = json::array();
  for (const auto& p : s.domain().vertices()) verts.push_back({p.x(), p.y()});
  dom["vertices"] = std::move(verts);
  json tris = json::array();
  for (const auto& t : s.domain().triangles()) tris.push_back({t[0], t[1], t[2]});
  dom["triangles"] = std::move(tris);
  dom["boundary_loops"] = s.domain().boundary_loops();
  json feats = json::array();
  for (const auto& e : s.domain().feature_edges()) feats.push_back({e[0], e[1]});
  dom["feature_edges"] = std::move(feats);
  j["domain"] = std::move(dom);
  json sub = json::array();
  for (int v = 0; v < s.domain().vertex_count(); ++v) {
    json row = json::array();
    for (int k = 1; k <= n; ++k) row.push_back({s.knot(v, k).x(), s.knot(v, k).y()});
    sub.push_back(std::move(row));
  }
  j["sub_knots"] = std::move(sub);
  json cps = json::array();
  for (const auto& c : s.control_points()) cps.push_back({c.x(), c.y(), c.z()});
  j["control_points"] = std::move(cps);
  json map = json::array();
  const int nb = beta_count(n);
  for (int t = 0; t < s.domain().triangle_count(); ++t) {
    json row = json::array();
    for (int i = 0; i < nb; ++i) row.push_back(s.control_point_index(t, i));
    map.push_back(std::move(row));
  }
  j["control_point_map"] = std::move(map);
  if (!f.atlas.empty()) {
    json seams = json::array();
    for (const Seam& seam : f.atlas.seams) {
      json a = json::array(), b = json::array();
      for (const auto& p : seam.a) a.push_back({p.x(), p.y()});
      for (const auto& p : seam.b) b.push_back({p.x(), p.y()});
      seams.push_back({{"sharp", seam.sharp}, {"a", std::move(a)}, {"b", std::move(b)}});
    }
    json borders = json::array();
    for (const auto& line : f.atlas.borders) {
      json b = json::array();
      for (const auto& p : line) b.push_back({p.x(), p.y()});
      borders.push_back(std::move(b));
    }
    j["atlas"] = {{"closed", f.atlas.closed},
                  {"genus", f.atlas.genus},
                  {"seams", std::move(seams)},
                  {"borders", std::move(borders)}};
  }
  j["metadata"] = std::move(meta);
  if (f.points.size() != f.point_parameters.size())
    throw InvalidInput(std::to_string(f.points.size()) + " points but " + std::to_string(f.point_parameters.size()) +
                       " point parameters");
  if (!f.points.empty()) {
    json pos = json::array(), par = json::array();
    for (size_t i = 0; i < f.points.size(); ++i) {
      const Point3& p = f.points[i];
      const Point2& u = f.point_parameters[i];
      if (!p.allFinite() || !u.allFinite())
        throw InvalidInput("point " + std::to_string(i) + " is not finite");
      pos.push_back({p.x(), p.y(), p.z()});
      par.push_back({u.x(), u.y()});
    }
    j["points"] = {{"positions", std::move(pos)}, {"parameters", std::move(par)}};
  }

  std::string out;
  pretty(j, out, 0);
  out += "\n";
  return out;
}

void write_tbs(const std::string& path, const SplineFile& file) {
  std::string text;
  try {
    text = format_tbs(file);
  } catch (const InvalidInput& e) {
    throw InvalidInput(path + ": " + e.what());
  }
  write_file_atomic(path, text);
}

namespace {

// Temporary files of live AtomicOutputs, for remove_pending_outputs(). Fixed buffers that are
// never freed, so a signal handler can read them at any moment; a slot's state says whether
// its path is complete (kLive). Outputs beyond kSlots, or with longer paths, are not
// registered: an interrupt then leaves their temporary file (hidden, named .NAME.tmp-PID-N).
constexpr int kSlots = 64;
constexpr size_t kPathMax = 4096;
constexpr int kFree = 0, kFilling = 1, kLive = 2;
char g_temp_paths[kSlots][kPathMax];
std::atomic<int> g_slot_state[kSlots];

int register_temp(const std::string& temp) {
  if (temp.size() >= kPathMax) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (g_slot_state[i].compare_exchange_strong(expected, kFilling)) {
      std::memcpy(g_temp_paths[i], temp.c_str(), temp.size() + 1);
      g_slot_state[i].store(kLive);
      return i;
    }
  }
  return -1;
}

void unregister_temp(int slot) {
  if (slot >= 0) g_slot_state[slot].store(kFree);
}

extern "C" void remove_and_reraise(int sig) {
  remove_pending_outputs();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

}  // namespace

void remove_pending_outputs() noexcept {
  for (int i = 0; i < kSlots; ++i)
    if (g_slot_state[i].load() == kLive) ::unlink(g_temp_paths[i]);
}

void remove_outputs_on_signal() {
  static std::once_flag once;
  std::call_once(once, [] {
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
      struct sigaction sa {};
      sa.sa_handler = remove_and_reraise;
      sigemptyset(&sa.sa_mask);
      sa.sa_flags = 0;
      ::sigaction(sig, &sa, nullptr);
    }
  });
}

void check_output_path(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  if (p.filename().empty()) throw IoError("cannot write '" + path + "': not a file name");
  std::error_code ec;
  const fs::file_status st = fs::status(p, ec);  // follows symbolic links
  if (fs::is_directory(st)) throw IoError("cannot write '" + path + "': it is a directory");
  // The rename would replace a device or a pipe (e.g. /dev/stdout) by a regular file.
  if (fs::exists(st) && !fs::is_regular_file(st))
    throw IoError("cannot write '" + path + "': it exists and is not a regular file (a device, pipe or socket); "
                  "give the path of a file");
  const fs::path folder = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  if (!fs::is_directory(folder, ec))
    throw IoError("cannot write '" + path + "': the folder '" + folder.string() + "' does not exist");
}

AtomicOutput::AtomicOutput(std::string path) : path_(std::move(path)) {
  static std::atomic<unsigned> counter{0};
  namespace fs = std::filesystem;
  check_output_path(path_);
  // A symbolic link is written through: the rename replaces its target, and the link stays.
  std::error_code link_ec;
  fs::path p(path_);
  if (fs::is_symlink(p, link_ec)) {
    const fs::path target = fs::weakly_canonical(p, link_ec);
    if (!link_ec) p = target;
  }
  target_ = p.string();
  for (int attempt = 0; attempt < 100; ++attempt) {
    const std::string candidate = (p.parent_path() / ("." + p.filename().string() + ".tmp-" +
                                                      std::to_string(::getpid()) + "-" +
                                                      std::to_string(counter++)))
                                      .string();
    // Registered before it exists: a signal between creating and registering would leave it.
    // (A signal while open() fails with EEXIST would remove a stale file of this process's
    // name, which is harmless.)
    const int slot = register_temp(candidate);
    const int fd = ::open(candidate.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0) {
      ::close(fd);
      temp_ = candidate;
      slot_ = slot;
      return;
    }
    const int err = errno;
    unregister_temp(slot);
    if (err != EEXIST)
      throw IoError("cannot write '" + path_ + "': " + std::strerror(err));
  }
  throw IoError("cannot write '" + path_ + "': no free temporary file name");
}

AtomicOutput::~AtomicOutput() {
  if (!committed_ && !temp_.empty()) std::remove(temp_.c_str());
  unregister_temp(slot_);
}

void AtomicOutput::commit() {
  if (std::rename(temp_.c_str(), target_.c_str()) != 0)
    throw IoError("cannot write '" + path_ + "': " + std::strerror(errno));
  committed_ = true;
  unregister_temp(slot_);
  slot_ = -1;
}

void AtomicOutput::write(std::string_view data) {
  std::ofstream f(temp_, std::ios::binary | std::ios::trunc);
  f.write(data.data(), static_cast<std::streamsize>(data.size()));
  f.flush();
  if (!f) throw IoError("cannot write '" + path_ + "': write failed (disk full?)");
}

void write_file_atomic(const std::string& path, std::string_view data) {
  AtomicOutput out(path);
  out.write(data);
  out.commit();
}

std::string read_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw IoError("cannot read '" + path + "': it is a directory");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw IoError("cannot read '" + path + "': " + std::strerror(errno));
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) throw IoError("cannot read '" + path + "': read error");
  return ss.str();
}

}  // namespace tbs
