#pragma once
/// \file
/// glTF 2.0 export of a tessellation through tinygltf.

#include <tbs/tessellate.h>
#include <tbs/types.h>

#include <string>
#include <vector>

namespace tbs {

struct GltfOptions {
  std::string generator = "tbs";  ///< The asset's generator string.
  std::string name = "surface";   ///< Mesh and node name.
  /// Optional values per mesh vertex (for example error_at() at each vertex's parameter),
  /// written as COLOR_0 on the heat_colour() scale from 0 to `color_scale_max`; NaN values are
  /// grey. Empty: no COLOR_0. \pre empty or one value per mesh vertex.
  std::vector<float> vertex_values = {};
  double color_scale_max = 0;     ///< The value drawn red; 0: the largest value.
  std::string color_quantity = "error";  ///< What the values are, for the mesh's extras.
  std::string units = "unitless";        ///< Their unit, for the mesh's extras.
};

struct MeshExportReport {
  size_t vertices = 0;  ///< Vertices written (copies along domain edges included).
  size_t faces = 0;
};

/// Writes the mesh as glTF 2.0, chosen by the extension: binary `.glb`, or `.gltf` (JSON) with
/// its buffer in a `.bin` file beside it (same name, extension .bin). One triangle primitive
/// with
/// - POSITION and NORMAL (float, unit normals; where the surface is singular the normal of the
///   faces around the vertex),
/// - COLOR_0 (float RGB, linear) when options.vertex_values are given; the mesh's extras
///   `tbs_color_scale` then hold the quantity, units and the values drawn blue (0) and red,
/// - TEXCOORD_0: the parameter normalised to the rectangle `domain` (u to the right, v up, so
///   that row 0 of an error map over the same rectangle is the top of the texture),
/// - _TRIANGLE_ID: the domain triangle of the vertex (float, exact up to 2^24).
/// Vertices on edges between domain triangles are written once per triangle (same position
/// bit for bit), so that every vertex has one triangle id.
/// Files are written atomically; for `.gltf` the `.bin` is renamed into place first, then the
/// `.gltf`. \throw InvalidInput for a mesh without faces, an extension that is not .glb or
/// .gltf, or vertex values of the wrong count; IoError if the model cannot be serialised or a
/// file cannot be written. nlohmann::json::type_error (not a tbs exception) escapes if a
/// string option (generator, name, color_quantity, units) is not valid UTF-8.
MeshExportReport write_gltf(const std::string& path, const Mesh& mesh, const Box2& domain,
                            const GltfOptions& options = {});

/// Writes the mesh's positions and faces as OBJ (ASCII, 17 digits) or binary PLY, chosen by the
/// extension (.obj, .ply), through CGAL's polygon-soup writers; shared vertices stay shared.
/// The file is written atomically. \throw InvalidInput for a mesh without faces or another
/// extension; IoError if CGAL cannot write the mesh or the file cannot be written.
MeshExportReport write_mesh_soup(const std::string& path, const Mesh& mesh);

}  // namespace tbs
