#pragma once
// What the scan readers share: the context of one read (file, limits, the checks every value
// passes, messages that name the file and the element), and one reader per format, each in
// its own read_<format>.cpp. read_scan() (scan_io.cpp) picks the reader by extension.

#include <tbs/errors.h>
#include <tbs/scan.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace tbs::detail {

// A coordinate beyond 1e30 is a unit or export error, not a measurement, and squaring it (as
// fitting does) would overflow double.
constexpr double kMaxAbsValue = 1e30;

// s with control characters replaced by '?', cut after max characters.
std::string printable(std::string_view s, std::size_t max = 40);
// The shortest decimal form that reads back as x.
std::string num(double x);
std::string num(std::uintmax_t x);

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
std::string stream_location(const Ctx& c, std::istream& is, bool binary);
// The file opened for binary reading. \throw IoError if it cannot be opened.
std::ifstream open_binary(const Ctx& c);
// The words of a line, split at white space.
std::vector<std::string_view> split_ws(std::string_view line);
// A number as std::from_chars reads it (also with a leading '+'); the reason if it is not one.
std::string parse_double(std::string_view s, double& x);

// One reader per format: the scan, or InvalidInput naming the file and the element.
Scan read_ply(const Ctx& c);
Scan read_off(const Ctx& c);
Scan read_stl(const Ctx& c);
Scan read_obj(const Ctx& c);
Scan read_xyz(const Ctx& c);

}  // namespace tbs::detail
