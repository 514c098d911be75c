#pragma once
/// \file
/// The atlas of a surface that no single planar domain can carry (a closed surface, one of any
/// genus, or a sheet whose one flattening would stretch too much): its charts are the
/// components of the domain, laid side by side in one plane under one spline, and its seams
/// glue their boundaries point for point (METHOD.md section 10).

#include <tbs/types.h>

#include <array>
#include <string>
#include <vector>

namespace tbs {

class Domain;
class Evaluator;
class Spline;

/// Two stretches of chart boundary glued into one curve of the surface. Point a[i] is glued to
/// b[i], and the segment a[i] a[i+1] to b[i] b[i+1], linearly (so each side runs at the speed
/// of the other, segment by segment). The sides lie in two charts, or twice in one chart (a
/// cut that opened a handle or a tube). A closed seam repeats its first point at the end.
struct Seam {
  std::vector<Point2> a;
  std::vector<Point2> b;  ///< as many points as a
  /// A crease (the surface is only C^0 there: a sharp edge of the object); otherwise the two
  /// sides join with one tangent plane.
  bool sharp = false;
};

/// The seams of a spline's domain and what they make of it. An empty atlas (no seam) is a
/// spline over one planar domain, as tbs made them before atlases: its components, if several,
/// are separate sheets.
///
/// The domain reaches a little beyond each chart (its margin, where the surface continues the
/// chart's own); the chart itself ends at its outline: the seam sides and the borders, which
/// join end to end into closed loops (chart_outlines()). Where two charts meet, the surface
/// is the one chart's up to the seam and the other's beyond it.
struct Atlas {
  std::vector<Seam> seams;
  /// The stretches of the charts' outlines glued to nothing: the surface's own boundary, each
  /// a polyline with its chart on the left (a whole loop repeats its first point at the end).
  std::vector<std::vector<Point2>> borders;
  /// The glued surface has no free boundary (it bounds a solid).
  bool closed = false;
  /// The genus of the glued surface (its handles: 0 for a sphere, 1 for a torus), as the
  /// cutting found it.
  int genus = 0;
  bool empty() const { return seams.empty(); }
};

/// The charts of a domain: its edge-connected components, numbered by their smallest triangle.
struct Charts {
  int count = 0;
  std::vector<int> of_triangle;  ///< the chart of each domain triangle
};

/// The charts of `domain`. Throws nothing but std::bad_alloc.
Charts domain_charts(const Domain& domain);

/// The outlines of the atlas's charts: its seam sides (side a as it runs, side b reversed) and
/// borders joined end to end (where their end points are equal) into closed loops, each with
/// its chart on the left (outer loops counter-clockwise, holes clockwise), the first point not
/// repeated. The trimmed surface is the part of the domain inside the loops (even-odd rule).
/// 	hrow InvalidInput if the pieces do not close into loops (an end meets no other piece).
std::vector<std::vector<Point2>> chart_outlines(const Atlas& atlas);

/// Whether p lies inside the loops (even-odd rule; points on a loop count as inside or not by
/// rounding). Throws nothing.
bool inside_outlines(const std::vector<std::vector<Point2>>& loops, const Point2& p);

/// The same test, fast for many points: the loops' segments bucketed by rows of the plane.
class OutlineIndex {
 public:
  /// Throws nothing but std::bad_alloc.
  explicit OutlineIndex(const std::vector<std::vector<Point2>>& loops);
  /// As inside_outlines(). Throws nothing.
  bool inside(const Point2& p) const;

 private:
  std::vector<std::array<Point2, 2>> segments_;
  std::vector<std::vector<int>> rows_;
  double y0_ = 0, dy_ = 1;
};

/// Checks the structure of an atlas: every seam has at least two points per side and as many
/// on both, every border at least two, all finite and at most 1e30 in magnitude; the genus is
/// not negative.
/// \throw InvalidInput `<name>: atlas.seams[3].b: ...` naming the seam and what is wrong.
void check_atlas_structure(const Atlas& atlas, const std::string& name);

/// How well the sides of the seams agree, sampled along every seam.
struct SeamCheck {
  size_t samples = 0;
  /// Of the samples, those where a side lies outside the domain, or in another chart than the
  /// side's other samples: the seam does not belong to this spline there. Left out of the rest.
  size_t outside = 0;
  /// The largest |F(a) - F(b)| between glued points, model units.
  double max_gap = 0;
  /// The largest angle (degrees) between the normals of glued points on smooth seams.
  double max_normal_jump = 0;
  /// On sharp seams: the smallest and largest angle (degrees) between the two sides' normals
  /// (the crease angle); 0 and 0 when there is no sharp seam.
  double min_crease = 0, max_crease = 0;
  /// Per seam, the largest gap (model units) and normal angle (degrees).
  std::vector<double> seam_gap, seam_angle;
};

/// Samples every seam at `samples_per_seam` points, evenly over its segments (the same share
/// for each), on both sides; `eval` evaluates `spline`. Deterministic for any `threads` (0 = all
/// cores). \throw InvalidInput if samples_per_seam < 1 or the atlas is malformed
///   (check_atlas_structure()).
SeamCheck check_seams(const Spline& spline, const Evaluator& eval, const Atlas& atlas,
                      int samples_per_seam = 1000, int threads = 0);

}  // namespace tbs
