#include <tbs/errors.h>
#include <tbs/io.h>
#include <tbs/mesh_export.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/PLY.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <sstream>

namespace tbs {

MeshExportReport write_mesh_soup(const std::string& path, const Mesh& mesh) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".obj" && ext != ".ply") throw InvalidInput(path + ": mesh files end in .obj or .ply");
  if (mesh.faces.empty()) throw InvalidInput(path + ": the mesh has no faces");
  using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
  std::vector<Point> points;
  points.reserve(mesh.positions.size());
  for (const Point3& p : mesh.positions) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::array<std::size_t, 3>> faces;
  faces.reserve(mesh.faces.size());
  for (const auto& f : mesh.faces)
    faces.push_back({static_cast<std::size_t>(f[0]), static_cast<std::size_t>(f[1]), static_cast<std::size_t>(f[2])});
  std::ostringstream out;
  bool ok = false;
  if (ext == ".obj") {
    ok = CGAL::IO::write_OBJ(out, points, faces, CGAL::parameters::stream_precision(17));
  } else {
    CGAL::IO::set_binary_mode(out);
    ok = CGAL::IO::write_PLY(out, points, faces);
  }
  if (!ok) throw IoError(path + ": CGAL could not write the mesh");
  write_file_atomic(path, out.str());
  return {mesh.positions.size(), mesh.faces.size()};
}

}  // namespace tbs
