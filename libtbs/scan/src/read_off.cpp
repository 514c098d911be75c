// The OFF reader: our own pass over the header, so that no count reaches CGAL before it is
// checked, then CGAL's OFF reader into containers that refuse counts the file cannot hold.
// COFF (vertex colours), which CGAL 5.5 misreads, is read by our own line reader.

#include "scan_readers.h"

#include <CGAL/IO/OFF.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace tbs::detail {
namespace {

// Corner counts above this are corrupt data; the cap keeps a bad count from allocating.
constexpr std::size_t kMaxPolygonCorners = 1 << 20;

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

// The longest line of a COFF file we read (a face of many corners still fits).
constexpr std::size_t kMaxOffLine = 1 << 20;

struct OffHeader {
  std::size_t vertices = 0, faces = 0;
  bool colours = false;  // COFF: a colour after each vertex (and maybe after each face)
  bool normals = false;  // NOFF: nx ny nz after each vertex
};

// The header of an OFF file, read by us before CGAL sees it: CGAL 5.5's header scanner reads
// the counts into ints and estimates a halfedge count from them in int arithmetic, which
// overflows (undefined behaviour) for counts near 2^31.
OffHeader read_off_header(const Ctx& c) {
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
  const bool normals = take("N");
  const bool homogeneous = take("4");
  const bool dimension = take("n");
  if (rest != "OFF") c.fail("line 1", kBadHeader);
  std::string next = token();
  bool other_dimension = false;
  if (dimension) {
    other_dimension = next != "3";
    next = token();
  }
  if (next == "BINARY" || textures || other_dimension || (colours && (homogeneous || dimension)))
    c.fail("line 1",
           "binary OFF and OFF with texture coordinates (ST), a dimension other than 3 or "
           "homogeneous coordinates with colours (C4OFF) are not supported; convert the scan to "
           "PLY or to plain ASCII OFF");
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
  return {nv, nf, colours, normals};
}

// COFF and CNOFF, read line by line: CGAL 5.5's polygon-soup reader can index past the values
// of a line when vertices carry colours. A vertex line is x y z, then nx ny nz (CNOFF), then
// its colour (1, 3 or 4 numbers), which is skipped; a face line is the corner count, the
// corners, then an optional colour. '#' starts a comment to the end of the line.
Scan read_off_lines(const Ctx& c, const OffHeader& h) {
  std::ifstream is = open_binary(c);
  std::string buf(kMaxOffLine, '\0');
  std::size_t line = 0;
  std::vector<std::string_view> words;
  // The words of the next line that has any; false at the end of the file.
  auto next = [&]() {
    while (true) {
      is.getline(buf.data(), static_cast<std::streamsize>(buf.size()));
      const auto got = is.gcount();
      if (is.fail() && !is.eof() && got == static_cast<std::streamsize>(buf.size()) - 1)
        c.fail(Where{"line", line + 1}, "longer than " + std::to_string(kMaxOffLine) +
                                            " characters; the file is corrupt");
      if (got == 0 && is.eof()) return false;
      if (is.bad()) throw IoError(c.path + ": read error; check the disk or the network share");
      ++line;
      std::string_view l(buf.data(), std::strlen(buf.data()));
      if (const auto hash = l.find('#'); hash != std::string_view::npos) l = l.substr(0, hash);
      words = split_ws(l);
      const bool eof = is.eof();
      is.clear();
      if (!words.empty()) return true;
      if (eof) return false;
    }
  };
  // The header's keyword and three counts, already checked; the data starts on the next line.
  for (std::size_t taken = 0; taken < 4;) {
    if (!next()) c.fail("line 1", "the file ends inside the header");
    taken += words.size();
    if (taken > 4)
      c.fail(Where{"line", line}, "the first vertex must start on the line after the counts");
  }
  Scan scan;
  scan.positions.reserve(h.vertices);
  const std::size_t need = h.normals ? 6 : 3;
  double v[6];
  for (std::size_t i = 0; i < h.vertices; ++i) {
    if (!next())
      c.fail(Where{"vertex", i}, "the file ends before the " + std::to_string(h.vertices) +
                                     " vertices the header announces; it is truncated");
    const Where where{"line", line};
    if (words.size() < need)
      c.fail(where, "vertex " + std::to_string(i) + " has " + std::to_string(words.size()) +
                        " values; a COFF vertex is x y z" + (h.normals ? " nx ny nz" : "") +
                        " and then its colour");
    for (std::size_t k = 0; k < need; ++k)
      if (const std::string bad = parse_double(words[k], v[k]); !bad.empty())
        c.fail(where, "value " + std::to_string(k + 1) + " " + bad + "; fix the exporter or the file");
    scan.positions.push_back(c.point(where, v[0], v[1], v[2]));
    if (h.normals) scan.normals.push_back(c.normal(where, v[3], v[4], v[5]));
  }
  std::vector<long long> corners;
  for (std::size_t f = 0; f < h.faces; ++f) {
    if (!next())
      c.fail(Where{"face", f}, "the file ends before the " + std::to_string(h.faces) +
                                   " faces the header announces; it is truncated");
    const Where where{"line", line};
    long long count = -1;
    const auto [end, ec] = std::from_chars(words[0].data(), words[0].data() + words[0].size(), count);
    if (ec != std::errc() || end != words[0].data() + words[0].size() || count < 0 ||
        count > static_cast<long long>(kMaxPolygonCorners))
      c.fail(where, "face " + std::to_string(f) + ": the corner count '" + printable(words[0]) +
                        "' is not a whole number from 3 to " + std::to_string(kMaxPolygonCorners) +
                        "; the file is corrupt");
    if (words.size() < static_cast<std::size_t>(count) + 1)
      c.fail(where, "face " + std::to_string(f) + " announces " + std::to_string(count) +
                        " corners but gives " + std::to_string(words.size() - 1) + "; the file is corrupt");
    corners.assign(static_cast<std::size_t>(count), 0);
    for (long long k = 0; k < count; ++k) {
      const std::string_view w = words[static_cast<std::size_t>(k) + 1];
      const auto [e, err] = std::from_chars(w.data(), w.data() + w.size(), corners[static_cast<std::size_t>(k)]);
      if (err != std::errc() || e != w.data() + w.size())
        c.fail(where, "face " + std::to_string(f) + ": corner " + std::to_string(k) + " '" +
                          printable(w) + "' is not a whole number; the file is corrupt");
    }
    c.add_polygon({"face", f}, corners, h.vertices, scan.triangles);
  }
  c.finish(scan);
  return scan;
}

}  // namespace

Scan read_off(const Ctx& c) {
  const OffHeader h = read_off_header(c);
  if (h.colours) return read_off_lines(c, h);
  const std::size_t nv = h.vertices, nf = h.faces;
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
             "binary OFF and OFF with texture coordinates (ST) or a dimension other than 3 are "
             "not supported; convert the scan to PLY or to plain ASCII OFF");
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

}  // namespace tbs::detail
