// The OBJ reader through tinyobjloader (its double-precision build), with a pass of our own
// for the numbers it would turn into 0 without a word, and (u, v) per vertex from vt.

#include "scan_readers.h"

#include <tbs/io.h>

#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace tbs::detail {
namespace {

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

}  // namespace

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

}  // namespace tbs::detail
