// glTF written by tbs read back with tinygltf: the tessellation's positions, normals,
// parameters and triangle ids, with correct accessor bounds.
#include <tbs/error_map.h>
#include <tbs/errors.h>
#include <tbs/io.h>
#include <tbs/mesh_export.h>
#include <tbs/scan.h>
#include <tbs/tessellate.h>

#include "random_spline.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <filesystem>
#include <fstream>
#include <map>

namespace tbs {
namespace {

namespace fs = std::filesystem;

template <class T>
std::vector<T> read_accessor(const tinygltf::Model& m, int index, int components) {
  const auto& a = m.accessors[index];
  const auto& v = m.bufferViews[a.bufferView];
  const auto& b = m.buffers[v.buffer];
  std::vector<T> out(a.count * components);
  std::memcpy(out.data(), b.data.data() + v.byteOffset + a.byteOffset, out.size() * sizeof(T));
  return out;
}

class Gltf : public ::testing::TestWithParam<std::string> {};

TEST_P(Gltf, ReadsBackAsTheTessellation) {
  test::GridOptions o;
  o.nx = o.ny = 4;
  o.hole = true;
  o.feature_column = 1;
  const Spline s = test::random_spline(3, o, 81);
  const Mesh mesh = tessellate(s, {.resolution = 3});
  const fs::path file = fs::temp_directory_path() / ("tbs_gltf_test_" + std::to_string(::getpid()) + GetParam());
  const MeshExportReport r = write_gltf(file, mesh, s.domain().bounding_box(), {.generator = "tbs test", .name = "part"});

  tinygltf::TinyGLTF loader;
  tinygltf::Model m;
  std::string err, warn;
  const bool ok = GetParam() == ".glb" ? loader.LoadBinaryFromFile(&m, &err, &warn, file)
                                       : loader.LoadASCIIFromFile(&m, &err, &warn, file);
  fs::path bin = file;
  bin.replace_extension(".bin");
  const bool has_bin = fs::exists(bin);
  fs::remove(file);
  fs::remove(bin);
  ASSERT_TRUE(ok) << err;
  // .glb holds its buffer; .gltf points to NAME.bin beside it.
  EXPECT_EQ(has_bin, GetParam() == ".gltf");
  ASSERT_EQ(m.buffers.size(), 1u);
  EXPECT_EQ(m.buffers[0].uri, GetParam() == ".gltf" ? bin.filename().string() : std::string());
  EXPECT_EQ(m.meshes.at(0).primitives.at(0).attributes.count("COLOR_0"), 0u);
  EXPECT_TRUE(warn.empty()) << warn;
  EXPECT_EQ(m.asset.generator, "tbs test");
  ASSERT_EQ(m.meshes.size(), 1u);
  const auto& prim = m.meshes[0].primitives[0];
  const auto pos = read_accessor<float>(m, prim.attributes.at("POSITION"), 3);
  const auto nrm = read_accessor<float>(m, prim.attributes.at("NORMAL"), 3);
  const auto uv = read_accessor<float>(m, prim.attributes.at("TEXCOORD_0"), 2);
  const auto ids = read_accessor<float>(m, prim.attributes.at("_TRIANGLE_ID"), 1);
  const auto idx = read_accessor<uint32_t>(m, prim.indices, 1);
  ASSERT_EQ(pos.size() / 3, r.vertices);
  ASSERT_EQ(idx.size(), 3 * mesh.faces.size());
  // Face by face, the corners are the tessellation's vertices (as floats), and every corner
  // carries the face's domain triangle.
  const Box2 box = s.domain().bounding_box();
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = idx[3 * f + k];
      const int v = mesh.faces[f][k];
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(pos[3 * i + c], static_cast<float>(mesh.positions[v][c]));
        ASSERT_EQ(nrm[3 * i + c], static_cast<float>(mesh.normals[v][c]));
      }
      ASSERT_EQ(ids[i], static_cast<float>(mesh.face_triangle[f]));
      ASSERT_NEAR(uv[2 * i], (mesh.parameters[v].x() - box.min.x()) / (box.max.x() - box.min.x()), 1e-6);
      ASSERT_NEAR(uv[2 * i + 1], (box.max.y() - mesh.parameters[v].y()) / (box.max.y() - box.min.y()), 1e-6);
    }
  // Accessor bounds are the exact extremes of the data.
  const auto& pa = m.accessors[prim.attributes.at("POSITION")];
  for (int c = 0; c < 3; ++c) {
    float lo = 1e30f, hi = -1e30f;
    for (size_t i = c; i < pos.size(); i += 3) lo = std::min(lo, pos[i]), hi = std::max(hi, pos[i]);
    EXPECT_EQ(pa.minValues[c], lo);
    EXPECT_EQ(pa.maxValues[c], hi);
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, Gltf, ::testing::Values(".glb", ".gltf"),
                         [](const auto& i) { return i.param == ".glb" ? "Glb" : "Gltf"; });

TEST(Gltf, ColoursAreTheHeatScaleOfTheVertexValues) {
  const Spline s = test::random_spline(2, test::GridOptions{}, 84);
  const Mesh mesh = tessellate(s, {.resolution = 2});
  GltfOptions o;
  o.units = "mm";
  o.color_scale_max = 2.0;
  for (size_t v = 0; v < mesh.positions.size(); ++v)
    o.vertex_values.push_back(v == 0 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(v % 7) * 0.5f);
  // A name that needs percent-encoding in the buffer's URI.
  const fs::path file = fs::temp_directory_path() / ("tbs gltf #" + std::to_string(::getpid()) + ".gltf");
  fs::path bin = file;
  bin.replace_extension(".bin");
  write_gltf(file, mesh, s.domain().bounding_box(), o);
  tinygltf::TinyGLTF loader;
  tinygltf::Model m;
  std::string err, warn;
  const bool ok = loader.LoadASCIIFromFile(&m, &err, &warn, file);
  const std::string text = read_file(file.string());
  fs::remove(file);
  fs::remove(bin);
  ASSERT_TRUE(ok) << err;
  EXPECT_NE(text.find("\"uri\": \"tbs%20gltf%20%23"), std::string::npos);
  const auto& prim = m.meshes[0].primitives[0];
  ASSERT_EQ(prim.attributes.count("COLOR_0"), 1u);
  const auto rgb = read_accessor<float>(m, prim.attributes.at("COLOR_0"), 3);
  const auto idx = read_accessor<uint32_t>(m, prim.indices, 1);
  auto linear = [](uint8_t c) {
    const double x = c / 255.0;
    return x <= 0.04045 ? x / 12.92 : std::pow((x + 0.055) / 1.055, 2.4);
  };
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = idx[3 * f + k];
      const int v = mesh.faces[f][k];
      const auto c = v == 0 ? std::array<uint8_t, 3>{160, 160, 160} : heat_colour(o.vertex_values[v] / 2.0);
      for (int j = 0; j < 3; ++j) ASSERT_NEAR(rgb[3 * i + j], linear(c[j]), 1e-6) << "vertex " << v;
    }
  // Value 3 (v % 7 == 6) is above the scale: red, the scale's top.
  const auto red = heat_colour(1.0);
  EXPECT_EQ(heat_colour(1.5), red);
  const auto& scale = m.meshes[0].extras.Get("tbs_color_scale");
  ASSERT_TRUE(scale.IsObject());
  EXPECT_EQ(scale.Get("red").GetNumberAsDouble(), 2.0);
  EXPECT_EQ(scale.Get("units").Get<std::string>(), "mm");
  EXPECT_EQ(scale.Get("attribute").Get<std::string>(), "COLOR_0");

  o.vertex_values.pop_back();
  EXPECT_THROW(write_gltf(file, mesh, s.domain().bounding_box(), o), InvalidInput);
  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(fs::exists(bin));
}

TEST(MeshSoup, ObjAndPlyReadBackWithTheSamePointsAndFaces) {
  const Spline s = test::random_spline(3, test::GridOptions{}, 83);
  const Mesh mesh = tessellate(s, {.resolution = 3});
  for (const std::string ext : {".obj", ".ply"}) {
    const fs::path file = fs::temp_directory_path() / ("tbs_soup_test_" + std::to_string(::getpid()) + ext);
    const MeshExportReport r = write_mesh_soup(file, mesh);
    EXPECT_EQ(r.vertices, mesh.positions.size());
    const Scan back = read_scan(file);
    fs::remove(file);
    ASSERT_EQ(back.triangles.size(), mesh.faces.size()) << ext;
    // Binary PLY round-trips doubles exactly; OBJ is text with 17 significant digits, which
    // tinyobjloader's own number parser reads back to within a few units in the last place.
    const double slack = ext == ".ply" ? 0.0 : 1e-15;
    for (size_t f = 0; f < mesh.faces.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const Point3 &a = back.positions[back.triangles[f][k]], &b = mesh.positions[mesh.faces[f][k]];
        ASSERT_LE((a - b).cwiseAbs().maxCoeff(), slack * (1 + b.cwiseAbs().maxCoeff())) << ext << " face " << f;
      }
  }
  EXPECT_THROW(write_mesh_soup((fs::temp_directory_path() / "x.stl").string(), mesh), InvalidInput);
}

TEST(Gltf, RefusesWhatItCannotWrite) {
  const Spline s = test::random_spline(2, test::GridOptions{}, 82);
  const Mesh mesh = tessellate(s, {.resolution = 2});
  const fs::path dir = fs::temp_directory_path();
  EXPECT_THROW(write_gltf((dir / "x.obj").string(), mesh, s.domain().bounding_box()), InvalidInput);
  EXPECT_THROW(write_gltf((dir / "x.glb").string(), Mesh{}, s.domain().bounding_box()), InvalidInput);
  EXPECT_THROW(write_gltf((dir / "no_such_dir" / "x.glb").string(), mesh, s.domain().bounding_box()), IoError);
  EXPECT_FALSE(fs::exists(dir / "no_such_dir"));
}

}  // namespace
}  // namespace tbs
