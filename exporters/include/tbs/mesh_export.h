#pragma once
/// \file
/// glTF 2.0 export of a tessellation through tinygltf.

#include <tbs/tessellate.h>
#include <tbs/types.h>

#include <string>

namespace tbs {

struct GltfOptions {
  std::string generator = "tbs";  ///< The asset's generator string.
  std::string name = "surface";   ///< Mesh and node name.
};

struct MeshExportReport {
  size_t vertices = 0;  ///< Vertices written (copies along domain edges included).
  size_t faces = 0;
};

/// Writes the mesh as glTF 2.0: binary `.glb`, or `.gltf` with the buffer embedded (base64),
/// chosen by the extension. One triangle primitive with
/// - POSITION and NORMAL (float, unit normals; where the surface is singular the normal of the
///   faces around the vertex),
/// - TEXCOORD_0: the parameter normalised to the rectangle `domain` (u to the right, v up, so
///   that row 0 of an error map over the same rectangle is the top of the texture),
/// - _TRIANGLE_ID: the domain triangle of the vertex (float, exact up to 2^24).
/// Vertices on edges between domain triangles are written once per triangle (same position
/// bit for bit), so that every vertex has one triangle id.
/// The file is written atomically. \throw InvalidInput for an empty mesh or an extension that
/// is not .glb or .gltf; IoError if it cannot be written.
MeshExportReport write_gltf(const std::string& path, const Mesh& mesh, const Box2& domain,
                            const GltfOptions& options = {});

/// Writes the mesh's positions and faces as OBJ (ASCII, 17 digits) or binary PLY, chosen by the
/// extension (.obj, .ply), through CGAL's polygon-soup writers; shared vertices stay shared.
/// The file is written atomically. \throw InvalidInput for an empty mesh or another extension;
/// IoError if it cannot be written.
MeshExportReport write_mesh_soup(const std::string& path, const Mesh& mesh);

}  // namespace tbs
