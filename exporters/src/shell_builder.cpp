#include "shell_builder.h"

#include <BRep_Builder.hxx>
#include <Precision.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListIteratorOfListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Wire.hxx>

#include <algorithm>
#include <map>
#include <numeric>

namespace tbs::detail {

namespace {
// Samples per edge and face for measuring the gap between the 3D curve and the curve on the
// surface; BRepCheck checks 23 points (uniform in the parameter), which are among these.
constexpr int kGapSamples = 66;
// Tolerances are the measured gaps with this much to spare, so that a check at points between
// the samples passes too.
constexpr double kSpare = 1.2;
}  // namespace

ShellBuilder::ShellBuilder() { BRep_Builder().MakeShell(shell_); }

int ShellBuilder::add_vertex(const gp_Pnt& p) {
  TopoDS_Vertex v;
  BRep_Builder().MakeVertex(v, p, Precision::Confusion());
  vertices_.push_back(v);
  points_.push_back(p);
  vertex_gap_.push_back(0);
  return static_cast<int>(vertices_.size()) - 1;
}

int ShellBuilder::add_edge(const Handle(Geom_Curve)& c, double first, double last, int v0, int v1) {
  BRep_Builder b;
  Edge e;
  b.MakeEdge(e.edge, c, Precision::Confusion());
  b.Add(e.edge, vertices_[static_cast<size_t>(v0)].Oriented(TopAbs_FORWARD));
  b.Add(e.edge, vertices_[static_cast<size_t>(v1)].Oriented(TopAbs_REVERSED));
  e.curve = c;
  e.first = first;
  e.last = last;
  e.v0 = v0;
  e.v1 = v1;
  double& g0 = vertex_gap_[static_cast<size_t>(v0)];
  double& g1 = vertex_gap_[static_cast<size_t>(v1)];
  g0 = std::max(g0, c->Value(first).Distance(points_[static_cast<size_t>(v0)]));
  g1 = std::max(g1, c->Value(last).Distance(points_[static_cast<size_t>(v1)]));
  edges_.push_back(e);
  return static_cast<int>(edges_.size()) - 1;
}

int ShellBuilder::add_degenerate_edge(int v, double first, double last) {
  BRep_Builder b;
  Edge e;
  b.MakeEdge(e.edge);
  b.Degenerated(e.edge, Standard_True);
  b.Add(e.edge, vertices_[static_cast<size_t>(v)].Oriented(TopAbs_FORWARD));
  b.Add(e.edge, vertices_[static_cast<size_t>(v)].Oriented(TopAbs_REVERSED));
  e.first = first;
  e.last = last;
  e.v0 = e.v1 = v;
  edges_.push_back(e);
  return static_cast<int>(edges_.size()) - 1;
}

void ShellBuilder::measure(Edge& e, const Handle(Geom2d_Curve)& pc, const Handle(Geom_Surface)& s) {
  for (int i = 0; i <= kGapSamples; ++i) {
    const double t = e.first + (e.last - e.first) * i / kGapSamples;
    const gp_Pnt2d uv = pc->Value(t);
    const gp_Pnt on_surface = s->Value(uv.X(), uv.Y());
    if (e.curve.IsNull()) {
      double& g = vertex_gap_[static_cast<size_t>(e.v0)];
      g = std::max(g, on_surface.Distance(points_[static_cast<size_t>(e.v0)]));
    } else {
      e.gap = std::max(e.gap, on_surface.Distance(e.curve->Value(t)));
    }
    if (i == 0 || i == kGapSamples) {
      const int v = i == 0 ? e.v0 : e.v1;
      double& g = vertex_gap_[static_cast<size_t>(v)];
      g = std::max(g, on_surface.Distance(points_[static_cast<size_t>(v)]));
    }
  }
}

void ShellBuilder::add_face(const Handle(Geom_Surface)& s, const std::vector<std::vector<Use>>& wires) {
  BRep_Builder b;
  TopoDS_Face f;
  b.MakeFace(f, s, Precision::Confusion());
  b.NaturalRestriction(f, Standard_False);
  // An edge that bounds the face on both sides (a seam of a chart with itself) gets both its
  // curves on the surface at once: the first for the edge run forward, the second backward.
  std::map<int, std::vector<const Use*>> uses_of;
  for (const auto& uses : wires)
    for (const Use& u : uses) uses_of[u.edge].push_back(&u);
  for (const auto& [id, uses] : uses_of) {
    Edge& e = edges_[static_cast<size_t>(id)];
    if (uses.size() == 2 && uses[0]->reversed != uses[1]->reversed) {
      const Use* forward = uses[0]->reversed ? uses[1] : uses[0];
      const Use* backward = uses[0]->reversed ? uses[0] : uses[1];
      b.UpdateEdge(e.edge, forward->pcurve, backward->pcurve, f, Precision::Confusion());
    } else {
      b.UpdateEdge(e.edge, uses[0]->pcurve, f, Precision::Confusion());
    }
    for (const Use* u : uses) measure(e, u->pcurve, s);
  }
  for (const auto& uses : wires) {
    TopoDS_Wire w;
    b.MakeWire(w);
    for (const Use& u : uses) {
      Edge& e = edges_[static_cast<size_t>(u.edge)];
      b.Add(w, u.reversed ? e.edge.Reversed() : e.edge);
    }
    w.Closed(Standard_True);
    b.Add(f, w);
  }
  b.Add(shell_, f);
  ++faces_;
}

TopoDS_Shape ShellBuilder::finish() {
  BRep_Builder b;
  std::vector<double> vertex_tol(vertices_.size());
  for (size_t v = 0; v < vertices_.size(); ++v) vertex_tol[v] = kSpare * vertex_gap_[v] + Precision::Confusion();
  for (Edge& e : edges_) {
    const double tol = kSpare * e.gap + Precision::Confusion();
    max_edge_tolerance_ = std::max(max_edge_tolerance_, tol);
    b.Range(e.edge, e.first, e.last);
    b.UpdateEdge(e.edge, tol);
    b.SameRange(e.edge, Standard_True);
    b.SameParameter(e.edge, Standard_True);
    for (int v : {e.v0, e.v1}) vertex_tol[static_cast<size_t>(v)] = std::max(vertex_tol[static_cast<size_t>(v)], tol);
  }
  for (size_t v = 0; v < vertices_.size(); ++v)
    b.UpdateVertex(vertices_[v], points_[v], vertex_tol[v]);
  shell_.Closed(Standard_False);
  // A shell must be connected (BRepCheck refuses one that is not): faces that share no edge,
  // the charts of an atlas or the components of a domain, go into shells of their own, in a
  // compound. One part stays the shell it is.
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(shell_, TopAbs_FACE, faces);
  TopTools_IndexedDataMapOfShapeListOfShape faces_of;
  TopExp::MapShapesAndAncestors(shell_, TopAbs_EDGE, TopAbs_FACE, faces_of);
  std::vector<int> part(static_cast<size_t>(faces.Extent()));
  std::iota(part.begin(), part.end(), 0);
  auto find = [&](int x) {
    while (part[static_cast<size_t>(x)] != x) x = part[static_cast<size_t>(x)] = part[static_cast<size_t>(part[static_cast<size_t>(x)])];
    return x;
  };
  for (int i = 1; i <= faces_of.Extent(); ++i) {
    int first = -1;
    for (TopTools_ListIteratorOfListOfShape it(faces_of(i)); it.More(); it.Next()) {
      const int f = faces.FindIndex(it.Value()) - 1;
      if (first < 0)
        first = f;
      else
        part[static_cast<size_t>(find(f))] = find(first);
    }
  }
  std::map<int, TopoDS_Shell> shells;
  for (int f = 0; f < faces.Extent(); ++f) {
    const int r = find(f);
    if (!shells.count(r)) {
      TopoDS_Shell s;
      b.MakeShell(s);
      shells[r] = s;
    }
    b.Add(shells[r], faces(f + 1));
  }
  if (shells.size() <= 1) return shell_;
  TopoDS_Compound c;
  b.MakeCompound(c);
  for (auto& [r, s] : shells) {
    s.Closed(Standard_False);
    b.Add(c, s);
  }
  return c;
}

}  // namespace tbs::detail
