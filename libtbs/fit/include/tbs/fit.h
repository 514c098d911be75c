#pragma once
/// \file
/// Fitting one DMS spline to scanned points with parameters (He & Qin, section 4): initial
/// domain, control points by sparse least squares, free knots, adaptive refinement.

#include <tbs/scan.h>
#include <tbs/spline.h>

#include <functional>
#include <stop_token>
#include <string>
#include <vector>

namespace tbs {

/// Progress of a long stage, reported to FitOptions::progress.
struct FitProgress {
  std::string stage;    ///< "normals", "domain", "solve", "knots", "error", "refine"
  std::string message;  ///< one line for a person, e.g. "iteration 3: 1,204 triangles"
  double fraction = 0;  ///< of the stage, in [0, 1]
};

struct FitOptions {
  int degree = 3;
  /// Target maximum error, relative to the largest side of the points' bounding box
  /// (1e-3 = 0.1 %), as in the paper. Ignored when tolerance_abs > 0.
  double tolerance = 1e-3;
  /// Target maximum error in model units; 0 means use `tolerance`.
  double tolerance_abs = 0;
  /// Domain triangles of the initial triangulation; 0 chooses points / 200, within [32, 4000].
  int triangles = 0;
  /// Weight of the normal fairness term, dimensionless: each point's term (n.F_u)^2 + (n.F_v)^2
  /// is multiplied by the squared longest edge of its domain triangle, which makes it a squared
  /// length like the distance term, for any parameter scale, and keeps it from growing stronger
  /// as refinement shrinks triangles.
  double fairness = 1e-3;
  /// Weight of the bending (thin-plate) term, dimensionless: the integral of
  /// |F_uu|^2 + 2 |F_uv|^2 + |F_vv|^2 over each domain triangle, times the mean point density
  /// (points per unit parameter area) and the fourth power of the triangle's longest edge, and
  /// by (beta_count(n) / points in it)^2 where a triangle holds more points than that. It
  /// decides the surface between points, where the point terms do not reach: without it a
  /// sparse scan (a mesh's vertices) can be met at its points by a surface that swings far off
  /// between them. 0 turns it off.
  double bending = 1e-4;
  /// Weight of the third-order smoothness term, dimensionless: the integral of
  /// |F_uuu|^2 + 3 |F_uuv|^2 + 3 |F_uvv|^2 + |F_vvv|^2 over each domain triangle, times the mean
  /// point density and the sixth power of the triangle's longest edge, and by
  /// (beta_count(n) / points in it)^2 where a triangle holds more points than that. It vanishes
  /// on quadratics, so unlike bending it does not flatten a curved surface: between sparse
  /// points it keeps the curvature the points show instead of swinging. 0 turns it off.
  double smoothness = 3e-6;
  /// Dihedral angle (degrees) above which a mesh edge is a sharp feature.
  double feature_angle = 40;
  bool features = true;
  /// Refinement stops before the spline would exceed this many control points; 0 means the
  /// number of points (3 unknowns per control point against 3 coordinates per point: beyond
  /// that the fit would interpolate).
  int max_control_points = 0;
  /// Most refinement rounds.
  int max_iterations = 25;
  /// Most OptimizeKnot passes over the vertices per refinement round, each followed by a
  /// control-point solve; they stop early when one lowers the local energies by less than 1 %.
  /// A move is judged with the control points of the vertex's star solved again on the local
  /// points. 0 keeps the knots where the default placement puts them (fixed knots).
  int knot_sweeps = 3;
  /// Memory limit in bytes, against estimate_fit_memory(): a fit expected to need more from the
  /// start is refused (InvalidInput, see check_fit_memory()), and refinement stops before the
  /// spline would need more (stop reason "memory limit"). 0 = no limit.
  size_t max_memory = 0;
  /// How messages name the memory limit, so that they say what to change (the tbs command
  /// sets "--max-memory").
  std::string max_memory_name = "FitOptions::max_memory";
  /// Worker threads; 0 = all cores. The result does not depend on it.
  int threads = 0;
  /// Called from the calling thread between steps, and every 2 s while normals are estimated.
  /// May be empty.
  std::function<void(const FitProgress&)> progress;
  /// Cooperative cancellation: when a stop is requested on the std::stop_source this token
  /// comes from (from any thread), fit() throws Cancelled at its next step: before every
  /// progress report, so between the stages (normals, domain, each solve, each knot sweep,
  /// each error measurement, each refinement round) and every 2 s inside the normal
  /// estimation. Other stages are not interrupted inside: the wait is at most one stage,
  /// which on 1M points can be 10 s and on 10M points 95 s (the domain build;
  /// docs/benchmarks.md).
  /// Default: a token that never stops.
  std::stop_token stop;
};

/// The fit report: the paper's Table 1 columns and more. Errors are distances |p - F(u)|.
struct FitReport {
  size_t points = 0;
  /// Points left out of the fit: outliers outside the largest parameter region (bare points),
  /// points of other mesh components, or (rarely) points the domain builder could not keep
  /// inside the domain. Their error is NaN. Every other point is located by Evaluator::locate
  /// at its own (u, v): `tbs eval` evaluates it.
  size_t points_excluded = 0;
  /// Of `points`, the guides (Scan::guide): held with a tenth of the weight, not measured.
  /// max_error and rms_error are those of the other points.
  size_t guide_points = 0;
  int degree = 0;
  int domain_triangles = 0;
  int domain_vertices = 0;
  int feature_edges = 0;
  int holes = 0;
  int control_points = 0;
  double scale = 0;  ///< largest side of the points' bounding box: errors are divided by it
  double max_error = 0;
  double rms_error = 0;
  double max_error_abs = 0;
  double rms_error_abs = 0;
  double tolerance = 0;      ///< relative
  double tolerance_abs = 0;  ///< model units
  double fairness = 0;
  double bending = 0;
  double smoothness = 0;
  bool converged = false;
  std::string stop_reason;
  int iterations = 0;
  bool normals_estimated = false;
  /// Domain triangles where the fitted surface folds (its normal reverses; check_shape() at
  /// resolution 8) and the largest stretch of its parameterization (ShapeCheck::max_stretch).
  int folds = 0;
  double max_stretch = 0;
  /// The atlas (Scan::atlas): charts (components of the domain), seams, whether the glued
  /// surface is closed, and its genus. 1 chart, 0 seams for a scan over one planar domain.
  int charts = 1;
  int seams = 0;
  bool closed = false;
  int genus = 0;
  /// Along the seams (check_seams(), 1,000 samples per seam): the largest distance between
  /// glued points (relative, and in model units), the largest angle between the normals of
  /// glued points where the seam is smooth (degrees), and the smallest and largest crease
  /// angle where it is sharp (0 without sharp seams).
  double seam_gap = 0;
  double seam_gap_abs = 0;
  double seam_normal_jump = 0;
  double seam_crease_min = 0, seam_crease_max = 0;
  /// Seam samples where a side lies outside the domain (left out of the above; 0 when every
  /// seam lies in its charts).
  size_t seam_samples_outside = 0;
  /// estimate_fit_memory() for the points, degree and control points of the result, in bytes
  /// (in the JSON with the times: it describes the run, not the spline).
  size_t memory_estimate = 0;
  double seconds = 0;
  /// Wall time per stage: normals, domain, solve, knots, refine, error.
  std::vector<std::pair<std::string, double>> stage_seconds;
  /// The control-point solves of the fit (the "solve" stage, the knot search's re-solves
  /// included), split into their parts: wall seconds summed over the solves.
  struct SolveStages {
    int solves = 0;
    double pattern = 0;        ///< support sets and sparsity pattern
    double basis_rows = 0;     ///< thread-seconds of the points' basis rows (part of pattern and assembly)
    double assembly = 0;       ///< normal equations: local systems, scatter, sparse matrix
    double analysis = 0;       ///< CHOLMOD ordering and symbolic factorisation
    double factorization = 0;  ///< CHOLMOD numeric factorisation
    double solve = 0;          ///< triangular solves and conjugate gradients
    int cg_iterations = 0;     ///< conjugate-gradient iterations on the fairness term's coupling
    long unknowns = 0;         ///< rows of the last solve's factorised matrix (the control points)
    long nonzeros = 0;         ///< of that matrix, lower triangle
  };
  SolveStages solve_stages;
  /// One entry per refinement round: triangles, control points, max and RMS error (relative).
  struct Round {
    int triangles;
    int control_points;
    double max_error;
    double rms_error;
  };
  std::vector<Round> rounds;

  /// The report as a JSON object (text), fields in a fixed order. Without times it is a
  /// function of the input and options only (stored in .tbs files, which must be reproducible).
  /// Throws no tbs exception; nlohmann::json::type_error if stop_reason is not valid UTF-8
  /// (it can quote FitOptions::max_memory_name).
  std::string to_json(bool with_times = true) const;
};

struct FitResult {
  Spline spline;
  /// The scan's atlas (its seams, closed, genus), for the .tbs; empty without one.
  Atlas atlas;
  FitReport report;
  std::vector<Point2> uv;       ///< the parameters used, one per input point
  std::vector<double> error;    ///< |p - F(u)| per input point, model units
};

/// Estimated peak memory (bytes) of fit() on `points` points at degree n while its spline has
/// `control_points` control points, the scan itself included. A model fitted to the peaks
/// measured on synthetic scans of 100k to 1M points at degrees 2 to 5 (docs/benchmarks.md,
/// section "Memory"; measured with the `tbs` command, which keeps freed memory for reuse),
/// plus a quarter for safety. Throws nothing.
size_t estimate_fit_memory(size_t points, int degree, size_t control_points);

/// The control points of the initial domain fit() builds for `points` points (the domain
/// builder aims at FitOptions::triangles, or points / 200 within [32, 4000]). Throws nothing.
size_t initial_control_points(size_t points, const FitOptions& options);

/// Refuses, before any work, a fit expected to need more than options.max_memory:
/// estimate_fit_memory(points, degree, initial_control_points()) > max_memory. fit() calls it;
/// callers that prepare the scan first (parameterize_scan()) can call it before doing so.
/// \throw InvalidInput `<name>: fitting N points at degree n needs about X of memory, more than
///   the limit of Y (<max_memory_name>); ...` with what to change. Nothing if max_memory is 0.
void check_fit_memory(const std::string& name, size_t points, const FitOptions& options);

/// Fits one DMS spline to a scan that has parameters.
/// \throw InvalidInput if options are out of range, the scan needs more memory than
///        options.max_memory, has no parameters, fewer than 3 points, sizes that differ, a
///        non-finite value or one above 1e30 in magnitude, a normal that is not of unit length,
///        a triangle index out of range, all points identical, degenerate, sliver (area below
///        1e-5 of the extent squared) or folded parameters, or normals that cannot be estimated;
///        SolverError `<source>: <problem>` if the sparse solve fails; Cancelled if options.stop
///        was requested.
///        Whatever options.progress throws passes through.
FitResult fit(const Scan& scan, const FitOptions& options);

}  // namespace tbs
