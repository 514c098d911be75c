// Scan readers. PLY, OFF and STL go through CGAL's readers, OBJ through tinyobjloader; only
// the XYZ layout, which no library reads, is parsed here. Around the libraries we add what they
// do not do: counts are checked before anything is allocated, indices are range-checked, values
// must be finite, and every failure names the file and the line or element.
#include <CGAL/IO/OFF.h>
#include <CGAL/IO/PLY/PLY_reader.h>
#include <CGAL/IO/STL.h>
#include <CGAL/Simple_cartesian.h>
#include <tbs/errors.h>
#include <tbs/io.h>
#include <tbs/scan.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <unordered_map>

namespace tbs {
namespace {

namespace fs = std::filesystem;
namespace cply = CGAL::IO::internal;

// A coordinate beyond 1e30 is a unit or export error, not a measurement, and squaring it (as
// fitting does) would overflow double.
constexpr double kMaxAbsValue = 1e30;
// Corner counts above this are corrupt data; the cap keeps a bad count from allocating.
constexpr std::size_t kMaxPolygonCorners = 1 << 20;
// A PLY header is a few hundred bytes; reading at most this much finds the end of any real one
// without reading a whole binary file that has no end_header.
constexpr std::size_t kMaxPlyHeaderBytes = 1 << 20;
// The longest XYZ line we accept (8 numbers with 17 digits fit in well under 1 KiB).
constexpr std::size_t kMaxXyzLine = 1 << 16;

const char* const kExtensions = ".ply, .obj, .off, .stl, .xyz, .txt";

std::string printable(std::string_view s, std::size_t max = 40) {
  std::string out(s.substr(0, max));
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  if (s.size() > max) out += "...";
  return out;
}

std::string num(double x) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

std::string num(std::uintmax_t x) { return std::to_string(x); }

// A place in a file: "vertex 12", "line 7", "face 3". Built into a string only on failure, so
// that reading millions of points does not build millions of strings.
struct Where {
  std::string_view kind;
  std::uintmax_t index = 0;
  std::string str() const { return std::string(kind) + " " + std::to_string(index); }
};

// The context of one read: messages are `<path>:<where>: <what>`.
struct Ctx {
  std::string path;
  std::uintmax_t file_size = 0;
  std::size_t limit = 0;  // max_points, capped to what an int index can address
  std::string limit_name;
  mutable std::size_t dropped = 0;  // faces (fan triangles) without three distinct corners

  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw InvalidInput(path + (where.empty() ? "" : ":" + where) + ": " + what);
  }

  [[noreturn]] void fail(const Where& where, const std::string& what) const {
    fail(where.str(), what);
  }

  // `what` ends where the number starts: "the header announces", "the file has at least".
  void check_count(const std::string& where, std::uintmax_t n, const std::string& what) const {
    if (n > limit)
      fail(where, what + " " + num(n) + " points; the limit is " + num(std::uintmax_t{limit}) +
                      " (" + limit_name + "): thin the scan or raise the limit");
  }

  void check_value(const Where& where, const char* name, double x) const {
    if (!std::isfinite(x))
      fail(where, std::string(name) + " is " + num(x) +
                      "; every value must be a finite number (fix or remove this element)");
    if (std::abs(x) > kMaxAbsValue)
      fail(where, std::string(name) + " = " + num(x) +
                      " is larger than 1e30 in magnitude; check the export units or remove it");
  }

  Point3 point(const Where& where, double x, double y, double z) const {
    check_value(where, "x", x);
    check_value(where, "y", y);
    check_value(where, "z", z);
    return {x, y, z};
  }

  Point2 param(const Where& where, double u, double v) const {
    check_value(where, "u", u);
    check_value(where, "v", v);
    return {u, v};
  }

  Vector3 normal(const Where& where, double x, double y, double z) const {
    check_value(where, "nx", x);
    check_value(where, "ny", y);
    check_value(where, "nz", z);
    const Vector3 n(x, y, z);
    const double len = n.norm();
    if (!(len > 0))
      fail(where,
           "the normal has zero length; give it a direction or leave normals out (tbs "
           "estimates them)");
    return n / len;
  }

  // Appends the fan triangulation of a polygon, checking its indices against `count`;
  // triangles with a repeated corner are dropped (degenerate, not an error).
  void add_polygon(const Where& where, std::span<const long long> corners, std::size_t count,
                   std::vector<std::array<int, 3>>& out) const {
    for (std::size_t j = 0; j < corners.size(); ++j)
      if (corners[j] < 0 || static_cast<unsigned long long>(corners[j]) >= count)
        fail(where, "corner " + std::to_string(j) + " refers to vertex " +
                        std::to_string(corners[j]) + ", but the vertices are numbered 0 to " +
                        std::to_string(count) +
                        " - 1; the file is corrupt or its faces belong to another vertex list");
    if (corners.size() < 3) ++dropped;
    for (std::size_t j = 1; j + 1 < corners.size(); ++j) {
      const std::array<int, 3> t{static_cast<int>(corners[0]), static_cast<int>(corners[j]),
                                 static_cast<int>(corners[j + 1])};
      if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        out.push_back(t);
      else
        ++dropped;
    }
  }

  void finish(Scan& scan) const {
    if (scan.positions.empty())
      fail("", "the file has no points; check that it is the scan you meant");
    check_count("", scan.positions.size(), "the file has");
    scan.source = path;
    scan.degenerate_faces = dropped;
  }
};

// Where a stream stopped, as "line N" for text or "byte N" for binary data.
std::string stream_location(const Ctx& c, std::istream& is, bool binary) {
  is.clear();
  const auto pos = is.tellg();
  if (binary)
    return pos < 0 || static_cast<std::uintmax_t>(pos) >= c.file_size
               ? "end of file"
               : "byte " + std::to_string(static_cast<long long>(pos));
  std::ifstream f(c.path, std::ios::binary);
  std::uintmax_t line = 1;
  char buf[1 << 16];
  std::uintmax_t left = pos < 0 ? c.file_size : static_cast<std::uintmax_t>(pos);
  while (left > 0 && f) {
    f.read(buf, static_cast<std::streamsize>(std::min<std::uintmax_t>(left, sizeof buf)));
    const auto got = static_cast<std::size_t>(f.gcount());
    line += static_cast<std::uintmax_t>(std::count(buf, buf + got, '\n'));
    left -= got;
  }
  // The readers consume a whole line before they judge it, so the bad line is the previous one.
  return "line " + std::to_string(line > 1 ? line - 1 : 1);
}

std::ifstream open_binary(const Ctx& c) {
  std::ifstream f(c.path, std::ios::binary);
  if (!f)
    throw IoError(c.path + ": cannot open the file: " + std::strerror(errno) +
                  "; check its permissions");
  return f;
}

// ---------------------------------------------------------------------------------------- PLY

struct PlyType {
  const char* name;
  const char* alias;
  int bytes;
  bool is_signed;
  bool is_float;
};

// The types CGAL's PLY reader knows (CGAL/IO/PLY/PLY_reader.h).
constexpr PlyType kPlyTypes[] = {
    {"char", "int8", 1, true, false},    {"uchar", "uint8", 1, false, false},
    {"short", "int16", 2, true, false},  {"ushort", "uint16", 2, false, false},
    {"int", "int32", 4, true, false},    {"uint", "uint32", 4, false, false},
    {"float", "float32", 4, true, true}, {"double", "float64", 8, true, true}};

const PlyType* ply_type(std::string_view s) {
  for (const PlyType& t : kPlyTypes)
    if (s == t.name || s == t.alias) return &t;
  return nullptr;
}

struct PlyProperty {
  std::string name;
  const PlyType* type = nullptr;       // the item type for lists
  const PlyType* size_type = nullptr;  // lists only
};

struct PlyElement {
  std::string name;
  std::uintmax_t count = 0;
  std::size_t line = 0;
  std::vector<PlyProperty> properties;

  // A lower bound of the bytes one item takes: binary, every scalar and list count; ASCII, one
  // digit and one separator per value.
  std::uintmax_t min_item_bytes(bool binary) const {
    std::uintmax_t b = 0;
    for (const PlyProperty& p : properties)
      b += binary ? static_cast<std::uintmax_t>(p.size_type ? p.size_type->bytes : p.type->bytes)
                  : 2;
    return b;
  }
};

enum class PlyFormat { kAscii = 0, kBinaryLittleEndian = 1, kBinaryBigEndian = 2 };

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::uintmax_t data_offset = 0;
};

std::vector<std::string_view> split_ws(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t b = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > b) out.push_back(line.substr(b, i - b));
  }
  return out;
}

// Reads the header once more than CGAL does: CGAL's PLY_reader does not report the format,
// silently skips properties of unknown types (which would shift every later value) and we need
// the element counts and value sizes before any item is read.
PlyHeader scan_ply_header(const Ctx& c, std::istream& is) {
  std::string head(
      static_cast<std::size_t>(std::min<std::uintmax_t>(c.file_size, kMaxPlyHeaderBytes)), '\0');
  is.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(is.gcount()));
  PlyHeader h;
  std::size_t pos = 0;
  for (std::size_t line = 1;; ++line) {
    const std::size_t eol = head.find('\n', pos);
    if (eol == std::string::npos) {
      if (head.size() < c.file_size)
        c.fail("", "no end_header line in the first " + num(std::uintmax_t{kMaxPlyHeaderBytes}) +
                       " bytes; this is not a PLY file");
      c.fail("", "the header has no end_header line; the file is truncated or not PLY");
    }
    const std::string where = "line " + std::to_string(line);
    const auto tok = split_ws(std::string_view(head).substr(pos, eol - pos));
    pos = eol + 1;
    if (line == 1) {
      if (tok.size() != 1 || tok[0] != "ply")
        c.fail(where, "not a PLY file (the first line must be 'ply'); check the file type");
      continue;
    }
    if (line == 2) {
      if (tok.size() != 3 || tok[0] != "format")
        c.fail(
            where,
            "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'; the header is "
            "corrupt");
      if (tok[1] == "ascii")
        h.format = PlyFormat::kAscii;
      else if (tok[1] == "binary_little_endian")
        h.format = PlyFormat::kBinaryLittleEndian;
      else if (tok[1] == "binary_big_endian")
        h.format = PlyFormat::kBinaryBigEndian;
      else
        c.fail(where, "unknown PLY format '" + printable(tok[1]) +
                          "'; use ascii, binary_little_endian or binary_big_endian");
      continue;
    }
    if (tok.empty()) c.fail(where, "empty header line; remove it");
    if (tok[0] == "end_header") break;
    if (tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "element") {
      std::uintmax_t n = 0;
      const auto r = tok.size() == 3
                         ? std::from_chars(tok[2].data(), tok[2].data() + tok[2].size(), n)
                         : std::from_chars_result{nullptr, std::errc::invalid_argument};
      if (r.ec != std::errc() || r.ptr != tok[2].data() + tok[2].size())
        c.fail(where,
               "expected 'element <name> <count>' with a non-negative integer count; the header "
               "is corrupt");
      h.elements.push_back({std::string(tok[1]), n, line, {}});
      continue;
    }
    if (tok[0] == "property") {
      if (h.elements.empty()) c.fail(where, "a property before any element; the header is corrupt");
      PlyProperty p;
      const bool list = tok.size() == 5 && tok[1] == "list";
      if (!list && tok.size() != 3)
        c.fail(where,
               "expected 'property <type> <name>' or 'property list <count type> <type> <name>'");
      p.name = std::string(tok.back());
      p.type = ply_type(list ? tok[3] : tok[1]);
      if (!p.type)
        c.fail(where, "property type '" + printable(list ? tok[3] : tok[1]) +
                          "' is not supported; use char, uchar, short, ushort, int, uint, float or "
                          "double (or int8 ... float64)");
      if (list) {
        p.size_type = ply_type(tok[2]);
        if (!p.size_type || p.size_type->is_float)
          c.fail(where, "list count type '" + printable(tok[2]) +
                            "' is not supported; use uchar, char, ushort, short, uint or int");
      }
      h.elements.back().properties.push_back(std::move(p));
      continue;
    }
    c.fail(where, "unknown header keyword '" + printable(tok[0]) + "'; the header is corrupt");
  }
  h.data_offset = pos;
  return h;
}

using ScalarGetter = double (*)(cply::PLY_read_number*);
using ListGetter = void (*)(cply::PLY_read_number*, std::vector<long long>&);

template <class T>
double scalar_as_double(cply::PLY_read_number* p) {
  return static_cast<double>(static_cast<cply::PLY_read_typed_number<T>*>(p)->buffer());
}

template <class T>
void list_as_integers(cply::PLY_read_number* p, std::vector<long long>& out) {
  const auto& b = static_cast<cply::PLY_read_typed_list<T>*>(p)->buffer();
  out.assign(b.begin(), b.end());
}

template <class T, class... Rest>
ScalarGetter scalar_getter(cply::PLY_read_number* p) {
  if (dynamic_cast<cply::PLY_read_typed_number<T>*>(p)) return &scalar_as_double<T>;
  if constexpr (sizeof...(Rest) > 0) return scalar_getter<Rest...>(p);
  return nullptr;
}

template <class T, class... Rest>
ListGetter list_getter(cply::PLY_read_number* p) {
  if (dynamic_cast<cply::PLY_read_typed_list<T>*>(p)) return &list_as_integers<T>;
  if constexpr (sizeof...(Rest) > 0) return list_getter<Rest...>(p);
  return nullptr;
}

ScalarGetter any_scalar(cply::PLY_read_number* p) {
  return scalar_getter<std::int8_t, std::uint8_t, std::int16_t, std::uint16_t, std::int32_t,
                       std::uint32_t, float, double>(p);
}

ListGetter integer_list(cply::PLY_read_number* p) {
  return list_getter<std::int8_t, std::uint8_t, std::int16_t, std::uint16_t, std::int32_t,
                     std::uint32_t>(p);
}

struct PlyReading {
  const Ctx& c;
  const PlyHeader& h;
  std::istream& is;

  bool binary() const { return h.format != PlyFormat::kAscii; }

  std::uintmax_t remaining() {
    const auto pos = is.tellg();
    return pos < 0 || static_cast<std::uintmax_t>(pos) > c.file_size
               ? 0
               : c.file_size - static_cast<std::uintmax_t>(pos);
  }

  // CGAL resizes a list to the count it reads before reading the items: look at the count
  // first so that a corrupt one fails here instead of allocating gigabytes.
  void check_list_count(const PlyProperty& p, std::uintmax_t max_count, const Where& where) {
    if (p.size_type->bytes == 1 && !p.size_type->is_signed) return;  // at most 255
    const auto pos = is.tellg();
    long long n = -1;
    bool truncated = false;
    if (!binary()) {
      if (!(is >> n)) truncated = true;
    } else {
      unsigned char b[4] = {};
      const int size = p.size_type->bytes;
      if (!is.read(reinterpret_cast<char*>(b), size)) {
        truncated = true;
      } else {
        if (h.format == PlyFormat::kBinaryBigEndian) std::reverse(b, b + size);
        unsigned long long u = 0;
        for (int i = size - 1; i >= 0; --i) u = (u << 8) | b[i];
        const unsigned long long sign_bit = 1ULL << (8 * size - 1);
        n = p.size_type->is_signed && (u & sign_bit)
                ? static_cast<long long>(u) - 2 * static_cast<long long>(sign_bit)
                : static_cast<long long>(u);
      }
    }
    is.clear();
    is.seekg(pos);
    if (truncated) c.fail(where, "the file ends early, inside this element; it is truncated");
    if (n < 0) c.fail(where, "list '" + p.name + "' has a negative length; the file is corrupt");
    const std::uintmax_t per_item = binary() ? static_cast<std::uintmax_t>(p.type->bytes) : 2;
    if (static_cast<std::uintmax_t>(n) > max_count ||
        static_cast<std::uintmax_t>(n) > remaining() / per_item + 1)
      c.fail(where, "list '" + p.name + "' claims " + std::to_string(n) +
                        " entries, more than the file can hold; the file is corrupt or truncated");
  }

  void read_item(cply::PLY_element& e, const PlyElement& he, std::uintmax_t max_list,
                 const Where& where) {
    for (std::size_t k = 0; k < e.number_of_properties(); ++k) {
      const PlyProperty& p = he.properties[k];
      if (p.size_type) check_list_count(p, max_list, where);
      e.property(k)->get(is);
      if (is.fail()) {
        is.clear();
        is >> std::ws;
        if (binary() || is.eof())
          c.fail(where,
                 "the file ends early, inside this element; it is truncated (copy or "
                 "export it again)");
        c.fail(where, "property '" + p.name + "' is not a valid " + p.type->name +
                          " number (NaN and infinity are not accepted either)");
      }
    }
  }
};

std::size_t find_property(const PlyElement& e, std::string_view name) {
  for (std::size_t k = 0; k < e.properties.size(); ++k)
    if (e.properties[k].name == name) return k;
  return SIZE_MAX;
}

Scan read_ply(const Ctx& c) {
  std::ifstream is = open_binary(c);
  const PlyHeader h = scan_ply_header(c, is);
  const bool binary = h.format != PlyFormat::kAscii;

  // Counts first: nothing is allocated for a header that promises more than the limit or more
  // than the file can hold.
  const PlyElement* vertex_header = nullptr;
  std::uintmax_t need = 0;
  for (const PlyElement& e : h.elements) {
    const std::string where = "line " + std::to_string(e.line);
    const bool is_vertex = e.name == "vertex" || e.name == "vertices";
    if (is_vertex) {
      if (vertex_header) c.fail(where, "a second vertex element; merge them into one");
      vertex_header = &e;
      c.check_count(where, e.count, "the header announces");
    }
    if (e.properties.empty()) continue;  // such items take no bytes and are skipped
    const std::uintmax_t per = e.min_item_bytes(binary);
    const std::uintmax_t available = c.file_size - std::min(c.file_size, h.data_offset);
    // +1: the last ASCII value needs no separator.
    if (e.count > (available + 1) / per || need + e.count * per > available + 1)
      c.fail(where, "the header announces " + num(e.count) + " " + e.name + " items, but only " + num(available) +
                        " bytes follow the header" +
                        (e.count <= available ? std::string(" and they need at least ") + num(need + e.count * per) +
                                                    (need > 0 ? " with the elements before them" : "")
                                              : std::string()) +
                        "; the file is truncated");
    need += e.count * per;
  }
  if (!vertex_header)
    c.fail("", "the file has no vertex element; a PLY scan needs 'element vertex' with x, y, z");

  cply::PLY_reader reader(false);
  is.clear();
  is.seekg(0);
  if (!reader.init(is) || reader.number_of_elements() != h.elements.size())
    c.fail("", "CGAL could not read the PLY header; the file is corrupt");
  for (std::size_t i = 0; i < h.elements.size(); ++i)
    if (reader.element(i).number_of_properties() != h.elements[i].properties.size())
      c.fail("line " + std::to_string(h.elements[i].line),
             "CGAL could not read the properties of this element; the header is corrupt");

  PlyReading r{c, h, is};
  Scan scan;
  const std::size_t vertex_count = static_cast<std::size_t>(vertex_header->count);
  std::vector<long long> corners;
  for (std::size_t i = 0; i < h.elements.size(); ++i) {
    cply::PLY_element& e = reader.element(i);
    const PlyElement& he = h.elements[i];
    const std::string where = "line " + std::to_string(he.line);
    const std::uintmax_t max_list = std::max<std::uintmax_t>(vertex_count, 3);
    auto item = [&](std::uintmax_t j) { return Where{he.name, j}; };

    if (&he == vertex_header) {
      ScalarGetter get[8] = {};  // x y z nx ny nz u v
      std::size_t at[8];
      const char* names[8] = {"x", "y", "z", "nx", "ny", "nz", nullptr, nullptr};
      const char* const uv_names[3][2] = {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}};
      for (const auto& pair : uv_names) {
        const bool a = find_property(he, pair[0]) != SIZE_MAX,
                   b = find_property(he, pair[1]) != SIZE_MAX;
        if (a && b) {
          names[6] = pair[0];
          names[7] = pair[1];
          break;
        }
        if (a != b && !names[6])
          c.fail(where, std::string("the vertices have property '") + (a ? pair[0] : pair[1]) +
                            "' but not '" + (a ? pair[1] : pair[0]) +
                            "'; give both parameters or neither");
      }
      for (int k = 0; k < 8; ++k) {
        at[k] = names[k] ? find_property(he, names[k]) : SIZE_MAX;
        if (at[k] == SIZE_MAX) continue;
        if (he.properties[at[k]].size_type)
          c.fail(where,
                 std::string("vertex property '") + names[k] + "' is a list; it must be a number");
        get[k] = any_scalar(e.property(at[k]));
        if (!get[k])
          c.fail(where, std::string("CGAL could not read property '") + names[k] +
                            "'; the header is corrupt");
      }
      if (!get[0] || !get[1] || !get[2])
        c.fail(where, "the vertices need properties x, y and z; export the positions");
      const int normals = (get[3] != nullptr) + (get[4] != nullptr) + (get[5] != nullptr);
      if (normals != 0 && normals != 3)
        c.fail(where, "the vertices have some of nx, ny, nz but not all three; give all or none");
      scan.positions.reserve(vertex_count);
      if (normals) scan.normals.reserve(vertex_count);
      if (get[6]) scan.uv.reserve(vertex_count);
      for (std::size_t j = 0; j < vertex_count; ++j) {
        const Where w = item(j);
        r.read_item(e, he, max_list, w);
        auto v = [&](int k) { return get[k](e.property(at[k])); };
        scan.positions.push_back(c.point(w, v(0), v(1), v(2)));
        if (normals) scan.normals.push_back(c.normal(w, v(3), v(4), v(5)));
        if (get[6]) scan.uv.push_back(c.param(w, v(6), v(7)));
      }
      continue;
    }

    if (he.name == "face" || he.name == "faces") {
      std::size_t k = find_property(he, "vertex_indices");
      if (k == SIZE_MAX) k = find_property(he, "vertex_index");
      if (k == SIZE_MAX || !he.properties[k].size_type)
        c.fail(where,
               "the faces have no 'vertex_indices' (or 'vertex_index') list; export the faces "
               "with one or leave them out");
      const ListGetter get = integer_list(e.property(k));
      if (!get)
        c.fail(where, "the face vertex indices must be integers, not " +
                          std::string(he.properties[k].type->name) +
                          "; export them as int or uint");
      for (std::uintmax_t j = 0; j < he.count; ++j) {
        const Where w = item(j);
        r.read_item(e, he, max_list, w);
        get(e.property(k), corners);
        c.add_polygon(w, corners, vertex_count, scan.triangles);
      }
      continue;
    }

    if (he.properties.empty()) continue;
    for (std::uintmax_t j = 0; j < he.count; ++j) r.read_item(e, he, max_list, item(j));
  }
  c.finish(scan);
  return scan;
}

// ---------------------------------------------------------------------------------------- OFF

using Kernel = CGAL::Simple_cartesian<double>;

struct OffTooMany {
  std::size_t count;
  const char* what;
};

// CGAL's OFF reader resizes its containers to the counts it reads; these containers refuse
// counts beyond what the file can hold before the allocation happens.
struct OffPoints : std::vector<Kernel::Point_3> {
  std::size_t cap = 0;
  void resize(std::size_t n) {
    if (n > cap) throw OffTooMany{n, "vertices"};
    std::vector<Kernel::Point_3>::resize(n);
  }
};

struct OffPolygon : std::vector<std::size_t> {
  void resize(std::size_t n) {
    if (n > kMaxPolygonCorners) throw OffTooMany{n, "corners"};
    std::vector<std::size_t>::resize(n);
  }
};

struct OffPolygons : std::vector<OffPolygon> {
  std::size_t cap = 0;
  void resize(std::size_t n) {
    if (n > cap) throw OffTooMany{n, "faces"};
    std::vector<OffPolygon>::resize(n);
  }
};

std::string signed_count(std::size_t n) {
  return n > static_cast<std::size_t>(LLONG_MAX) ? std::to_string(static_cast<long long>(n))
                                                 : std::to_string(n);
}

// The header of an OFF file, read by us before CGAL sees it: CGAL 5.5's header scanner reads
// the counts into ints and estimates a halfedge count from them in int arithmetic, which
// overflows (undefined behaviour) for counts near 2^31. Returns the vertex and face counts.
std::pair<std::size_t, std::size_t> read_off_header(const Ctx& c) {
  constexpr const char* kBadHeader =
      "not a valid OFF header (expected OFF, NOFF, 4OFF or 4NOFF, then the vertex, face and edge "
      "counts, each below 2^31)";
  std::ifstream is = open_binary(c);
  // Tokens of the header; '#' starts a comment to the end of the line. A token is always read
  // whole: splitting a long one would read numbers CGAL reads differently (41 digits with
  // leading zeros are one count to CGAL; found by fuzzing). An overlong token comes back empty,
  // which no header accepts.
  auto token = [&is]() {
    constexpr std::size_t kLongest = 32;  // no valid header token is this long
    std::string t;
    bool overlong = false;
    char ch;
    while (is.get(ch)) {
      if (ch == '#') {
        if (!t.empty() || overlong) break;
        while (is.get(ch) && ch != '\n') {
        }
      } else if (std::isspace(static_cast<unsigned char>(ch))) {
        if (!t.empty() || overlong) break;
      } else {
        if (t.size() == kLongest) overlong = true;
        if (!overlong) t += ch;
      }
    }
    return overlong ? std::string() : t;
  };
  const std::string keyword = token();
  // [ST][C][N][4][n]OFF
  std::string_view rest = keyword;
  auto take = [&rest](std::string_view prefix) {
    if (!rest.starts_with(prefix)) return false;
    rest.remove_prefix(prefix.size());
    return true;
  };
  const bool textures = take("ST"), colours = take("C");
  take("N");
  take("4");
  const bool dimension = take("n");
  if (rest != "OFF") c.fail("line 1", kBadHeader);
  std::string next = token();
  bool other_dimension = false;
  if (dimension) {
    other_dimension = next != "3";
    next = token();
  }
  if (next == "BINARY" || textures || colours || other_dimension)
    c.fail("line 1",
           "binary OFF and OFF with colours (C), texture coordinates (ST) or a dimension other "
           "than 3 are not supported; convert the scan to PLY or to plain ASCII OFF");
  long long counts[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    const std::string t = k == 0 ? next : token();
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), counts[k]);
    if (t.empty() || ec != std::errc() || end != t.data() + t.size() || counts[k] < 0 ||
        counts[k] > INT_MAX)
      c.fail("line 1", kBadHeader);
  }
  // CGAL doubles the edge count in int arithmetic; the count is otherwise unused.
  if (counts[2] > INT_MAX / 2)
    c.fail("line 1", "the edge count " + std::to_string(counts[2]) +
                         " is out of range (at most 2^30); readers ignore it, so set it to 0");
  const auto nv = static_cast<std::size_t>(counts[0]), nf = static_cast<std::size_t>(counts[1]);
  // Minimum bytes of a vertex ("0 0 0\n") and of a face ("3 0 1 2\n").
  constexpr std::uintmax_t kVertexBytes = 6, kFaceBytes = 8;
  c.check_count("line 1", nv, "the header announces");
  if (nv * kVertexBytes + nf * kFaceBytes > c.file_size)
    c.fail("line 1", "the header announces " + std::to_string(nv) + " vertices and " +
                         std::to_string(nf) + " faces, more than the " + num(c.file_size) +
                         " bytes of the file can hold; the file is truncated");
  // CGAL's estimate 2.1 (V + F + 10) must stay below 2^31.
  if (static_cast<double>(nv + nf) > 1e9)
    c.fail("line 1", "the header announces " + std::to_string(nv) + " vertices and " +
                         std::to_string(nf) + " faces; OFF files are read only up to 10^9 vertices "
                         "and faces together; convert the scan to PLY");
  return {nv, nf};
}

Scan read_off(const Ctx& c) {
  const auto [nv, nf] = read_off_header(c);
  {
    // CGAL's own view of the (now bounded) header: the variants its reader gets wrong.
    std::ifstream is = open_binary(c);
    CGAL::File_scanner_OFF header(is, false);
    if (is.fail() || header.skel())
      c.fail("line 1",
             "not a valid OFF header (expected OFF, NOFF, 4OFF or 4NOFF, then the vertex, face "
             "and edge counts, each below 2^31)");
    // CGAL 5.5's polygon-soup OFF reader misreads these: binary faces are followed by a colour
    // count it does not skip (so faces are lost), and for colours (COFF) and texture
    // coordinates (STOFF) it can index past the values of a line.
    if (header.binary() || header.has_colors() || header.has_textures() ||
        (header.n_dimensional() && header.dimension() != 3))
      c.fail("line 1",
             "binary OFF and OFF with colours (C), texture coordinates (ST) or a dimension other "
             "than 3 are not supported; convert the scan to PLY or to plain ASCII OFF");
    if (header.size_of_vertices() != nv || header.size_of_facets() != nf)
      c.fail("line 1", "CGAL reads this header differently (" + std::to_string(header.size_of_vertices()) +
                           " vertices, " + std::to_string(header.size_of_facets()) +
                           " faces); the header is malformed");
    // CGAL's face reader converts every number of a face line to size_t, which is undefined
    // for negative, non-finite or huge values (found by fuzzing). Read the lines as it does
    // (vertex lines through its own scanner, then one line per face, '#' comments removed) and
    // check the numbers first.
    double x = 0, y = 0, z = 0, w = 0;
    for (std::size_t i = 0; i < nv && is.good(); ++i) header.scan_vertex(x, y, z, w);
    std::string line;
    for (std::size_t f = 0; f < nf && is.good(); ++f) {
      is >> CGAL::skip_comment_OFF;  // what the scanner's private skip_comment() does
      if (!std::getline(is, line)) break;
      if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
      std::istringstream numbers(line);
      double value = 0;
      std::size_t k = 0, corners = 0;
      while (numbers >> value) {
        if (k == 0) {
          if (!(value >= 0 && value <= static_cast<double>(kMaxPolygonCorners) && value == std::floor(value)))
            c.fail(Where{"face", f}, "the corner count " + num(value) + " is not a whole number from 3 to " +
                                          std::to_string(kMaxPolygonCorners) + "; the file is corrupt");
          corners = static_cast<std::size_t>(value);
        } else if (k <= corners &&
                   !(value >= 0 && value < static_cast<double>(nv) && value == std::floor(value))) {
          c.fail(Where{"face", f}, "corner " + std::to_string(k - 1) + " is vertex " + num(value) +
                                        ", not a whole number from 0 to " + std::to_string(nv) + " - 1");
        }
        ++k;
      }
    }
  }

  std::ifstream is = open_binary(c);
  OffPoints points;
  points.cap = nv;
  OffPolygons polygons;
  polygons.cap = nf;
  std::vector<Kernel::Vector_3> normals;
  bool ok = false;
  try {
    ok = CGAL::IO::read_OFF(
        is, points, polygons,
        CGAL::parameters::vertex_normal_output_iterator(std::back_inserter(normals))
            .verbose(false));
  } catch (const OffTooMany& e) {
    c.fail(stream_location(c, is, false),
           "a face with " + signed_count(e.count) + " corners; the file is corrupt");
  }
  if (!ok)
    c.fail(stream_location(c, is, false),
           "CGAL could not read this vertex or face: a malformed or out-of-range number, too few "
           "values, a vertex index outside 0 to " +
               std::to_string(nv) + " - 1, or the end of the file before the " +
               std::to_string(nv) + " vertices and " + std::to_string(nf) +
               " faces the header announces (truncated)");

  Scan scan;
  scan.positions.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    scan.positions.push_back(c.point({"vertex", i}, points[i].x(), points[i].y(), points[i].z()));
  if (!normals.empty()) {
    if (normals.size() != points.size())
      c.fail("", "CGAL read normals for only some vertices; the file is corrupt");
    for (std::size_t i = 0; i < normals.size(); ++i)
      scan.normals.push_back(
          c.normal({"vertex", i}, normals[i].x(), normals[i].y(), normals[i].z()));
  }
  std::vector<long long> corners;
  for (std::size_t f = 0; f < polygons.size(); ++f) {
    corners.assign(polygons[f].begin(), polygons[f].end());
    c.add_polygon({"face", f}, corners, nv, scan.triangles);
  }
  c.finish(scan);
  return scan;
}

// ---------------------------------------------------------------------------------------- STL

Scan read_stl(const Ctx& c) {
  std::ifstream is = open_binary(c);
  // A binary STL is an 80-byte header, a triangle count and 50 bytes per triangle. CGAL reads
  // it triangle by triangle (no allocation from the count), but a huge count is refused here so
  // that a large file fails before it is read: a mesh has about two triangles per vertex.
  char head[84] = {};
  is.read(head, sizeof head);
  const bool full_head = is.gcount() == static_cast<std::streamsize>(sizeof head);
  std::uint32_t declared = 0;
  for (int i = 3; i >= 0; --i)
    declared = (declared << 8) | static_cast<unsigned char>(head[80 + i]);
  std::size_t first = 0;
  while (first < 80 && std::isspace(static_cast<unsigned char>(head[first]))) ++first;
  const bool ascii =
      std::string_view(head + first, std::min<std::size_t>(5, 84 - first)) == "solid";
  const bool binary_layout = full_head && 84 + 50 * std::uintmax_t{declared} == c.file_size;
  if (binary_layout && declared / 2 > c.limit)
    c.check_count("byte 80", declared / 2,
                  "the header announces " + num(std::uintmax_t{declared}) + " triangles, about");

  // CGAL falls back to the binary reader when the ASCII one fails, and takes a file shorter
  // than a binary header for an empty binary STL: a truncated small ASCII file would be
  // accepted. A complete ASCII STL ends with 'endsolid'.
  if (ascii && !binary_layout) {
    const std::uintmax_t tail = std::min<std::uintmax_t>(c.file_size, 4096);
    std::string end(static_cast<std::size_t>(tail), '\0');
    is.clear();
    is.seekg(static_cast<std::streamoff>(c.file_size - tail));
    is.read(end.data(), static_cast<std::streamsize>(tail));
    if (end.find("endsolid") == std::string::npos)
      c.fail("", "neither a complete ASCII STL (no closing 'endsolid') nor a binary one" +
                     (full_head ? " (its header announces " + num(std::uintmax_t{declared}) +
                                      " triangles, " + num(84 + 50 * std::uintmax_t{declared}) +
                                      " bytes, but the file has " + num(c.file_size) + ")"
                                : std::string()) +
                     "; the file is truncated or corrupt");
  }

  // CGAL merges corners through an ordered map of positions, which a NaN corrupts (the facet
  // vanishes without an error). Binary facets are checked here first; an ASCII file of binary
  // layout never matches a non-finite float (that needs a byte of 0x80 or more).
  if (full_head && (binary_layout || !ascii)) {  // what CGAL reads as binary (it ignores extra bytes)
    is.clear();
    is.seekg(84);
    char rec[50];
    for (std::uint32_t f = 0; f < declared && is.read(rec, sizeof rec); ++f)
      for (int corner = 0; corner < 3; ++corner) {
        double xyz[3];
        for (int k = 0; k < 3; ++k) {
          const char* b = rec + 12 * (1 + corner) + 4 * k;
          std::uint32_t bits = 0;
          for (int i = 3; i >= 0; --i) bits = (bits << 8) | static_cast<unsigned char>(b[i]);
          xyz[k] = std::bit_cast<float>(bits);
        }
        c.point({"facet", f}, xyz[0], xyz[1], xyz[2]);
      }
  }

  is.clear();
  is.seekg(0);
  std::vector<std::array<double, 3>> points;
  std::vector<std::array<int, 3>> triangles;
  if (!CGAL::IO::read_STL(is, points, triangles, CGAL::parameters::verbose(false))) {
    if (!ascii && full_head)
      c.fail("", "not a valid binary STL: its header announces " + num(std::uintmax_t{declared}) +
                     " triangles (" + num(84 + 50 * std::uintmax_t{declared}) +
                     " bytes) but the file has " + num(c.file_size) + " bytes; it is truncated");
    c.fail("", std::string("not a valid ") + (ascii ? "ASCII " : "") +
                   "STL: CGAL found a facet without exactly three vertices, a malformed number or "
                   "no closing 'endsolid'; the file is truncated or corrupt");
  }
  // CGAL creates points only for facet corners: a point no facet uses is a leftover of an
  // incomplete facet.
  std::vector<char> used(points.size(), 0);
  for (const auto& t : triangles)
    for (int i : t)
      if (i >= 0 && static_cast<std::size_t>(i) < used.size())
        used[static_cast<std::size_t>(i)] = 1;
  if (std::find(used.begin(), used.end(), 0) != used.end())
    c.fail("", "the last facet is incomplete; the file is truncated or corrupt");
  Scan scan;
  c.check_count("", points.size(), "the file has");
  scan.positions.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    scan.positions.push_back(c.point({"vertex", i}, points[i][0], points[i][1], points[i][2]));
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const long long t[3] = {triangles[f][0], triangles[f][1], triangles[f][2]};
    c.add_polygon({"facet", f}, t, points.size(), scan.triangles);
  }
  c.finish(scan);
  return scan;
}

// ---------------------------------------------------------------------------------------- OBJ

// A number as std::from_chars reads it (also with a leading '+'); the reason if it is not one.
std::string parse_double(std::string_view s, double& x) {
  const std::string_view token = s;
  if (!s.empty() && s[0] == '+' && (s.size() == 1 || (s[1] != '-' && s[1] != '+')))
    s.remove_prefix(1);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), x);
  if (r.ptr != s.data() + s.size() || r.ec == std::errc::invalid_argument)
    return "'" + printable(token) + "' is not a number";
  if (r.ec == std::errc::result_out_of_range)
    return "'" + printable(token) + "' is beyond the range of double";
  return {};
}

// tinyobjloader turns a number it cannot parse (including "nan" and "inf") into 0 without a
// word, and a missing one into 0 as well; this pass rejects those lines with their number.
void check_obj_numbers(const Ctx& c, std::string_view text) {
  std::size_t line = 0, pos = 0;
  while (pos < text.size()) {
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    const std::string_view l = text.substr(pos, eol - pos);
    pos = eol + 1;
    ++line;
    if (l.size() < 2 || l.find_first_not_of(" \t") == std::string_view::npos) continue;
    const std::string_view t = l.substr(l.find_first_not_of(" \t"));
    if (t[0] != 'v') continue;
    const auto tok = split_ws(t);
    const std::size_t need = tok[0] == "v" ? 3 : tok[0] == "vn" ? 3 : tok[0] == "vt" ? 2 : 0;
    if (need == 0) continue;
    const Where where{"line", line};
    if (tok.size() < need + 1)
      c.fail(where, "'" + std::string(tok[0]) + "' needs " + std::to_string(need) +
                        " numbers, found " + std::to_string(tok.size() - 1) +
                        "; the file is truncated or corrupt");
    for (std::size_t k = 1; k <= need; ++k) {
      double x = 0;
      if (const std::string bad = parse_double(tok[k], x); !bad.empty())
        c.fail(where, bad + "; fix the exporter or the file");
      c.check_value(where,
                    tok[0] == "vt"   ? (k == 1 ? "u" : "v")
                    : tok[0] == "vn" ? (k == 1   ? "nx"
                                        : k == 2 ? "ny"
                                                 : "nz")
                                     : (k == 1   ? "x"
                                        : k == 2 ? "y"
                                                 : "z"),
                    x);
    }
  }
}

struct CornerKey {
  int v, vt, vn;
  bool operator==(const CornerKey&) const = default;
};

struct CornerHash {
  std::size_t operator()(const CornerKey& k) const {
    std::uint64_t h = static_cast<std::uint32_t>(k.v);
    h = h * 0x9E3779B97F4A7C15ULL ^ static_cast<std::uint32_t>(k.vt);
    h = h * 0x9E3779B97F4A7C15ULL ^ static_cast<std::uint32_t>(k.vn);
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

Scan read_obj(const Ctx& c) {
  const std::string text = read_file(c.path);
  check_obj_numbers(c, text);

  tinyobj::ObjReaderConfig config;
  config.triangulate = false;  // we fan-triangulate, as for the other formats
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  // From a string, so that tinyobjloader does not open the .mtl files the OBJ names.
  if (!reader.ParseFromString(text, "", config)) {
    std::string e = reader.Error();
    while (!e.empty() && (e.back() == '\n' || e.back() == '.')) e.pop_back();
    c.fail("", "tinyobjloader could not read it (" + printable(e, 200) +
                   "); OBJ indices start at 1 and must name existing v/vt/vn lines");
  }
  const tinyobj::attrib_t& a = reader.GetAttrib();
  const std::size_t nv = a.vertices.size() / 3, nvt = a.texcoords.size() / 2,
                    nvn = a.normals.size() / 3;
  c.check_count("", nv, "the file has");
  // OBJ numbers its v, vt, vn lines and faces from 1.
  auto v_name = [](const char* kind, std::size_t i) { return Where{kind, i + 1}; };
  std::vector<Vector3> vn(nvn);
  for (std::size_t i = 0; i < nvn; ++i)
    vn[i] = c.normal(v_name("vn", i), a.normals[3 * i], a.normals[3 * i + 1], a.normals[3 * i + 2]);

  Scan scan;
  // The point of a (v, vt, vn) triple: the first triple of each v in a table, the others (UV
  // seams, normal creases: few) in a hash map.
  std::vector<int> first_point(nv, -1);
  std::vector<std::array<int, 2>> first_key(nv);
  std::unordered_map<CornerKey, int, CornerHash> other_points;
  int has_vt = -1, has_vn = -1;  // unknown until the first corner
  std::size_t face = 0;
  std::vector<long long> corners, corner_v;
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    const auto& m = shape.mesh;
    std::size_t total = 0;
    for (unsigned char n : m.num_face_vertices) total += n;
    if (total != m.indices.size())
      c.fail("",
             "a face has more than 255 corners, which tinyobjloader cannot represent; split it");
    std::size_t offset = 0;
    for (unsigned char n : m.num_face_vertices) {
      const Where where{"face", ++face};
      corners.clear();
      corner_v.clear();
      for (std::size_t j = 0; j < n; ++j) {
        const tinyobj::index_t& ix = m.indices[offset + j];
        const std::string corner = "corner " + std::to_string(j + 1);
        auto check = [&](int idx, std::size_t count, const char* kind) {
          if (idx < 0 || static_cast<std::size_t>(idx) >= count)
            c.fail(where, corner + " refers to " + kind + " " +
                              (idx < 0 ? "before the first one (a relative index too far back)"
                                       : std::to_string(idx + 1)) +
                              ", but the file has " + std::to_string(count) + " " + kind +
                              " lines; the file is corrupt or truncated");
        };
        check(ix.vertex_index, nv, "v");
        const int t = ix.texcoord_index >= 0, nn = ix.normal_index >= 0;
        if (has_vt < 0) has_vt = t;
        if (has_vn < 0) has_vn = nn;
        if (t != has_vt)
          c.fail(where, corner + (t ? " has" : " has no") +
                            " texture coordinate (vt) while earlier corners " +
                            (t ? "have none" : "have one") +
                            "; give every face corner a vt index or none");
        if (nn != has_vn)
          c.fail(where, corner + (nn ? " has" : " has no") + " normal (vn) while earlier corners " +
                            (nn ? "have none" : "have one") +
                            "; give every face corner a vn index or none");
        if (t) check(ix.texcoord_index, nvt, "vt");
        if (nn) check(ix.normal_index, nvn, "vn");
        const CornerKey key{ix.vertex_index, t ? ix.texcoord_index : -1, nn ? ix.normal_index : -1};
        const std::size_t v = static_cast<std::size_t>(key.v);
        const int next = static_cast<int>(scan.positions.size());
        int point = next;
        if (first_point[v] < 0) {
          first_point[v] = next;
          first_key[v] = {key.vt, key.vn};
        } else if (first_key[v] == std::array<int, 2>{key.vt, key.vn}) {
          point = first_point[v];
        } else {
          point = other_points.try_emplace(key, next).first->second;
        }
        if (point == next) {
          if (scan.positions.size() == c.limit)
            c.check_count(where.str(), c.limit + 1, "the faces use at least");
          scan.positions.push_back(c.point(v_name("v", v), a.vertices[3 * v], a.vertices[3 * v + 1],
                                           a.vertices[3 * v + 2]));
          if (t)
            scan.uv.push_back(c.param(v_name("vt", static_cast<std::size_t>(key.vt)),
                                      a.texcoords[2 * key.vt], a.texcoords[2 * key.vt + 1]));
          if (nn) scan.normals.push_back(vn[static_cast<std::size_t>(key.vn)]);
        }
        corners.push_back(point);
        corner_v.push_back(key.v);
      }
      offset += n;
      // Drop triangles with a repeated position, also when the corners differ only in vt/vn.
      for (std::size_t j = 1; j + 1 < corners.size(); ++j)
        if (corner_v[0] != corner_v[j] && corner_v[j] != corner_v[j + 1] &&
            corner_v[0] != corner_v[j + 1])
          scan.triangles.push_back({static_cast<int>(corners[0]), static_cast<int>(corners[j]),
                                    static_cast<int>(corners[j + 1])});
        else
          ++c.dropped;
    }
  }

  if (face == 0) {
    // A point cloud: vt and vn lines, if one per v line, belong to the v line of the same rank.
    scan.positions.reserve(nv);
    for (std::size_t v = 0; v < nv; ++v)
      scan.positions.push_back(
          c.point(v_name("v", v), a.vertices[3 * v], a.vertices[3 * v + 1], a.vertices[3 * v + 2]));
    if (nvt == nv)
      for (std::size_t v = 0; v < nv; ++v)
        scan.uv.push_back(c.param(v_name("vt", v), a.texcoords[2 * v], a.texcoords[2 * v + 1]));
    if (nvn == nv) scan.normals = std::move(vn);
  } else {
    for (std::size_t v = 0; v < nv; ++v) {
      if (first_point[v] >= 0) continue;
      if (has_vt == 1 || has_vn == 1)
        c.fail(v_name("v", v),
               std::string("no face uses this vertex, but the faces have ") +
                   (has_vt == 1 ? "texture coordinates" : "normals") +
                   ", which it would lack; remove unused vertices or use them in a face");
      if (scan.positions.size() == c.limit) c.check_count("", c.limit + 1, "the file has at least");
      scan.positions.push_back(
          c.point(v_name("v", v), a.vertices[3 * v], a.vertices[3 * v + 1], a.vertices[3 * v + 2]));
    }
  }
  c.finish(scan);
  return scan;
}

// ---------------------------------------------------------------------------------------- XYZ

Scan read_xyz(const Ctx& c) {
  std::ifstream is = open_binary(c);
  Scan scan;
  std::string buf(kMaxXyzLine, '\0');
  std::size_t columns = 0, first_line = 0;
  std::size_t line = 0;
  double v[8];
  while (true) {
    is.getline(buf.data(), static_cast<std::streamsize>(buf.size()));
    const auto got = is.gcount();
    if (is.fail() && !is.eof() && got == static_cast<std::streamsize>(buf.size()) - 1)
      c.fail("line " + std::to_string(line + 1), "longer than " + std::to_string(kMaxXyzLine) +
                                                     " characters; this is not an XYZ text file");
    if (got == 0 && is.eof()) break;
    if (is.bad()) throw IoError(c.path + ": read error; check the disk or the network share");
    ++line;
    const std::string_view l(buf.data(), std::strlen(buf.data()));
    if (l.size() + 1 < static_cast<std::size_t>(got))
      c.fail(Where{"line", line}, "contains a NUL byte; this is not an XYZ text file");
    const auto tok = split_ws(l);
    const bool eof = is.eof();
    is.clear();
    if (tok.empty() || tok[0][0] == '#') {
      if (eof) break;
      continue;
    }
    const Where where{"line", line};
    if (columns == 0) {
      if (tok.size() != 3 && tok.size() != 5 && tok.size() != 6 && tok.size() != 8)
        c.fail(where, "has " + std::to_string(tok.size()) +
                          " values; expected 3 (x y z), 5 (x y z u v), 6 (x y z nx ny nz) or 8 "
                          "(x y z u v nx ny nz)");
      columns = tok.size();
      first_line = line;
    } else if (tok.size() != columns) {
      c.fail(where, "has " + std::to_string(tok.size()) + " values but line " +
                        std::to_string(first_line) + " has " + std::to_string(columns) +
                        "; every point needs the same columns (is the file truncated?)");
    }
    for (std::size_t k = 0; k < columns; ++k)
      if (const std::string bad = parse_double(tok[k], v[k]); !bad.empty())
        c.fail(where,
               "value " + std::to_string(k + 1) + " " + bad + "; fix the exporter or the file");
    if (scan.positions.size() == c.limit)
      c.check_count(where.str(), c.limit + 1, "the file has at least");
    scan.positions.push_back(c.point(where, v[0], v[1], v[2]));
    if (columns == 5 || columns == 8) scan.uv.push_back(c.param(where, v[3], v[4]));
    if (columns == 6) scan.normals.push_back(c.normal(where, v[3], v[4], v[5]));
    if (columns == 8) scan.normals.push_back(c.normal(where, v[5], v[6], v[7]));
    if (eof) break;
  }
  c.finish(scan);
  return scan;
}

}  // namespace

Scan read_scan(const std::string& path, const ScanReadOptions& options) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st))
    throw IoError(path + ": cannot read the file: " +
                  (ec ? ec.message() : std::string("no such file")) + "; check the path");
  if (fs::is_directory(st))
    throw IoError(path + ": is a directory, not a file; give the path of a scan file");
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe)
      throw IoError(path + ": cannot open the file: " + std::strerror(errno) +
                    "; check its permissions");
  }
  Ctx c;
  c.path = path;
  c.file_size = fs::file_size(path, ec);
  if (ec) throw IoError(path + ": cannot read the file size: " + ec.message() + "; check the path");
  c.limit = std::min<std::size_t>(options.max_points, static_cast<std::size_t>(INT_MAX));
  c.limit_name = options.limit_name;

  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  using Reader = Scan (*)(const Ctx&);
  Reader reader = ext == ".ply"                    ? &read_ply
                  : ext == ".obj"                  ? &read_obj
                  : ext == ".off"                  ? &read_off
                  : ext == ".stl"                  ? &read_stl
                  : ext == ".xyz" || ext == ".txt" ? &read_xyz
                                                   : nullptr;
  if (!reader)
    c.fail("", (ext.empty() ? std::string("the file name has no extension")
                            : "unknown extension '" + printable(ext) + "'") +
                   "; supported scan formats are " + kExtensions);
  if (c.file_size == 0) c.fail("", "the file is empty; export the scan again");
  try {
    return reader(c);
  } catch (const Error&) {
    throw;
  } catch (const std::bad_alloc&) {
    c.fail("", "out of memory while reading; the file is corrupt or too large for this machine");
  } catch (const std::exception& e) {
    // A library failing in a way it does not report (e.g. a CGAL precondition, a length error).
    c.fail("", std::string("could not be read (") + printable(e.what(), 200) +
                   "); the file is corrupt or truncated");
  }
}

}  // namespace tbs
