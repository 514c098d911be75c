// The XYZ/TXT reader, which no library provides: one point per line, 3, 5, 6 or 8 columns
// (x y z [u v] [nx ny nz]).

#include "scan_readers.h"

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

// The longest XYZ line we accept (8 numbers with 17 digits fit in well under 1 KiB).
constexpr std::size_t kMaxXyzLine = 1 << 16;

}  // namespace

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

}  // namespace tbs::detail
