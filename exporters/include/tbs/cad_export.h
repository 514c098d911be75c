#pragma once
/// \file
/// STEP and IGES export through OpenCASCADE: every Bezier patch becomes an exact B-spline
/// face, the faces are sewn into one shell, the shell must pass OCCT's BRepCheck_Analyzer,
/// and only then is the file written (atomically).

#include <tbs/types.h>

#include <span>
#include <functional>
#include <string>
#include <vector>

namespace tbs {

struct CadPatches;
struct Extraction;

/// Triangular Bezier patches of one degree: the input of the CAD writers.
struct TrianglePatchSet {
  int degree = 0;
  std::vector<Point3> control_points;  ///< beta_count(degree) per patch, beta order.
  /// Number of whole patches (control_points.size() / beta_count(degree)). Throws nothing.
  size_t size() const;
};
/// The compact CAD patches (the default export). Throws nothing but std::bad_alloc.
TrianglePatchSet patch_set(const CadPatches& patches);
/// The exact pieces (`--exact`). Throws nothing but std::bad_alloc.
TrianglePatchSet patch_set(const Extraction& extraction);

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
  /// Called with a line of text at each stage (making faces, sewing, in steps of 10 %,
  /// checking, translating, writing): large sets take minutes. Empty: silent. An exception
  /// it throws stops the export and passes through write_step()/write_iges(); nothing is
  /// written then.
  std::function<void(const std::string&)> progress;
  TriangleFaces faces = TriangleFaces::Quads;
  /// Distance within which patch edges are sewn together; 0 means 1e-7 of the model size.
  double sewing_tolerance = 0;
};

/// What a writer built.
struct CadExportReport {
  size_t faces = 0;        ///< B-spline faces written.
  size_t shells = 0;       ///< Shells after sewing (1 for a connected surface).
  size_t free_edges = 0;   ///< Edges with one face: the surface's boundary (and holes).
  double sewing_tolerance = 0;
  double seconds = 0;
};

/// Writes a STEP file (atomically).
/// \throw InvalidInput if options.units is not mm, cm, m, um, in or ft ("unitless" included),
///   the set has no patches or a degree below 1, or a control point is not finite;
///   Error (the base class) if OpenCASCADE cannot make a face, cannot translate the shape or
///   throws, or the sewn shape fails BRepCheck_Analyzer (nothing is written then; the
///   message starts with `path: `); IoError if the file cannot be written.
CadExportReport write_step(const std::string& path, const TrianglePatchSet& patches,
                           const CadExportOptions& options = {});

/// Writes an IGES 5.3 file in BRep mode (faces, shell). Throws as write_step().
CadExportReport write_iges(const std::string& path, const TrianglePatchSet& patches,
                           const CadExportOptions& options = {});

}  // namespace tbs
