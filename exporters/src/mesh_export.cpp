#include <tbs/errors.h>
#include <tbs/io.h>
#include <tbs/error_map.h>
#include <tbs/mesh_export.h>

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <cmath>
#include <map>
#include <sstream>

namespace tbs {

namespace {

// Appends `data` to the buffer (4-byte aligned) and adds a view and an accessor for it.
template <class T>
int add_accessor(tinygltf::Model& m, const std::vector<T>& data, int component_type, int type, int count,
                 int target, std::vector<double> min = {}, std::vector<double> max = {}) {
  auto& buf = m.buffers[0].data;
  while (buf.size() % 4) buf.push_back(0);
  const size_t offset = buf.size();
  const size_t bytes = data.size() * sizeof(T);
  buf.resize(offset + bytes);
  std::memcpy(buf.data() + offset, data.data(), bytes);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = offset;
  view.byteLength = bytes;
  view.target = target;
  m.bufferViews.push_back(view);
  tinygltf::Accessor acc;
  acc.bufferView = static_cast<int>(m.bufferViews.size()) - 1;
  acc.componentType = component_type;
  acc.type = type;
  acc.count = static_cast<size_t>(count);
  acc.minValues = std::move(min);
  acc.maxValues = std::move(max);
  m.accessors.push_back(acc);
  return static_cast<int>(m.accessors.size()) - 1;
}

// 8-bit sRGB to the linear values glTF colours are.
float linear(uint8_t c) {
  const double x = c / 255.0;
  return static_cast<float>(x <= 0.04045 ? x / 12.92 : std::pow((x + 0.055) / 1.055, 2.4));
}

// A relative URI reference for a file name: RFC 3986 unreserved characters kept, all other
// bytes percent-encoded.
std::string uri_of(const std::string& name) {
  std::string out;
  for (unsigned char c : name) {
    if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') {
      out += static_cast<char>(c);
    } else {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%%%02X", c);
      out += buf;
    }
  }
  return out;
}

}  // namespace

MeshExportReport write_gltf(const std::string& path, const Mesh& mesh, const Box2& domain,
                            const GltfOptions& o) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".glb" && ext != ".gltf") throw InvalidInput(path + ": glTF files end in .glb or .gltf");
  if (mesh.faces.empty()) throw InvalidInput(path + ": the mesh has no faces");
  if (!o.vertex_values.empty() && o.vertex_values.size() != mesh.positions.size())
    throw InvalidInput(path + ": " + std::to_string(o.vertex_values.size()) + " colour values for " +
                       std::to_string(mesh.positions.size()) + " vertices");

  // One copy of a vertex per domain triangle that uses it.
  std::map<std::pair<int, int>, int> copy;
  std::vector<int> source;
  std::vector<float> triangle_id;
  std::vector<uint32_t> indices;
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (int v : mesh.faces[f]) {
      const auto [it, added] = copy.try_emplace({v, mesh.face_triangle[f]}, static_cast<int>(source.size()));
      if (added) {
        source.push_back(v);
        triangle_id.push_back(static_cast<float>(mesh.face_triangle[f]));
      }
      indices.push_back(static_cast<uint32_t>(it->second));
    }
  // Normals: the spline's; where it is singular, the area-weighted normal of the faces.
  std::vector<Vector3> face_normal_sum(mesh.positions.size(), Vector3::Zero());
  for (const auto& f : mesh.faces) {
    const Vector3 n = (mesh.positions[f[1]] - mesh.positions[f[0]]).cross(mesh.positions[f[2]] - mesh.positions[f[0]]);
    for (int v : f) face_normal_sum[v] += n;
  }
  const size_t nv = source.size();
  std::vector<float> pos(3 * nv), nrm(3 * nv), uv(2 * nv);
  std::vector<double> pmin(3, 1e300), pmax(3, -1e300), tmin(2, 1e300), tmax(2, -1e300), imin{1e300}, imax{-1e300};
  const double du = std::max(domain.max.x() - domain.min.x(), 1e-300), dv = std::max(domain.max.y() - domain.min.y(), 1e-300);
  for (size_t i = 0; i < nv; ++i) {
    const int v = source[i];
    Vector3 n = mesh.normals[v];
    if (!(n.norm() > 0.5)) n = face_normal_sum[v].norm() > 0 ? Vector3(face_normal_sum[v].normalized()) : Vector3(0, 0, 1);
    const float t[2] = {static_cast<float>((mesh.parameters[v].x() - domain.min.x()) / du),
                        static_cast<float>((domain.max.y() - mesh.parameters[v].y()) / dv)};
    for (int k = 0; k < 3; ++k) {
      pos[3 * i + k] = static_cast<float>(mesh.positions[v][k]);
      nrm[3 * i + k] = static_cast<float>(n[k]);
      pmin[k] = std::min(pmin[k], double(pos[3 * i + k]));
      pmax[k] = std::max(pmax[k], double(pos[3 * i + k]));
    }
    for (int k = 0; k < 2; ++k) {
      uv[2 * i + k] = t[k];
      tmin[k] = std::min(tmin[k], double(t[k]));
      tmax[k] = std::max(tmax[k], double(t[k]));
    }
    imin[0] = std::min(imin[0], double(triangle_id[i]));
    imax[0] = std::max(imax[0], double(triangle_id[i]));
  }

  tinygltf::Model m;
  m.asset.version = "2.0";
  m.asset.generator = valid_utf8(o.generator);
  m.buffers.resize(1);
  tinygltf::Primitive prim;
  tinygltf::Value color_extras;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  const double count = static_cast<double>(nv);
  prim.indices = add_accessor(m, indices, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR,
                              static_cast<int>(indices.size()), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER,
                              {0.0}, {count - 1});
  prim.attributes["POSITION"] = add_accessor(m, pos, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3,
                                             static_cast<int>(nv), TINYGLTF_TARGET_ARRAY_BUFFER, pmin, pmax);
  prim.attributes["NORMAL"] = add_accessor(m, nrm, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3,
                                           static_cast<int>(nv), TINYGLTF_TARGET_ARRAY_BUFFER);
  prim.attributes["TEXCOORD_0"] = add_accessor(m, uv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2,
                                               static_cast<int>(nv), TINYGLTF_TARGET_ARRAY_BUFFER, tmin, tmax);
  if (!o.vertex_values.empty()) {
    double top = o.color_scale_max;
    if (!(top > 0)) {
      top = 0;
      for (float v : o.vertex_values)
        if (std::isfinite(v)) top = std::max(top, double(v));
      if (!(top > 0)) top = 1;
    }
    std::vector<float> rgb(3 * nv);
    std::vector<double> cmin(3, 1e300), cmax(3, -1e300);
    for (size_t i = 0; i < nv; ++i) {
      const float v = o.vertex_values[source[i]];
      const auto c = std::isfinite(v) ? heat_colour(v / top) : std::array<uint8_t, 3>{160, 160, 160};
      for (int k = 0; k < 3; ++k) {
        rgb[3 * i + k] = linear(c[k]);
        cmin[k] = std::min(cmin[k], double(rgb[3 * i + k]));
        cmax[k] = std::max(cmax[k], double(rgb[3 * i + k]));
      }
    }
    prim.attributes["COLOR_0"] = add_accessor(m, rgb, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3,
                                              static_cast<int>(nv), TINYGLTF_TARGET_ARRAY_BUFFER, cmin, cmax);
    tinygltf::Value::Object scale;
    scale["attribute"] = tinygltf::Value(std::string("COLOR_0"));
    scale["quantity"] = tinygltf::Value(o.color_quantity);
    scale["units"] = tinygltf::Value(o.units);
    scale["blue"] = tinygltf::Value(0.0);
    scale["red"] = tinygltf::Value(top);
    tinygltf::Value::Object extras;
    extras["tbs_color_scale"] = tinygltf::Value(scale);
    color_extras = tinygltf::Value(extras);
  }
  prim.attributes["_TRIANGLE_ID"] = add_accessor(m, triangle_id, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR,
                                                 static_cast<int>(nv), TINYGLTF_TARGET_ARRAY_BUFFER, imin, imax);
  // indices are an index list: exact min/max over the data.
  {
    uint32_t lo = UINT32_MAX, hi = 0;
    for (uint32_t i : indices) lo = std::min(lo, i), hi = std::max(hi, i);
    m.accessors[prim.indices].minValues = {double(lo)};
    m.accessors[prim.indices].maxValues = {double(hi)};
  }
  tinygltf::Mesh gm;
  gm.name = valid_utf8(o.name);
  gm.extras = color_extras;
  gm.primitives.push_back(prim);
  m.meshes.push_back(gm);
  tinygltf::Node node;
  node.mesh = 0;
  node.name = valid_utf8(o.name);
  m.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes.push_back(0);
  m.scenes.push_back(scene);
  m.defaultScene = 0;
  // A plain material, so viewers shade it the same way.
  tinygltf::Material mat;
  mat.name = "tbs surface";
  mat.doubleSided = true;
  mat.pbrMetallicRoughness.metallicFactor = 0.0;
  mat.pbrMetallicRoughness.roughnessFactor = 0.6;
  m.materials.push_back(mat);
  m.meshes[0].primitives[0].material = 0;

  std::ostringstream out;
  tinygltf::TinyGLTF writer;
  if (ext == ".glb") {
    if (!writer.WriteGltfSceneToStream(&m, out, false, true))
      throw IoError(path + ": tinygltf could not serialise the mesh");
    write_file_atomic(path, out.str());
    return {nv, mesh.faces.size()};
  }
  // .gltf: the buffer goes to NAME.bin. tinygltf's stream writer embeds buffers, so the model
  // is serialised without its data and the buffer entry pointed at the .bin afterwards.
  const std::filesystem::path bin = std::filesystem::path(path).replace_extension(".bin");
  std::vector<unsigned char> data;
  data.swap(m.buffers[0].data);
  if (!writer.WriteGltfSceneToStream(&m, out, true, false))
    throw IoError(path + ": tinygltf could not serialise the mesh");
  nlohmann::ordered_json doc = nlohmann::ordered_json::parse(out.str());
  doc["buffers"][0] = {{"byteLength", data.size()}, {"uri", uri_of(bin.filename().string())}};
  const std::string text = doc.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
  AtomicOutput bin_out(bin.string()), gltf_out(path);
  bin_out.write(std::string_view(reinterpret_cast<const char*>(data.data()), data.size()));
  gltf_out.write(text);
  bin_out.commit();
  gltf_out.commit();
  return {nv, mesh.faces.size()};
}

}  // namespace tbs
