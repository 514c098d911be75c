#pragma once
// The surface forms of the converters as OpenCASCADE shells, with the topology they already
// know: shared vertices and edges, no sewing.

#include <tbs/cad_export.h>
#include <tbs/cad_patches.h>
#include <tbs/cad_regions.h>
#include <tbs/extract.h>

#include <TopoDS_Shape.hxx>

namespace tbs::detail {

struct ShellResult {
  TopoDS_Shape shell;  // a shell, or a compound of shells (parts that share no edge)
  size_t faces = 0;
  double max_edge_tolerance = 0;  // the largest measured edge gap, as written
};

// One face per region, trimmed by its loops.
ShellResult region_shell(const CadRegions& regions);

// Faces of triangular patches: three quads per patch, or one quad collapsed at corner 0.
ShellResult patch_shell(const CadPatches& patches, TriangleFaces faces);

// The exact pieces as patches with shared edges (pieces meet edge to edge, no T-junctions).
CadPatches patches_of(const Extraction& extraction);

}  // namespace tbs::detail
