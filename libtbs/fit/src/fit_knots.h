#pragma once
// Internal: OptimizeKnot (paper section 4.3) by a derivative-free pattern search.

#include "fit_solve.h"

#include <tbs/evaluator.h>
#include <tbs/spline.h>

#include <functional>
#include <vector>

namespace tbs::detail {

struct KnotSweepStats {
  int vertices = 0;  // vertices optimised
  int moved = 0;     // vertices whose knots changed
  double energy_before = 0, energy_after = 0;  // sum of their local energies
};

/// One pass of OptimizeKnot(t_s) over `vertices` (domain vertex indices). Vertices fewer than
/// 4 edges apart get different colours; each colour class runs in parallel (`threads`, 0 = all
/// cores) on per-worker copies of the spline, so the result does not depend on the thread
/// count: a vertex's search sees only the state at the start of its class. Moves only
/// accepted when the local energy (points located in the 2-ring of s, at most 512 of them taken
/// evenly by index), with the control points of the star of s solved again on those points for
/// the candidate knots, falls and every knot condition still holds (a vertex whose star holds
/// too few points to decide those control points is left alone; an accepted move's control
/// points are kept in `spline`). The knot conditions: primary knots of interior vertices stay inside their 1-ring (no
/// triangle flips or collapses), sub-knots within Traas's radius r of the primary knot,
/// boundary sub-knots outside the domain; boundary primary knots and the knots of feature
/// vertices stay fixed. `located` is updated for points whose triangle changes;
/// `on_primary_move(v, p)` reports primary knot moves. `keep_rows` (for tests): a candidate
/// move computes again only the basis rows of points its basis functions may reach; false
/// computes every local point's row for every candidate (the same result, slower).
KnotSweepStats optimize_knots(Spline& spline, Evaluator& eval, std::vector<int>& located,
                              const FitPoints& pts, double lambda, std::span<const int> vertices,
                              const std::function<void(int, const Point2&)>& on_primary_move,
                              int threads, bool keep_rows = true);

}  // namespace tbs::detail
