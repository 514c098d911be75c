#include <CGAL/Eigen_svd.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/jet_estimate_normals.h>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>
#include <tbs/errors.h>
#include <tbs/scan.h>
#include <unistd.h>

#include "jet_solver.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <string_view>
#include <vector>

namespace tbs {
namespace {

namespace fs = std::filesystem;
using Tri = std::array<int, 3>;

fs::path temp_dir() {
  const fs::path p = fs::temp_directory_path() / ("tbs_scan_io_test_" + std::to_string(::getpid()));
  fs::create_directories(p);
  return p;
}

std::string write(const std::string& name, std::string_view data) {
  const fs::path p = temp_dir() / name;
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(data.data(), static_cast<std::streamsize>(data.size()));
  return p.string();
}

// Binary data in either byte order.
struct Bytes {
  bool big_endian = false;
  std::string data;

  template <class T>
  Bytes& put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (big_endian) std::reverse(b, b + sizeof(T));
    data.append(b, sizeof(T));
    return *this;
  }
  Bytes& text(std::string_view s) {
    data += s;
    return *this;
  }
};

// Reads `path` expecting exception E whose one-line message names the path and contains
// `fragment`.
template <class E = InvalidInput>
void expect_error(const std::string& path, const std::string& fragment,
                  const ScanReadOptions& options = {}) {
  SCOPED_TRACE(path);
  try {
    read_scan(path, options);
    ADD_FAILURE() << "no exception; expected one containing '" << fragment << "'";
  } catch (const E& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

// The float nearest to x. Through a volatile: this file gets CGAL's -frounding-math, and with
// it GCC 12's SLP vectorizer drops the double -> float -> double round trip of two adjacent
// constants (x and y came back as 0.1 and 0.2 at -O2, right at -O1 or -fno-tree-slp-vectorize).
double f32(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}

// ------------------------------------------------------------------------------------ PLY

TEST(ScanIo, PlyAsciiPointsWithNormalsAndUv) {
  const std::string path = write("uv.ply", R"(ply
format ascii 1.0
comment made by scan_io_test
element vertex 3
property double x
property double y
property double z
property float nx
property float ny
property float nz
property double u
property double v
end_header
0.1 -2.5 3e-3 0 0 2 0.25 0.75
1 2 3 3 0 4 1e-7 -0.5
-1.5 0 1e20 0 -1 0 0 1
)");
  const Scan s = read_scan(path);
  EXPECT_EQ(s.source, path);
  ASSERT_EQ(s.positions.size(), 3u);
  EXPECT_EQ(s.positions[0], Point3(0.1, -2.5, 3e-3));
  EXPECT_EQ(s.positions[1], Point3(1, 2, 3));
  EXPECT_EQ(s.positions[2], Point3(-1.5, 0, 1e20));
  ASSERT_TRUE(s.has_normals());
  EXPECT_EQ(s.normals[0], Vector3(0, 0, 1));
  EXPECT_EQ(s.normals[1], Vector3(0.6, 0, 0.8));
  EXPECT_EQ(s.normals[2], Vector3(0, -1, 0));
  ASSERT_TRUE(s.has_uv());
  EXPECT_EQ(s.uv[0], Point2(0.25, 0.75));
  EXPECT_EQ(s.uv[1], Point2(1e-7, -0.5));
  EXPECT_EQ(s.uv[2], Point2(0, 1));
  EXPECT_FALSE(s.has_faces());
}

TEST(ScanIo, PlyAsciiFacesAreFanTriangulatedAndDegenerateOnesDropped) {
  const std::string path = write("faces.PLY", R"(ply
format ascii 1.0
element vertex 5
property float x
property float y
property float z
element face 3
property list uchar int vertex_indices
end_header
0 0 0
1 0 0
1 1 0
0 1 0
0.1 0.2 0.3
4 0 1 2 3
3 0 0 1
3 1 4 2
)");
  const Scan s = read_scan(path);
  ASSERT_EQ(s.positions.size(), 5u);
  // Float properties are read as float.
  EXPECT_EQ(s.positions[4], Point3(f32(0.1), f32(0.2), f32(0.3)));
  EXPECT_FALSE(s.has_normals());
  EXPECT_FALSE(s.has_uv());
  EXPECT_EQ(s.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {1, 4, 2}}));
}

TEST(ScanIo, PlyBinaryLittleEndianWithStParameters) {
  Bytes b;
  b.text(
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float "
      "y\nproperty float z\nproperty float s\nproperty float t\nproperty uchar red\nelement face "
      "1\nproperty list uchar uint vertex_index\nend_header\n");
  const float v[3][5] = {
      {0.5f, 1.25f, -3.75f, 0.125f, 0.875f}, {2, 4, 8, 1, 0}, {-1, -2, -4, 0, 1}};
  for (const auto& r : v) {
    for (float x : r) b.put(x);
    b.put<std::uint8_t>(7);
  }
  b.put<std::uint8_t>(3).put<std::uint32_t>(0).put<std::uint32_t>(1).put<std::uint32_t>(2);
  const Scan s = read_scan(write("st.ply", b.data));
  ASSERT_EQ(s.positions.size(), 3u);
  ASSERT_EQ(s.uv.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(s.positions[i], Point3(v[i][0], v[i][1], v[i][2]));
    EXPECT_EQ(s.uv[i], Point2(v[i][3], v[i][4]));
  }
  EXPECT_EQ(s.triangles, (std::vector<Tri>{{0, 1, 2}}));
}

std::string big_endian_ply() {
  // Doubles, texture_u/texture_v, extra properties and an extra element, and a face list
  // whose count is a 4-byte int (the reader looks at it before CGAL allocates).
  Bytes b;
  b.big_endian = true;
  b.text(
      "ply\r\nformat binary_big_endian 1.0\r\ncomment CRLF header\r\nelement vertex 4\r\n"
      "property double x\r\nproperty double y\r\nproperty double z\r\nproperty uchar flags\r\n"
      "property double texture_u\r\nproperty double texture_v\r\nelement edge 1\r\n"
      "property int vertex1\r\nproperty int vertex2\r\nelement face 2\r\n"
      "property uchar flags\r\nproperty list int int vertex_indices\r\nproperty float quality\r\n"
      "end_header\r\n");
  const double v[4][5] = {{0.1, 0.2, 0.3, 0.1, 0.7},
                          {1.1, 0.2, 0.3, 0.9, 0.7},
                          {1.1, 1.2, 0.3, 0.9, 0.3},
                          {0.1, 1.2, 0.3, 0.1, 0.3}};
  for (const auto& r : v) {
    b.put(r[0]).put(r[1]).put(r[2]).put<std::uint8_t>(1).put(r[3]).put(r[4]);
  }
  b.put<std::int32_t>(0).put<std::int32_t>(1);
  b.put<std::uint8_t>(0).put<std::int32_t>(4);
  for (int i : {0, 1, 2, 3}) b.put<std::int32_t>(i);
  b.put(1.5f);
  b.put<std::uint8_t>(0).put<std::int32_t>(3);
  for (int i : {2, 2, 3}) b.put<std::int32_t>(i);
  b.put(1.5f);
  return b.data;
}

TEST(ScanIo, PlyBinaryBigEndianWithTextureUvAndExtraElements) {
  const Scan s = read_scan(write("be.ply", big_endian_ply()));
  ASSERT_EQ(s.positions.size(), 4u);
  EXPECT_EQ(s.positions[0], Point3(0.1, 0.2, 0.3));
  EXPECT_EQ(s.positions[2], Point3(1.1, 1.2, 0.3));
  EXPECT_EQ(s.uv[1], Point2(0.9, 0.7));
  EXPECT_EQ(s.uv[3], Point2(0.1, 0.3));
  EXPECT_EQ(s.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
}

// A large binary file (2M points, 66 MB: the reader takes it item by item into the Scan's
// arrays, sized once from the header) gives back every value it was written with: mixed
// types, an extra property between the coordinates and the parameters, and faces after them.
TEST(ScanIo, PlyBinaryTwoMillionPointsComeBackExactly) {
  constexpr std::uint32_t kPoints = 2'000'000, kFaces = 1000;
  std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(kPoints) +
      "\nproperty double x\nproperty float y\nproperty float z\nproperty uchar intensity\n"
      "property double u\nproperty float v\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "element face " + std::to_string(kFaces) + "\nproperty list uchar int vertex_indices\nend_header\n";
  // Values from a fixed sequence; floats are exact in double, doubles are written as is.
  std::mt19937_64 rng(20);
  std::uniform_real_distribution<double> uni(-1000.0, 1000.0);
  std::vector<double> x(kPoints), u(kPoints);
  std::vector<float> y(kPoints), z(kPoints), v(kPoints);
  Bytes b;
  b.data.reserve(header.size() + kPoints * 41u + kFaces * 13u);
  b.text(header);
  for (std::uint32_t i = 0; i < kPoints; ++i) {
    x[i] = uni(rng), u[i] = uni(rng) * 1e-3;
    y[i] = static_cast<float>(uni(rng)), z[i] = static_cast<float>(uni(rng)), v[i] = static_cast<float>(uni(rng));
    b.put(x[i]).put(y[i]).put(z[i]).put<std::uint8_t>(static_cast<std::uint8_t>(i)).put(u[i]).put(v[i]);
    b.put(0.0f).put(0.6f).put(0.8f);
  }
  for (std::uint32_t f = 0; f < kFaces; ++f)
    b.put<std::uint8_t>(3)
        .put(static_cast<std::int32_t>(3 * f))
        .put(static_cast<std::int32_t>(3 * f + 1))
        .put(static_cast<std::int32_t>(kPoints - 1 - f));
  const std::string path = write("two_million.ply", b.data);
  b.data = std::string();
  const Scan s = read_scan(path);
  fs::remove(path);
  ASSERT_EQ(s.positions.size(), kPoints);
  ASSERT_EQ(s.uv.size(), kPoints);
  ASSERT_EQ(s.normals.size(), kPoints);
  ASSERT_EQ(s.triangles.size(), kFaces);
  std::size_t wrong = 0, first = kPoints;
  for (std::uint32_t i = 0; i < kPoints; ++i) {
    const bool ok = s.positions[i] == Point3(x[i], y[i], z[i]) && s.uv[i] == Point2(u[i], v[i]) &&
                    std::fabs(s.normals[i].y() - 0.6) < 1e-7 && std::fabs(s.normals[i].z() - 0.8) < 1e-7;
    if (!ok && wrong++ == 0) first = i;
  }
  EXPECT_EQ(wrong, 0u) << "first at point " << first;
  const int last = static_cast<int>(3 * (kFaces - 1));
  EXPECT_EQ(s.triangles.back(), (Tri{last, last + 1, static_cast<int>(kPoints - kFaces)}));
  // The arrays are sized from the header: no growth left over.
  EXPECT_EQ(s.positions.capacity(), kPoints);
  EXPECT_EQ(s.uv.capacity(), kPoints);
}

TEST(ScanErrors, PlyContentErrorsNameTheElement) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty "
      "double z\n";
  const std::string faces = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string pts = "0 0 0\n1 0 0\n0 1 0\n";
  expect_error(write("range.ply", head + faces + pts + "3 0 1 7\n"),
               "face 0: corner 2 refers to vertex 7");
  expect_error(write("negative.ply", head + faces + pts + "3 0 -1 2\n"),
               "face 0: corner 1 refers to vertex -1");
  expect_error(write("nan.ply", head + "end_header\n0 0 0\n1 nan 0\n0 1 0\n"),
               "vertex 1: property 'y'");
  expect_error(write("big.ply", head + "end_header\n0 0 0\n1 0 0\n0 1 1e31\n"),
               "vertex 2: z = 1e+31");
  expect_error(write("notnum.ply", head + "end_header\n0 0 0\n1 x 0\n0 1 0\n"),
               "vertex 1: property 'y'");
  expect_error(write("short.ply", head + "end_header\n10 10 10\n10 10 10\n10 10\n"),
               "vertex 2: the file ends early");
  expect_error(write("nofaces.ply", head + faces + "10 10 10\n10 10 10\n10 10 10\n"),
               "face 0: the file ends early");
  expect_error(
      write("short2.ply", head + "end_header\n0 0 0\n1 0 0\n0 1\n"),
      "line 3: the header announces 3 vertex items, but only 16 bytes follow the header and they need at "
      "least 18;");
  expect_error(write("nofaces2.ply", head + faces + pts),
               "but only 18 bytes follow the header and they need at least 20 with the elements before them;");
  expect_error(write("zero_normal.ply",
                     head + "property float nx\nproperty float ny\nproperty float nz\nend_header\n"
                            "0 0 0 0 0 1\n1 0 0 0 0 0\n0 1 0 0 0 1\n"),
               "vertex 1: the normal has zero length");
  expect_error(
      write("half_uv.ply", head + "property float u\nend_header\n0 0 0 0\n1 0 0 0\n0 1 0 0\n"),
      "'u' but not 'v'");
  expect_error(write("int64.ply", head + "property int64 id\nend_header\n"),
               ":line 7: property type 'int64'");
  expect_error(write("noxyz.ply",
                     "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n"),
               "need properties x, y and z");
  expect_error(write("novertex.ply", "ply\nformat ascii 1.0\nend_header\n"), "no vertex element");
  expect_error(write("empty_vertex.ply", head + "end_header\n"), "only 0 bytes follow the header");
  expect_error(write("zero.ply",
                     "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float "
                     "y\nproperty float z\nend_header\n"),
               "no points");
  expect_error(write("notply.ply", "PLY?\n"), "line 1: not a PLY file");
  expect_error(write("format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n"),
               "line 2: unknown PLY format");
  expect_error(write("noend.ply", head), "no end_header");
}

TEST(ScanErrors, PlyBinaryNanAndCorruptListCount) {
  Bytes b;
  b.text(
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list int int vertex_indices\nend_header\n");
  for (int i = 0; i < 9; ++i) b.put(i == 4 ? std::numeric_limits<float>::quiet_NaN() : 1.0f);
  b.put<std::int32_t>(3).put<std::int32_t>(0).put<std::int32_t>(1).put<std::int32_t>(2);
  expect_error(write("bin_nan.ply", b.data), "vertex 1: y is nan");

  Bytes c;
  c.text(
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list int int vertex_indices\nend_header\n");
  for (int i = 0; i < 9; ++i) c.put(1.0f * static_cast<float>(i));
  c.put<std::int32_t>(2000000000).put<std::int32_t>(0).put<std::int32_t>(1).put<std::int32_t>(2);
  expect_error(write("bin_count.ply", c.data),
               "face 0: list 'vertex_indices' claims 2000000000 entries");
}

TEST(ScanErrors, PlyHeaderCountsAreCheckedBeforeAllocating) {
  // 10^12 vertices: refused from the header, with the limit in the message.
  const std::string head =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  expect_error(write("huge.ply", head + std::string(24, '\0')),
               "announces 1000000000000 points; the limit is 50000000");
  ScanReadOptions small;
  small.max_points = 2;
  expect_error(write("three.ply",
                     "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                     "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n"),
               "the limit is 2", small);
  // Within the limit but more than the file holds: refused as truncated, before reading.
  expect_error(write("truncated.ply",
                     "ply\nformat binary_little_endian 1.0\nelement vertex 40000000\n"
                     "property float x\nproperty float y\nproperty float z\nend_header\n" +
                         std::string(100, '\0')),
               "the file is truncated");
  // A huge count of an element we skip is refused the same way.
  expect_error(write("huge_other.ply",
                     "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                     "property float y\nproperty float z\nelement junk 1000000000000000\n"
                     "property uchar a\nend_header\n0 0 0\n1\n"),
               "the file is truncated");
}

// ------------------------------------------------------------------------------------ OBJ

TEST(ScanIo, ObjSeamGivesOnePointPerDistinctCorner) {
  const std::string path = write("seam.obj", R"(# a square whose corner 3 sits on a UV seam
mtllib missing.mtl
v 0 0 0
v 1 0 0
v 1 1 0.5
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vt 0.5 0.5
vn 0 0 2
vn 0 3 4
usemtl none
f 1/1/1 2/2/1 3/3/2
f 1/1/1 3/5/2 4/4/1
)");
  const Scan s = read_scan(path);
  ASSERT_EQ(s.positions.size(), 5u);
  EXPECT_EQ(s.positions,
            (std::vector<Point3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0.5}, {1, 1, 0.5}, {0, 1, 0}}));
  EXPECT_EQ(s.uv, (std::vector<Point2>{{0, 0}, {1, 0}, {1, 1}, {0.5, 0.5}, {0, 1}}));
  EXPECT_EQ(s.normals,
            (std::vector<Vector3>{{0, 0, 1}, {0, 0, 1}, {0, 0.6, 0.8}, {0, 0.6, 0.8}, {0, 0, 1}}));
  EXPECT_EQ(s.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 3, 4}}));
}

TEST(ScanIo, ObjUnusedVerticesBecomeBarePointsAndPolygonsAreFanned) {
  const std::string path = write("bare.obj",
                                 "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.25 0.5 2.5\n"
                                 "f 1 2 3 4\nf 1 1 2\nf -5 -3 -2\n");
  const Scan s = read_scan(path);
  EXPECT_EQ(s.positions,
            (std::vector<Point3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.25, 0.5, 2.5}}));
  EXPECT_FALSE(s.has_uv());
  EXPECT_FALSE(s.has_normals());
  // f 1 1 2 is dropped (repeated corner); relative indices are resolved.
  EXPECT_EQ(s.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {0, 2, 3}}));
}

TEST(ScanIo, ObjPointCloudTakesVtAndVnByOrder) {
  const Scan s =
      read_scan(write("cloud.obj", "v 0 0 0\nv 1 0 0\nvn 0 0 1\nvn 1 0 0\nvt 0.5 0.25\nvt 0 1\n"));
  EXPECT_EQ(s.positions, (std::vector<Point3>{{0, 0, 0}, {1, 0, 0}}));
  EXPECT_EQ(s.normals, (std::vector<Vector3>{{0, 0, 1}, {1, 0, 0}}));
  EXPECT_EQ(s.uv, (std::vector<Point2>{{0.5, 0.25}, {0, 1}}));
}

TEST(ScanErrors, ObjContentErrors) {
  const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n";
  expect_error(write("mixed.obj", v + "f 1/1 2/2 3/3\nf 1/1 2 3/3\n"),
               "face 2: corner 2 has no texture coordinate (vt)");
  expect_error(write("range.obj", v + "f 1 2 9\n"), "face 1: corner 3 refers to v 9");
  expect_error(write("vtrange.obj", v + "f 1/1 2/2 3/7\n"), "face 1: corner 3 refers to vt 7");
  expect_error(write("relative.obj", v + "f 1 2 -7\n"),
               "face 1: corner 3 refers to v before the first one");
  expect_error(write("zero.obj", v + "f 0 1 2\n"), "tinyobjloader could not read it");
  expect_error(write("nan.obj", "v 0 0 0\nv 1 nan 0\n"), "line 2: y is nan");
  expect_error(write("inf.obj", "v 0 0 0\nv 1 1e999 0\n"),
               "line 2: '1e999' is beyond the range of double");
  expect_error(write("word.obj", "v 0 0 0\nvt 1 x\n"), "line 2: 'x' is not a number");
  expect_error(write("big.obj", "v 0 0 -1e31\n"), "line 1: z = -1e+31");
  expect_error(write("twocoords.obj", "v 0 0\n"), "line 1: 'v' needs 3 numbers, found 2");
  expect_error(write("zeronormal.obj", "v 0 0 0\nvn 0 0 0\n"), "vn 1: the normal has zero length");
  expect_error(write("unused.obj", v + "v 5 5 5\nf 1/1 2/2 3/3\n"),
               "v 4: no face uses this vertex");
  expect_error(write("comments.obj", "# nothing\n\n"), "no points");
}

// ------------------------------------------------------------------------------------ OFF

TEST(ScanIo, OffPolygonSoup) {
  const Scan s = read_scan(write("soup.off",
                                 "OFF\n# a comment\n5 3 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0.25\n2 2 2\n"
                                 "4 0 1 2 3\n3 0 0 1\n3 1 4 2\n"));
  EXPECT_EQ(s.positions,
            (std::vector<Point3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.25}, {2, 2, 2}}));
  EXPECT_EQ(s.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {1, 4, 2}}));
  EXPECT_FALSE(s.has_normals());
  EXPECT_FALSE(s.has_uv());
}

TEST(ScanIo, OffWithNormals) {
  const Scan s = read_scan(
      write("normals.off", "NOFF\n3 1 0\n0 0 0 0 0 2\n1 0 0 0 3 4\n0 1 0 1 0 0\n3 0 1 2\n"));
  EXPECT_EQ(s.normals, (std::vector<Vector3>{{0, 0, 1}, {0, 0.6, 0.8}, {1, 0, 0}}));
  EXPECT_EQ(s.triangles, (std::vector<Tri>{{0, 1, 2}}));
}

TEST(ScanErrors, OffErrors) {
  expect_error(write("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n"),
               "face 0: corner 2 is vertex 9, not a whole number from 0 to 3 - 1");
  // Checked before CGAL's reader, which converts these to size_t (undefined behaviour).
  expect_error(write("edges.off", "OFF\n3 1 001920497493\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
               "line 1: the edge count 1920497493 is out of range");
  expect_error(write("negative_index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -2\n"),
               "face 0: corner 2 is vertex -2");
  expect_error(write("negative_count.off", "OFF\n3 1 0\n0 0 0\n# comment\n1 0 0\n0 1 0\n-100 1\n"),
               "face 0: the corner count -100 is not a whole number");
  expect_error(write("fractional.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n"),
               "face 0: corner 1 is vertex 1.5");
  expect_error(write("short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n"),
               "line 6: CGAL could not read");
  expect_error(write("truncated.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 1\n3 0 1 2\n"),
               "line 7: CGAL could not read");
  expect_error(write("inf.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1e400 0\n3 0 1 2\n"),
               "line 5: CGAL could not read");
  expect_error(write("big.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1e35 0\n3 0 1 2\n"),
               "vertex 2: y = 1e+35");
  expect_error(write("header.off", "OFX\n3 1 0\n"), "line 1: not a valid OFF header");
  expect_error(write("huge.off", "OFF\n1000000000000 1 0\n"), "line 1: not a valid OFF header");
  expect_error(write("negative.off", "OFF\n-3 1 0\n0 0 0\n"), "line 1: not a valid OFF header");
  expect_error(write("limit.off", "OFF\n2000000000 0 0\n"), "the limit is 50000000");
  expect_error(write("bytes.off", "OFF\n4000 0 0\n0 0 0\n"), "the file is truncated");
  expect_error(write("empty.off", "OFF\n0 0 0\n"), "no points");
  // Variants CGAL 5.5's soup reader gets wrong, and that tbs does not read itself, are refused.
  const std::string binary_off("OFF BINARY\n\0\0\0\3\0\0\0\1\0\0\0\0", 23);
  for (const std::string& v :
       {std::string("STOFF\n3 1 0\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n"),
        std::string("C4OFF\n3 1 0\n0 0 0 1 1\n1 0 0 1 1\n0 1 0 1 1\n3 0 1 2 1 1\n"), binary_off})
    expect_error(write("variant.off", v), "line 1: binary OFF and OFF with texture coordinates");
}

// COFF, as MeshLab and CGAL's demo data write it: every vertex line ends with a colour of 1, 3
// or 4 numbers (integers or fractions), faces may carry one too, comments and blank lines
// anywhere. tbs reads the positions (and CNOFF's normals) and skips the colours: the same scan
// as the plain OFF without them.
TEST(ScanIo, OffWithColoursReadsAsWithout) {
  const Scan plain = read_scan(write("plain.off",
                                     "OFF\n5 3 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0.25\n2 2 2\n"
                                     "4 0 1 2 3\n3 0 0 1\n3 1 4 2\n"));
  const Scan coloured = read_scan(write("coloured.off",
                                        "# exported\nCOFF\n5 3 0\n\n0 0 0 192 192 192 255\n"
                                        "1 0 0 0.9 0 0 # red\n1 1 0 7\n0 1 0.25 0 0 0.9\n"
                                        "2 2 2 1 2 3 4\n\n4 0 1 2 3 0.9 0 0\n3 0 0 1\n3 1 4 2 255 0 0 255\n"));
  EXPECT_EQ(coloured.positions, plain.positions);
  EXPECT_EQ(coloured.triangles, plain.triangles);
  EXPECT_EQ(coloured.degenerate_faces, plain.degenerate_faces);
  EXPECT_FALSE(coloured.has_normals());
  // Counts and data on one line after the keyword; normals before the colour.
  const Scan normals = read_scan(write(
      "cnoff.off", "CNOFF 3 1 0\n0 0 0 0 0 2 1 1 1\n1 0 0 0 3 4 1 1 1\n0 1 0 1 0 0 1 1 1\n3 0 1 2\n"));
  EXPECT_EQ(normals.normals, (std::vector<Vector3>{{0, 0, 1}, {0, 0.6, 0.8}, {1, 0, 0}}));
  EXPECT_EQ(normals.triangles, (std::vector<Tri>{{0, 1, 2}}));
}

TEST(ScanErrors, OffWithColoursErrors) {
  const std::string v3 = "0 0 0 1 1 1\n1 0 0 1 1 1\n0 1 0 1 1 1\n";
  expect_error(write("c_short_vertex.off", "COFF\n3 1 0\n0 0 0 1 1 1\n1 0\n0 1 0 1 1 1\n3 0 1 2\n"),
               "line 4: vertex 1 has 2 values; a COFF vertex is x y z and then its colour");
  expect_error(write("c_nan.off", "COFF\n3 1 0\n0 0 0 1 1 1\n1 nan 0 1 1 1\n0 1 0 1 1 1\n3 0 1 2\n"),
               "line 4: y is nan");
  expect_error(write("c_text.off", "COFF\n3 1 0\n0 0 0 1 1 1\n1 x 0 1 1 1\n0 1 0 1 1 1\n3 0 1 2\n"),
               "line 4: value 2 'x' is not a number");
  expect_error(write("c_range.off", "COFF\n3 1 0\n" + v3 + "3 0 1 9\n"),
               "face 0: corner 2 refers to vertex 9, but the vertices are numbered 0 to 3 - 1");
  expect_error(write("c_count.off", "COFF\n3 1 0\n" + v3 + "-3 0 1 2\n"),
               "line 6: face 0: the corner count '-3' is not a whole number");
  expect_error(write("c_few.off", "COFF\n3 1 0\n" + v3 + "4 0 1 2\n"),
               "line 6: face 0 announces 4 corners but gives 3");
  expect_error(write("c_fraction.off", "COFF\n3 1 0\n" + v3 + "3 0 1.5 2\n"),
               "line 6: face 0: corner 1 '1.5' is not a whole number");
  expect_error(write("c_truncated.off", "COFF\n4 1 0\n" + v3 + "3 0 1 2\n"),
               "face 0: the file ends before the 1 faces the header announces");
  expect_error(write("c_together.off", "COFF\n3 1 0 0 0 0 1 1 1\n1 0 0 1 1 1\n0 1 0 1 1 1\n3 0 1 2\n"),
               "line 2: the first vertex must start on the line after the counts");
}

// ------------------------------------------------------------------------------------ STL

const char* const kAsciiStl = R"(solid test
  facet normal 0 0 1
    outer loop
      vertex 0 0 0
      vertex 1 0 0
      vertex 1 1 0
    endloop
  endfacet
  facet normal 0 0 1
    outer loop
      vertex 0 0 0
      vertex 1 1 0
      vertex 0 1 0.5
    endloop
  endfacet
endsolid test
)";

std::string binary_stl() {
  Bytes b;
  b.text("solid header of a binary file");  // binary STLs often start like ASCII ones
  b.data.resize(80, ' ');
  b.put<std::uint32_t>(3);
  const float tris[3][9] = {
      {0, 0, 0, 1, 0, 0, 1, 1, 0}, {0, 0, 0, 1, 1, 0, 0, 1, 0.5f}, {0, 0, 0, 0, 0, 0, 1, 1, 0}};
  for (const auto& t : tris) {
    b.put(0.0f).put(0.0f).put(1.0f);
    for (float x : t) b.put(x);
    b.put<std::uint16_t>(0);
  }
  return b.data;
}

TEST(ScanIo, StlAsciiMergesCorners) {
  const Scan s = read_scan(write("ascii.stl", kAsciiStl));
  EXPECT_EQ(s.positions, (std::vector<Point3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5}}));
  EXPECT_EQ(s.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
}

TEST(ScanIo, StlBinaryMergesCornersAndDropsDegenerateTriangles) {
  const Scan s = read_scan(write("binary.StL", binary_stl()));
  EXPECT_EQ(s.positions, (std::vector<Point3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5}}));
  EXPECT_EQ(s.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
}

TEST(ScanErrors, StlErrors) {
  std::string bin = binary_stl();
  bin.resize(bin.size() - 10);
  expect_error(write("truncated.stl", bin),
               "announces 3 triangles, 234 bytes, but the file has 224");
  bin = binary_stl();
  std::memcpy(bin.data(), "binary ", 7);
  bin.resize(bin.size() - 10);
  expect_error(write("truncated2.stl", bin),
               "announces 3 triangles (234 bytes) but the file has 224 bytes");
  bin = binary_stl();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(bin.data() + 84 + 12 + 4, &nan, 4);  // triangle 0, corner 0, y
  expect_error(write("nan_bin.stl", bin), "facet 0: y is nan");
  const std::string ascii = kAsciiStl;
  expect_error(write("noend.stl", ascii.substr(0, ascii.find("endsolid"))),
               "no closing 'endsolid'");
  expect_error(write("fourvertices.stl",
                     "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                     "vertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid a\n"),
               "not a valid ASCII STL");
  expect_error(write("inf.stl",
                     "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 1e999\n"
                     "vertex 1 1 0\nendloop\nendfacet\nendsolid a\n"),
               "not a valid ASCII STL");
  expect_error(write("none.stl", "solid a\nendsolid a\n"), "no points");
  Bytes huge;
  huge.text("binary");
  huge.data.resize(80, ' ');
  huge.put<std::uint32_t>(200000000);
  expect_error(write("huge.stl", huge.data), "announces 200000000 triangles (10000000084 bytes)");
  // The limit: from the triangle count of a binary header (about two triangles per vertex),
  // then on the merged vertices.
  ScanReadOptions none;
  none.max_points = 0;
  expect_error(write("limit0.stl", binary_stl()),
               "byte 80: the header announces 3 triangles, about 1 points; the limit is 0", none);
  ScanReadOptions one;
  one.max_points = 1;
  expect_error(write("limit1.stl", binary_stl()), "the file has 4 points; the limit is 1", one);
}

// ------------------------------------------------------------------------------------ XYZ

TEST(ScanIo, XyzThreeColumns) {
  const Scan s = read_scan(write(
      "a.xyz", "# x y z\n0.1 0.2 0.3\n\n  \t\n1e3 -2 +3\n  # indented comment\n-0 5e-324 1e30"));
  EXPECT_EQ(s.positions,
            (std::vector<Point3>{{0.1, 0.2, 0.3}, {1e3, -2, 3}, {-0.0, 5e-324, 1e30}}));
  EXPECT_FALSE(s.has_uv());
  EXPECT_FALSE(s.has_normals());
  EXPECT_FALSE(s.has_faces());
}

TEST(ScanIo, XyzFiveColumnsCrlf) {
  const Scan s = read_scan(write("b.TXT", "0 0 0 0.5 0.25\r\n1 2 3 0.75 1\r\n"));
  EXPECT_EQ(s.positions, (std::vector<Point3>{{0, 0, 0}, {1, 2, 3}}));
  EXPECT_EQ(s.uv, (std::vector<Point2>{{0.5, 0.25}, {0.75, 1}}));
  EXPECT_FALSE(s.has_normals());
}

TEST(ScanIo, XyzSixColumns) {
  const Scan s = read_scan(write("c.xyz", "0 0 0 0 0 5\n1\t2\t3\t-3 4 0\n"));
  EXPECT_EQ(s.normals, (std::vector<Vector3>{{0, 0, 1}, {-0.6, 0.8, 0}}));
  EXPECT_FALSE(s.has_uv());
}

TEST(ScanIo, XyzEightColumns) {
  const Scan s = read_scan(write("d.xyz", "1 2 3 0.5 0.125 0 3 4\n"));
  EXPECT_EQ(s.positions, (std::vector<Point3>{{1, 2, 3}}));
  EXPECT_EQ(s.uv, (std::vector<Point2>{{0.5, 0.125}}));
  EXPECT_EQ(s.normals, (std::vector<Vector3>{{0, 0.6, 0.8}}));
}

TEST(ScanErrors, XyzErrors) {
  expect_error(write("cols.xyz", "1 2 3\n\n4 5\n"), "line 3: has 2 values but line 1 has 3");
  expect_error(write("four.xyz", "# c\n1 2 3 4\n"), "line 2: has 4 values; expected 3");
  expect_error(write("word.xyz", "1 2 x3\n"), "line 1: value 3 'x3' is not a number");
  expect_error(write("nan.xyz", "1 2 3\n1 nan 3\n"), "line 2: y is nan");
  expect_error(write("inf.xyz", "1 2 -inf\n"), "line 1: z is -inf");
  expect_error(write("big.xyz", "1e31 2 3\n"), "line 1: x = 1e+31 is larger than 1e30");
  expect_error(write("bigu.xyz", "1 2 3 4 1e300\n"), "line 1: v = 1e+300");
  expect_error(write("zeron.xyz", "1 2 3 0 0 0\n"), "line 1: the normal has zero length");
  expect_error(write("nul.xyz", std::string("1 2 3\n1 2\0 3\n", 12)),
               "line 2: contains a NUL byte");
  expect_error(write("long.xyz", std::string(100000, '1')), "line 1: longer than");
  expect_error(write("comments.xyz", "# only\n\n# comments\n"), "no points");
  ScanReadOptions small;
  small.max_points = 10;
  std::string eleven;
  for (int i = 0; i < 11; ++i) eleven += "1 2 3\n";
  expect_error(write("eleven.xyz", eleven),
               "line 11: the file has at least 11 points; the limit is 10", small);
  EXPECT_EQ(read_scan(write("ten.xyz", eleven.substr(6)), small).positions.size(), 10u);
}

// ------------------------------------------------------------------------- all formats

TEST(ScanErrors, FilesystemErrorsAreIoErrors) {
  expect_error<IoError>((temp_dir() / "missing.ply").string(), "cannot read the file");
  fs::create_directories(temp_dir() / "folder.xyz");
  expect_error<IoError>((temp_dir() / "folder.xyz").string(), "is a directory");
  EXPECT_THROW(read_scan((temp_dir() / "missing.obj").string()), IoError);
  if (::geteuid() != 0) {  // root reads anything
    const std::string path = write("locked.xyz", "1 2 3\n");
    fs::permissions(path, fs::perms::none);
    expect_error<IoError>(path, "cannot open the file");
    fs::permissions(path, fs::perms::owner_all);
  }
}

TEST(ScanErrors, EmptyFilesAndUnknownExtensions) {
  for (const char* name : {"e.ply", "e.obj", "e.off", "e.stl", "e.xyz", "e.txt"})
    expect_error(write(name, ""), "the file is empty");
  expect_error(write("scan.las", "1 2 3\n"),
               "unknown extension '.las'; supported scan formats are .ply, .obj");
  expect_error(write("noext", "1 2 3\n"), "no extension");
  EXPECT_THROW(read_scan(write("scan.pcd", "1 2 3\n")), InvalidInput);
}

// Every proper prefix of a file whose format announces its size must be refused; for the
// others (OBJ, XYZ) a prefix may be a valid smaller file, but no prefix may crash or hang.
void check_prefixes(const std::string& name, const std::string& data, std::size_t must_fail_below) {
  SCOPED_TRACE(name);
  for (std::size_t n = 1; n < data.size(); ++n) {
    const std::string path = write(name, data.substr(0, n));
    if (n < must_fail_below) {
      EXPECT_THROW(read_scan(path), InvalidInput) << "prefix of " << n << " bytes";
    } else {
      try {
        read_scan(path);
      } catch (const Error&) {
      }
    }
  }
}

TEST(ScanErrors, TruncatedFilesAreRefused) {
  check_prefixes("t_be.ply", big_endian_ply(), big_endian_ply().size());
  const std::string ascii_ply =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float "
      "z\n"
      "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
  check_prefixes("t_ascii.ply", ascii_ply, ascii_ply.size() - 1);  // all but the last newline
  const std::string off = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
  check_prefixes("t.off", off, off.size() - 1);
  check_prefixes("t_bin.stl", binary_stl(), binary_stl().size());
  const std::string stl = kAsciiStl;
  check_prefixes("t_ascii.stl", stl, stl.find("endsolid") + 8);
  check_prefixes(
      "t.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\n",
      0);
  check_prefixes("t.xyz", "0.5 0.25 1 0 0 1\n2 3 4 0 1 0\n", 0);
}

// Random byte changes must give a scan or a tbs::Error, never a crash, hang or other exception.
void check_mutations(const std::string& name, const std::string& data, unsigned seed) {
  SCOPED_TRACE(name);
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 300; ++trial) {
    std::string d = data;
    const int changes = 1 + static_cast<int>(rng() % 4);
    for (int i = 0; i < changes; ++i) {
      const std::size_t at = rng() % d.size();
      switch (rng() % 3) {
        case 0:
          d[at] = static_cast<char>(rng());
          break;
        case 1:
          d[at] = "0123456789-.e \n"[rng() % 15];
          break;
        default:
          d.erase(at, 1 + rng() % 4);
          break;
      }
      if (d.empty()) d = "x";
    }
    try {
      read_scan(write(name, d));
    } catch (const Error&) {
    }
  }
}

TEST(ScanErrors, CorruptedFilesNeverCrash) {
  check_mutations("m_be.ply", big_endian_ply(), 1);
  check_mutations("m_ascii.ply",
                  "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                  "property float z\nproperty float u\nproperty float v\nelement face 2\n"
                  "property list ushort int vertex_indices\nend_header\n"
                  "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n3 0 1 2\n4 0 2 3 1\n",
                  2);
  check_mutations("m.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", 3);
  check_mutations("m_bin.stl", binary_stl(), 4);
  check_mutations("m_ascii.stl", kAsciiStl, 5);
  check_mutations("m.obj",
                  "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 "
                  "3/3/1\nf -1/-1/-1 1/1/1 2/2/1\n",
                  6);
  check_mutations("m.xyz", "0.5 0.25 1 0 0 1\n2 3 4 0 1 0\n", 7);
}

// ----------------------------------------------------------------------------- normals

// z = f(x, y), a smooth surface with curvature of both signs.
double height(double x, double y) {
  return 0.2 * std::sin(2 * x) * std::cos(1.5 * y) + 0.1 * x * y;
}
Vector3 true_normal(double x, double y) {
  const double fx = 0.4 * std::cos(2 * x) * std::cos(1.5 * y) + 0.1 * y;
  const double fy = -0.3 * std::sin(2 * x) * std::sin(1.5 * y) + 0.1 * x;
  return Vector3(-fx, -fy, 1).normalized();
}

struct Sample {
  std::vector<Point3> positions;
  std::vector<Point2> xy;
  std::vector<Tri> triangles;  // counter-clockwise seen from +Z
};

Sample sample_surface(int n, unsigned seed) {
  Sample s;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  const double h = 2.0 / (n - 1);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const bool inner = i > 0 && j > 0 && i < n - 1 && j < n - 1;
      const double x = -1 + h * (i + (inner ? jitter(rng) : 0)),
                   y = -1 + h * (j + (inner ? jitter(rng) : 0));
      s.positions.emplace_back(x, y, height(x, y));
      s.xy.emplace_back(x, y);
    }
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i;
      s.triangles.push_back({a, a + 1, a + n + 1});
      s.triangles.push_back({a, a + n + 1, a + n});
    }
  return s;
}

double angle_deg(const Vector3& a, const Vector3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 /
         std::numbers::pi;
}

// Checks every normal against the true one, times `sign` (+1 up, -1 down).
void expect_normals(const Sample& s, const std::vector<Vector3>& normals, double sign) {
  ASSERT_EQ(normals.size(), s.positions.size());
  double worst = 0;
  for (std::size_t i = 0; i < normals.size(); ++i) {
    EXPECT_NEAR(normals[i].norm(), 1.0, 1e-12);
    worst = std::max(worst, angle_deg(normals[i], sign * true_normal(s.xy[i].x(), s.xy[i].y())));
  }
  EXPECT_LT(worst, 2.0);
}

TEST(NormalEstimation, UvOrientsAlongPuCrossPv) {
  const Sample s = sample_surface(40, 11);
  expect_normals(s, estimate_normals(s.positions, s.xy, {}), +1);
  std::vector<Point2> yx;
  for (const Point2& p : s.xy) yx.emplace_back(p.y(), p.x());
  expect_normals(s, estimate_normals(s.positions, yx, {}), -1);
}

TEST(NormalEstimation, UvWithTrianglesIgnoresWinding) {
  const Sample s = sample_surface(30, 12);
  std::vector<Tri> reversed = s.triangles;
  for (Tri& t : reversed) std::swap(t[1], t[2]);
  expect_normals(s, estimate_normals(s.positions, s.xy, s.triangles), +1);
  expect_normals(s, estimate_normals(s.positions, s.xy, reversed), +1);
  std::vector<Point2> yx;
  for (const Point2& p : s.xy) yx.emplace_back(p.y(), p.x());
  expect_normals(s, estimate_normals(s.positions, yx, reversed), -1);
}

TEST(NormalEstimation, WithoutUvTrianglesOrientByWinding) {
  const Sample s = sample_surface(30, 13);
  std::vector<Tri> reversed = s.triangles;
  for (Tri& t : reversed) std::swap(t[1], t[2]);
  expect_normals(s, estimate_normals(s.positions, {}, s.triangles), +1);
  expect_normals(s, estimate_normals(s.positions, {}, reversed), -1);
}

TEST(NormalEstimation, BarePointsOrientAlongThePcaAxis) {
  const Sample s = sample_surface(30, 14);
  expect_normals(s, estimate_normals(s.positions, {}, {}), +1);
  // Turned upside down the scan is still oriented toward +Z of its PCA frame.
  Sample flipped = s;
  for (Point3& p : flipped.positions) p = Point3(p.x(), -p.y(), -p.z());
  for (const Vector3& n : estimate_normals(flipped.positions, {}, {})) EXPECT_GT(n.z(), 0);
}

TEST(NormalEstimation, DuplicatedPositionsShareTheirNormal) {
  // A pole: one position repeated more often than k, with different parameters.
  Sample s = sample_surface(25, 15);
  const std::size_t pole = 12 * 25 + 12;
  for (int i = 0; i < 30; ++i) {
    s.positions.push_back(s.positions[pole]);
    s.xy.push_back(s.xy[pole]);
  }
  const std::vector<Vector3> n = estimate_normals(s.positions, s.xy, {});
  expect_normals(s, n, +1);
  for (std::size_t i = 25 * 25; i < n.size(); ++i) EXPECT_EQ(n[i], n[pole]);
}

TEST(NormalEstimation, SameResultForAnyThreadCount) {
  const Sample s = sample_surface(60, 16);
  std::vector<Vector3> one, many;
  tbb::task_arena(1).execute([&] { one = estimate_normals(s.positions, s.xy, {}, 24); });
  tbb::task_arena(2).execute([&] { many = estimate_normals(s.positions, s.xy, {}, 24); });
  ASSERT_EQ(one.size(), many.size());
  for (std::size_t i = 0; i < one.size(); ++i) ASSERT_EQ(one[i], many[i]) << i;
  // A progress callback (called every 2 s: not at all on this small sample) changes nothing.
  std::vector<double> fractions;
  const std::vector<Vector3> reported =
      estimate_normals(s.positions, s.xy, {}, 24, [&](double f) { fractions.push_back(f); });
  EXPECT_EQ(reported, one);
  for (double f : fractions) EXPECT_TRUE(f > 0 && f <= 1) << f;
}

TEST(NormalEstimation, ReadThenEstimate) {
  // The two halves together: a PLY read back gives the normals of the points it was made from.
  const Sample s = sample_surface(20, 17);
  std::string text =
      "ply\nformat ascii 1.0\nelement vertex " + std::to_string(s.positions.size()) +
      "\nproperty double x\nproperty double y\nproperty double z\nproperty double u\n"
      "property double v\nend_header\n";
  char buf[200];
  for (std::size_t i = 0; i < s.positions.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g %.17g %.17g\n", s.positions[i].x(),
                  s.positions[i].y(), s.positions[i].z(), s.xy[i].x(), s.xy[i].y());
    text += buf;
  }
  const Scan scan = read_scan(write("surface.ply", text));
  EXPECT_EQ(scan.positions, s.positions);
  expect_normals(s, estimate_normals(scan.positions, scan.uv, scan.triangles), +1);
}

TEST(NormalEstimation, MatchCgalJetEstimateNormalsToRounding) {
  // Points in random order and at random places (no ties between neighbour distances), so
  // that both searches find the same k neighbours, whatever order they visit the points in.
  // For k = 18 (what fits use), 24 and 40 the normals must be CGAL::jet_estimate_normals'
  // up to rounding and orientation.
  using K = CGAL::Simple_cartesian<double>;
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> coord(-1, 1);
  std::vector<Point3> positions;
  std::vector<std::pair<K::Point_3, K::Vector_3>> cgal;
  for (int i = 0; i < 3000; ++i) {
    const double x = coord(rng), y = coord(rng);
    positions.emplace_back(x, y, height(x, y));
    cgal.emplace_back(K::Point_3(x, y, height(x, y)), K::Vector_3(0, 0, 0));
  }
  for (const int k : {18, 24, 40}) {
    const std::vector<Vector3> ours = estimate_normals(positions, {}, {}, k);
    auto reference = cgal;
    CGAL::jet_estimate_normals<CGAL::Sequential_tag>(
        reference, static_cast<unsigned>(k - 1),  // CGAL's k leaves out the point itself
        CGAL::parameters::point_map(CGAL::First_of_pair_property_map<std::pair<K::Point_3, K::Vector_3>>())
            .normal_map(CGAL::Second_of_pair_property_map<std::pair<K::Point_3, K::Vector_3>>())
            .degree_fitting(2));
    double worst = 0;
    for (std::size_t i = 0; i < positions.size(); ++i) {
      const K::Vector_3& r = reference[i].second;
      const Vector3 ref = Vector3(r.x(), r.y(), r.z()).normalized();
      worst = std::max(worst, std::min((ours[i] - ref).norm(), (ours[i] + ref).norm()));
    }
    EXPECT_LT(worst, 1e-12) << "k = " << k;
  }
}

TEST(NormalEstimation, JetSolverGivesTheSvdSolutionAlsoWhenRankDeficient) {
  // The jet fit's solver (a complete orthogonal decomposition) against CGAL's Jacobi SVD, on
  // the k x 6 systems of a degree-2 jet: well-posed ones, and rank-deficient ones (the
  // neighbours on two lines x = const, so that 1, x and x^2 are dependent), where the
  // minimum-norm solution is the one both must give. A plain QR would fail the second.
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> coord(-1, 1);
  for (const bool deficient : {false, true})
    for (int trial = 0; trial < 20; ++trial) {
      const int k = 18;
      detail::JetSolver::Matrix m(k, 6);
      detail::JetSolver::Vector b(k), b_svd(k);
      for (int i = 0; i < k; ++i) {
        const double x = deficient ? (i % 2 ? 0.5 : -0.25) : coord(rng), y = coord(rng);
        const double row[6] = {1, x, y, x * x, x * y, y * y};
        for (int c = 0; c < 6; ++c) m.set(i, c, row[c]);
        const double z = 0.3 * x - 0.2 * y + 0.7 * x * y + 0.01 * coord(rng);
        b.set(i, z);
        b_svd.set(i, z);
      }
      const double condition = detail::JetSolver::solve(m, b);
      CGAL::Eigen_svd::solve(m, b_svd);
      EXPECT_TRUE(deficient ? condition > 0 : std::isfinite(condition) && condition >= 1) << condition;
      for (int c = 0; c < 6; ++c) EXPECT_NEAR(b(c), b_svd(c), 1e-12) << (deficient ? "rank-deficient, " : "") << "trial "
                                                                    << trial << ", coefficient " << c;
    }
}

TEST(NormalEstimation, InvalidInputs) {
  const Sample s = sample_surface(10, 18);
  EXPECT_THROW(estimate_normals(s.positions, s.xy, {}, 5), InvalidInput);
  EXPECT_THROW(estimate_normals(s.positions, std::span<const Point2>(s.xy).first(3), {}),
               InvalidInput);
  const std::vector<Tri> bad{{0, 1, 100}};
  EXPECT_THROW(estimate_normals(s.positions, {}, bad), InvalidInput);
  std::vector<Point3> nan = s.positions;
  nan[3].y() = std::nan("");
  EXPECT_THROW(estimate_normals(nan, {}, {}), InvalidInput);
  std::vector<Point3> line;
  for (int i = 0; i < 30; ++i) line.emplace_back(i, 2 * i, 0);
  EXPECT_THROW(estimate_normals(line, {}, {}), InvalidInput);
  const std::vector<Point3> few(40, Point3(1, 2, 3));
  EXPECT_THROW(estimate_normals(few, {}, {}), InvalidInput);
}

}  // namespace
}  // namespace tbs
