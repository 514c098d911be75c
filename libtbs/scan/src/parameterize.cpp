// Parameters for raw scans (parameterize_scan): checks the scan, has a point cloud's surface
// reconstructed, repairs the mesh and picks its component, cuts a closed surface open,
// flattens it, subdivides it where asked, and gives every point the parameter of its place on
// the flattened mesh; the report. The steps are in the files scan_mesh.h names.

#include "scan_mesh.h"

#include <tbs/errors.h>
#include <tbs/parameterize.h>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>

namespace tbs {
namespace detail {

// A number for a message, in 4 significant digits.
std::string short_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

std::string plural(size_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

}  // namespace detail

using namespace detail;

std::string ParameterizeReport::to_json() const {
  auto topo = [](const MeshTopology& t) {
    return nlohmann::ordered_json{{"vertices", t.vertices}, {"edges", t.edges},        {"faces", t.faces},
                                  {"components", t.components}, {"boundary_loops", t.boundary_loops},
                                  {"genus", t.genus}};
  };
  nlohmann::ordered_json j;
  j["input"] = input;
  j["input_points"] = input_points;
  j["input_faces"] = input_faces;
  if (input == "point cloud") {
    j["reconstructed_faces"] = reconstructed_faces;
    j["bridge_faces_removed"] = bridge_faces_removed;
  }
  j["repair"] = {{"vertices_merged", vertices_merged},
                 {"faces_removed", faces_removed},
                 {"vertices_split", vertices_split},
                 {"reoriented", reoriented},
                 {"isolated_points", isolated_points}};
  j["topology"] = topo(topology);
  j["component"] = component;
  j["component_topology"] = topo(used);
  j["seam_edges"] = seam_edges;
  j["charts"] = charts;
  j["seams"] = seams;
  j["stretch"] = stretch;
  j["method"] = method;
  j["fallback_reason"] = fallback_reason;
  if (method == "LSCM, areas relaxed")
    j["conformal_distortion"] = {{"angle", {{"mean", conformal.angle_mean}, {"max", conformal.angle_max}}},
                                 {"area", {{"mean", conformal.area_mean}, {"max", conformal.area_max}}}};
  j["angle_distortion"] = {{"mean", distortion.angle_mean}, {"max", distortion.angle_max}};
  j["area_distortion"] = {{"mean", distortion.area_mean}, {"max", distortion.area_max}};
  j["points_projected"] = points_projected;
  j["points_dropped"] = points_dropped;
  j["subdivisions"] = subdivisions;
  j["points_added"] = points_added;
  j["seconds"] = seconds;
  return j.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

ParameterizedScan parameterize_scan(const Scan& scan, const ParameterizeOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string name = scan.source.empty() ? "the scan" : scan.source;
  auto say = [&](const std::string& s) {
    if (o.progress) o.progress(s);
  };
  ParameterizedScan out;
  ParameterizeReport& rep = out.report;
  const bool cloud = scan.triangles.empty();
  rep.input = cloud ? "point cloud" : "mesh";
  rep.input_points = scan.positions.size();
  rep.input_faces = scan.triangles.size();
  if (scan.positions.size() < 3) throw InvalidInput(name + ": too few points to parameterize (" + std::to_string(scan.positions.size()) + ")");
  // What read_scan guarantees, checked again for scans built in code.
  for (size_t i = 0; i < scan.positions.size(); ++i)
    if (!scan.positions[i].allFinite() || scan.positions[i].cwiseAbs().maxCoeff() > 1e30)
      throw InvalidInput(name + ": point " + std::to_string(i) + " is not finite or larger than 1e30 in magnitude");
  if (!scan.normals.empty() && scan.normals.size() != scan.positions.size())
    throw InvalidInput(name + ": " + std::to_string(scan.normals.size()) + " normals for " +
                       std::to_string(scan.positions.size()) + " points; give one per point or none");
  for (size_t i = 0; i < scan.normals.size(); ++i)
    if (!scan.normals[i].allFinite() || !(scan.normals[i].stableNorm() > 0))
      throw InvalidInput(name + ": normal " + std::to_string(i) + " is not a finite, non-zero vector");
  for (size_t f = 0; f < scan.triangles.size(); ++f)
    for (int v : scan.triangles[f])
      if (v < 0 || static_cast<size_t>(v) >= scan.positions.size())
        throw InvalidInput(name + ": triangle " + std::to_string(f) + " refers to point " + std::to_string(v) +
                           ", but the points are numbered 0 to " + std::to_string(scan.positions.size() - 1));

  std::vector<Tri> triangles = scan.triangles;
  if (cloud) triangles = reconstruct_surface(scan, name, rep, say);

  say("repairing the mesh");
  Mesh3 mesh = repair(scan.positions, triangles, rep);
  if (mesh.faces.empty()) throw InvalidInput(name + ": no usable triangle is left after removing degenerate ones");
  int components = 0;
  const std::vector<int> label = face_components(mesh.faces, components);
  rep.topology = mesh_topology(mesh.points.size(), mesh.faces);
  const int want = o.component <= 0 ? 1 : o.component;
  if (want > components)
    throw InvalidInput(name + ": there is no component " + std::to_string(want) + ": the mesh has " + rep.topology.describe() +
                       "; choose --component 1 to " + std::to_string(components));
  rep.component = want;

  // The chosen component, vertices renumbered in order of first use.
  Mesh3 part;
  std::vector<int> local(mesh.points.size(), -1), face_local(mesh.faces.size(), -1);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (label[f] != want - 1) continue;
    Tri t;
    for (int k = 0; k < 3; ++k) {
      int& l = local[mesh.faces[f][k]];
      if (l < 0) l = int(part.points.size()), part.points.push_back(mesh.points[mesh.faces[f][k]]);
      t[k] = l;
    }
    face_local[f] = int(part.faces.size());
    part.faces.push_back(t);
  }
  rep.used = mesh_topology(part.points.size(), part.faces);
  const std::string found = "component " + std::to_string(want) + " of " + std::to_string(components) + " has " +
                            plural(rep.used.vertices, "vertex", "vertices") + ", " +
                            plural(size_t(rep.used.boundary_loops), "boundary loop", "boundary loops") +
                            ", genus " + std::to_string(rep.used.genus);
  {
    // Faces that are all slivers (nearly collinear corners) survive the exact degeneracy test
    // but flatten onto a curve.
    double area = 0;
    Eigen::AlignedBox3d box;
    for (const Tri& t : part.faces) {
      const Point3 &a = part.points[t[0]], &b = part.points[t[1]], &c = part.points[t[2]];
      area += 0.5 * (b - a).cross(c - a).norm();
      box.extend(a), box.extend(b), box.extend(c);
    }
    const double diagonal = box.diagonal().norm();
    if (!(area > 1e-10 * diagonal * diagonal))
      throw InvalidInput(name + ": " + found + ", but its " + plural(part.faces.size(), "face has", "faces have") +
                         " almost no area (" + short_number(area) + " in a box of diagonal " +
                         short_number(diagonal) + "): they are slivers; remesh the scan");
  }
  // A step's refusal, prefixed with the file and the component as the checks above are.
  auto naming_the_component = [&](auto&& step) {
    try {
      return step();
    } catch (const InvalidInput& e) {
      throw InvalidInput(name + ": " + found + ": " + e.what());
    }
  };
  const bool closed = rep.used.boundary_loops == 0;
  if ((closed || rep.used.genus > 0) && !o.cut_closed)
    throw InvalidInput(name + ": " + found + ": the surface is " + (closed ? "closed" : "not a disk (it has handles)") +
                       "; allow tbs to cut it into charts, or cut it open into a disk yourself");
  std::vector<P2> uv;
  // One flattening where the surface is a disk, possibly with holes, and it keeps within the
  // chart stretch (an explicit method is used as asked); charts otherwise.
  bool charts = closed || rep.used.genus > 0;
  if (!charts) {
    try {
      uv = naming_the_component([&] { return flatten(part, o, rep); });
      normalise(part, uv);
      rep.stretch = flattening_stretch(part, uv);
      if (o.method == FlattenMethod::Auto && rep.stretch > o.chart_stretch) {
        char text[160];
        std::snprintf(text, sizeof text, "one flattening stretches %.3g times (more than %.3g); cutting the surface "
                      "into charts", rep.stretch, o.chart_stretch);
        say(text);
        charts = true;
      }
    } catch (const InvalidInput&) {
      if (o.method != FlattenMethod::Auto) throw;
      say("no single flattening is bijective (" + rep.fallback_reason + "); cutting the surface into charts");
      charts = true;
    }
  }
  if (charts) {
    ChartCut cut = naming_the_component([&] { return cut_into_charts(part, o, rep); });
    part = std::move(cut.mesh);
    uv = std::move(cut.uv);
    rep.charts = cut.charts;
    rep.seams = cut.seams.size();
    rep.seam_edges = cut.seam_edges;
    rep.stretch = cut.stretch;
    rep.method = "charts (LSCM)";
    rep.fallback_reason.clear();
    out.scan.atlas.seams = std::move(cut.seams);
    out.scan.atlas.borders = std::move(cut.borders);
    out.scan.atlas.closed = closed;
    out.scan.atlas.genus = rep.used.genus;
  }
  rep.distortion = distortion(part, uv);

  // The input point of each part vertex: exact positions, first index.
  std::unordered_map<std::string, size_t> index_of;
  auto key = [](const Point3& p) { return std::string(reinterpret_cast<const char*>(p.data()), 3 * sizeof(double)); };
  for (size_t i = scan.positions.size(); i-- > 0;) index_of[key(scan.positions[i])] = i;
  Scan& s = out.scan;
  s.source = scan.source;
  if (!cloud) {
    // Vertices on seams appear once per chart: count the input points used.
    std::vector<char> used_point(scan.positions.size(), 0);
    for (const Point3& p : part.points) {
      const auto it = index_of.find(key(p));
      if (it != index_of.end()) used_point[it->second] = 1;
    }
    rep.points_dropped = scan.positions.size() - static_cast<size_t>(std::count(used_point.begin(), used_point.end(), 1));
    // Each vertex's input point; subdivision vertices take their edge's first vertex's (for the
    // normal) and are marked as new in `source` below.
    std::vector<int> origin(part.points.size());
    std::iota(origin.begin(), origin.end(), 0);
    const size_t original = part.points.size();
    while (o.min_points > 0 && part.points.size() < o.min_points && rep.subdivisions < 4) {
      subdivide(part, uv, origin, o.sharp_angle);
      ++rep.subdivisions;
    }
    rep.points_added = part.points.size() - original;
    if (rep.subdivisions) say("subdivided the mesh " + std::to_string(rep.subdivisions) + " times: " +
                              plural(part.points.size(), "point", "points"));
    for (size_t v = 0; v < part.points.size(); ++v) {
      const auto it = index_of.find(key(part.points[origin[v]]));
      const size_t src = it == index_of.end() ? 0 : it->second;
      out.source.push_back(src);
      if (original < part.points.size()) s.guide.push_back(v >= original ? 1 : 0);
      s.positions.push_back(part.points[v]);
      s.uv.emplace_back(uv[v].x(), uv[v].y());
      if (scan.has_normals()) s.normals.push_back(scan.normals[src].stableNormalized());
    }
    s.triangles = part.faces;
  } else {
    // Every point takes the parameter of its closest point on the mesh, if that lies on the
    // chosen component.
    say("projecting the points onto the mesh");
    std::vector<K::Triangle_3> tris;
    for (const Tri& t : mesh.faces)
      tris.emplace_back(P3(mesh.points[t[0]].x(), mesh.points[t[0]].y(), mesh.points[t[0]].z()),
                        P3(mesh.points[t[1]].x(), mesh.points[t[1]].y(), mesh.points[t[1]].z()),
                        P3(mesh.points[t[2]].x(), mesh.points[t[2]].y(), mesh.points[t[2]].z()));
    using Prim = CGAL::AABB_triangle_primitive<K, std::vector<K::Triangle_3>::const_iterator>;
    using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Prim>>;
    Tree tree(tris.begin(), tris.end());
    tree.accelerate_distance_queries();
    for (size_t i = 0; i < scan.positions.size(); ++i) {
      const Point3& p = scan.positions[i];
      const auto [q, prim] = tree.closest_point_and_primitive(P3(p.x(), p.y(), p.z()));
      const size_t f = static_cast<size_t>(prim - tris.begin());
      if (face_local[f] < 0) {
        ++rep.points_dropped;
        continue;
      }
      const Tri& t = part.faces[face_local[f]];
      // Barycentric coordinates of q in the 3D triangle.
      const Vector3 e1 = part.points[t[1]] - part.points[t[0]], e2 = part.points[t[2]] - part.points[t[0]];
      const Vector3 r = Vector3(q.x(), q.y(), q.z()) - part.points[t[0]];
      Eigen::Matrix2d g;
      g << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
      Eigen::Vector2d l = g.ldlt().solve(Eigen::Vector2d(e1.dot(r), e2.dot(r)));
      l = l.cwiseMax(0.0);
      if (l.sum() > 1) l /= l.sum();
      const P2 &a = uv[t[0]], &b = uv[t[1]], &c = uv[t[2]];
      s.positions.push_back(p);
      s.uv.emplace_back(a.x() + l[0] * (b.x() - a.x()) + l[1] * (c.x() - a.x()),
                        a.y() + l[0] * (b.y() - a.y()) + l[1] * (c.y() - a.y()));
      if (scan.has_normals()) s.normals.push_back(scan.normals[i].stableNormalized());
      out.source.push_back(i);
      ++rep.points_projected;
    }
  }
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace tbs
