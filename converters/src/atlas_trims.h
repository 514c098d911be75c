#pragma once
// Region faces over an atlas (cad_regions.h): the trims and topology of one face per chart.

#include <tbs/cad_regions.h>
#include <tbs/evaluator.h>

#include <vector>

namespace tbs::detail {

// Over `atlas` of the spline that `ev` evaluates (`charts`: its domain's, domain_charts()): the
// topological vertices (seam and border ends, shared by the charts that meet there), one edge
// per seam (its two sides as trims of the faces it glues) and
// per border (a free edge), the loops of every face (face_of_chart[c] is the face of chart c,
// its outline's loops with the outer one first), the 3D curve of every edge (within `curve_tol`
// of the middle of its sides, at most `rounds` refinements) and its measured gap to the faces.
// Fills out.vertex_ids, vertex_parameters, vertices, edges and faces[].loops; the faces'
// surfaces must be set.
// \throw Error if an outline does not close or lies outside its chart's domain.
void atlas_trims(const Atlas& atlas, const Evaluator& ev, const Charts& charts,
                 const std::vector<int>& face_of_chart,
                 double curve_tol, int degree, int rounds, CadRegions& out);

}  // namespace tbs::detail
