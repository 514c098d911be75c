// The STL reader (ASCII and binary) through CGAL's, with the triangle count of a binary file
// checked against the file size first.

#include "scan_readers.h"

#include <CGAL/IO/STL.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace tbs::detail {

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

}  // namespace tbs::detail
