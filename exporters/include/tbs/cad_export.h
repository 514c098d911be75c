#pragma once
/// \file
/// STEP and IGES export through OpenCASCADE. The shell is built directly from the topology the
/// converters know: one vertex per shared corner, one edge per shared curve with a curve on
/// every face it bounds, and tolerances measured on the geometry (no sewing). It must pass
/// OCCT's BRepCheck_Analyzer, and only then is the file written (atomically). Three surface
/// forms: region faces (make_cad_regions(), the default), triangle patches
/// (make_cad_patches()) and the exact pieces (extract_bezier()).

#include <tbs/types.h>

#include <cstdint>
#include <span>
#include <functional>
#include <string>
#include <vector>

namespace tbs {

struct CadPatches;
struct Extraction;

struct CadRegions;

enum class StepSchema { AP214, AP242 };

/// How a triangular patch becomes tensor-product B-spline faces.
enum class TriangleFaces {
  Quads,      ///< Three quads meeting at the centroid, none degenerate (the default).
  Collapsed,  ///< One quad with an edge collapsed to a corner.
};

struct CadExportOptions {
  /// Length unit of the coordinates, written into the file: mm, cm, m, um, in, ft. The
  /// coordinates are written as they are, in this unit.
  std::string units = "mm";
  /// The product (STEP PRODUCT and FILE_NAME, IGES sender). Written in ASCII, as both formats
  /// expect: every other character becomes '_'.
  std::string product_name = "tbs surface";
  /// Free text for the file header (STEP FILE_DESCRIPTION, IGES start section): e.g. the
  /// fit report. ASCII as product_name.
  std::string description;
  StepSchema schema = StepSchema::AP214;
  /// Called with a line of text at each stage (building the shell, checking, translating,
  /// writing). Empty: silent. An exception it throws stops the export and passes through
  /// write_step()/write_iges(); nothing is written then.
  std::function<void(const std::string&)> progress;
  /// Triangle patches and exact pieces: how a triangle becomes faces.
  TriangleFaces faces = TriangleFaces::Quads;
};

/// What a writer built.
struct CadExportReport {
  size_t faces = 0;        ///< B-spline faces written.
  size_t shells = 0;       ///< Shells (1 for a connected surface).
  size_t edges = 0;        ///< Edges of the shape (degenerate ones not counted).
  size_t free_edges = 0;   ///< Edges with one face: the surface's boundary (and holes).
  size_t free_loops = 0;   ///< Connected chains of free edges: 1 + holes for a sheet.
  /// A closed shell (no free edge) is written as a solid, oriented outward.
  bool solid = false;
  /// The solid's volume (model units cubed), 0 for a shell.
  double volume = 0;
  /// Largest edge tolerance written: the measured gap between an edge's curve and the
  /// faces it bounds (model units).
  double max_edge_tolerance = 0;
  double build_seconds = 0;      ///< Building the shell.
  double check_seconds = 0;      ///< BRepCheck_Analyzer.
  double volume_seconds = 0;     ///< Measuring a solid's volume.
  double translate_seconds = 0;  ///< OCCT's translation to STEP or IGES entities.
  double write_seconds = 0;      ///< Writing the file.
  double seconds = 0;            ///< All of it.
  uintmax_t file_bytes = 0;      ///< Size of the written file.
};

/// Writes region faces as a STEP file (atomically): an ADVANCED_FACE on a B_SPLINE_SURFACE
/// per region, bounded by edge loops.
/// \throw InvalidInput if options.units is not mm, cm, m, um, in or ft ("unitless" included),
///   there are no faces, or a pole or control point is not finite;
///   Error (the base class) if OpenCASCADE cannot translate the shape or throws, or the shape
///   fails BRepCheck_Analyzer (nothing is written then; the message starts with `path: `);
///   IoError if the file cannot be written.
CadExportReport write_step(const std::string& path, const CadRegions& regions,
                           const CadExportOptions& options = {});
/// Writes triangle patches as a STEP file (a face per quad, options.faces). Throws as above.
CadExportReport write_step(const std::string& path, const CadPatches& patches,
                           const CadExportOptions& options = {});
/// Writes the exact pieces as a STEP file (a face per quad, options.faces). Throws as above.
CadExportReport write_step(const std::string& path, const Extraction& pieces,
                           const CadExportOptions& options = {});

/// Writes an IGES 5.3 file in BRep mode (faces, shell). Throws as write_step().
CadExportReport write_iges(const std::string& path, const CadRegions& regions,
                           const CadExportOptions& options = {});
/// Writes triangle patches as IGES. Throws as write_step().
CadExportReport write_iges(const std::string& path, const CadPatches& patches,
                           const CadExportOptions& options = {});
/// Writes the exact pieces as IGES. Throws as write_step().
CadExportReport write_iges(const std::string& path, const Extraction& pieces,
                           const CadExportOptions& options = {});

}  // namespace tbs
