// Reading a scan file: read_scan() picks the reader for the extension (read_<format>.cpp) and
// turns what a library throws without a word into InvalidInput naming the file. Around the
// libraries every reader adds what they do not do: counts are checked before anything is
// allocated, indices are range-checked, values must be finite, and every failure names the file
// and the line or element (scan_readers.h).

#include "scan_readers.h"

#include <tbs/errors.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace tbs {
namespace detail {

std::string printable(std::string_view s, std::size_t max) {
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

}  // namespace detail

namespace {

namespace fs = std::filesystem;

const char* const kExtensions = ".ply, .obj, .off, .stl, .xyz, .txt";

}  // namespace

using namespace detail;

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
