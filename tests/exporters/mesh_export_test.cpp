// glTF written by tbs read back with tinygltf: the tessellation's positions, normals,
// parameters and triangle ids, with correct accessor bounds.
#include <tbs/errors.h>
#include <tbs/mesh_export.h>
#include <tbs/scan.h>
#include <tbs/tessellate.h>

#include "random_spline.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cstring>
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
  fs::remove(file);
  ASSERT_TRUE(ok) << err;
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
