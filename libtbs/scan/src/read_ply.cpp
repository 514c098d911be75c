// The PLY reader (ASCII and binary): our own pass over the header, for the format, the element
// counts and the value types CGAL does not report, then CGAL's PLY reader for the items.

#include "scan_readers.h"

#include <CGAL/IO/PLY/PLY_reader.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace tbs::detail {
namespace {

namespace cply = CGAL::IO::internal;

// A PLY header is a few hundred bytes; reading at most this much finds the end of any real one
// without reading a whole binary file that has no end_header.
constexpr std::size_t kMaxPlyHeaderBytes = 1 << 20;

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

}  // namespace

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

}  // namespace tbs::detail
