#pragma once
// A shell built directly from known topology: vertices and edges shared by the faces that meet
// there, each edge with its 3D curve and a curve on the surface of every face it bounds. No
// sewing: the tolerances are measured, not searched for.

#include <Geom2d_Curve.hxx>
#include <Geom_Curve.hxx>
#include <Geom_Surface.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Vertex.hxx>
#include <gp_Pnt.hxx>

#include <vector>

namespace tbs::detail {

class ShellBuilder {
 public:
  ShellBuilder();

  // A vertex at p; its tolerance grows to cover every curve end and face corner at it.
  int add_vertex(const gp_Pnt& p);
  // An edge on curve c over [first, last], from vertex v0 to v1 (equal for a closed edge).
  int add_edge(const Handle(Geom_Curve)& c, double first, double last, int v0, int v1);
  // A degenerate edge at vertex v (a pole of a collapsed patch): no 3D curve, its range is
  // that of the pcurve given with its use.
  int add_degenerate_edge(int v, double first, double last);

  // One use of an edge in a face's wire: the edge, whether the wire runs it backwards, and
  // its curve in the face's parameters (over the edge's range).
  struct Use {
    int edge;
    bool reversed;
    Handle(Geom2d_Curve) pcurve;
  };
  // A face on surface s bounded by the wires (the first is the outer one).
  void add_face(const Handle(Geom_Surface)& s, const std::vector<std::vector<Use>>& wires);

  // The shell, or where the faces fall into parts that share no edge, a compound of one shell
  // per part. Edge tolerances are the largest distance measured between each edge's 3D curve
  // and its curves on the faces' surfaces (plus OCCT's confusion distance), vertex tolerances
  // cover the edges and curve ends at them.
  TopoDS_Shape finish();

  size_t face_count() const { return faces_; }
  double max_edge_tolerance() const { return max_edge_tolerance_; }

 private:
  struct Edge {
    TopoDS_Edge edge;
    Handle(Geom_Curve) curve;
    double first = 0, last = 0;
    int v0 = -1, v1 = -1;
    double gap = 0;
  };
  void measure(Edge& e, const Handle(Geom2d_Curve)& pc, const Handle(Geom_Surface)& s);

  std::vector<TopoDS_Vertex> vertices_;
  std::vector<gp_Pnt> points_;
  std::vector<double> vertex_gap_;
  std::vector<Edge> edges_;
  TopoDS_Shell shell_;
  size_t faces_ = 0;
  double max_edge_tolerance_ = 0;
};

}  // namespace tbs::detail
