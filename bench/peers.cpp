// Side-by-side benchmark tools for bench/run.py: OpenCASCADE's plate surface as a peer, and
// the one error measure every surface is judged by.
//
//   tbs_peers plate SCAN OUT.brep [--constraints N] [--tolerance T] [--max-degree D]
//                                 [--max-segments S] [--criterion C]
//       Builds GeomPlate_BuildPlateSurface from N points of SCAN (a random sample, fixed seed;
//       each a GeomPlate_PointConstraint), approximates it with GeomPlate_MakeApprox as one
//       Geom_BSplineSurface (criterion order C, default -1: the 3D distance only; 3D tolerance
//       T, relative to the largest side of the scan's bounding box) and writes it as a BRep
//       face. Prints one JSON object: poles, degrees, constraints, seconds.
//
//   tbs_peers points SCAN OUT.xyz
//       The positions of SCAN (any format tbs reads) as text, for FreeCAD.
//
//   tbs_peers distance SCAN SURFACE [--resolution R] [--chordal-tolerance T] [--dump FILE]
//       The distance from every point of SCAN to SURFACE, which is either a .tbs spline
//       (tessellated by tbs::tessellate, adaptive, chordal tolerance T of the model size,
//       default 1e-5) or a .brep holding one B-spline face (FreeCAD's approxSurface, the
//       plate), tessellated on an R x R grid over its parameter rectangle (default 600,
//       doubled while the grid's chordal deviation exceeds T, up to 2,400). Both become
//       triangle meshes, and the same code (CGAL's AABB tree, closest point on the mesh)
//       measures every point. Prints one JSON object: the max, RMS and mean distance over the
//       largest side of the scan's bounding box, the absolute max and RMS, and the
//       tessellation's measured chordal deviation, which bounds how far the mesh distance can
//       be from the distance to the surface itself. --dump writes x, y and the relative
//       distance of every point, for plots.
#include <tbs/io.h>
#include <tbs/scan.h>
#include <tbs/tessellate.h>

#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GeomPlate_BuildPlateSurface.hxx>
#include <GeomPlate_MakeApprox.hxx>
#include <GeomPlate_PointConstraint.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Surface.hxx>
#include <Standard_Failure.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using K = CGAL::Simple_cartesian<double>;

struct TriMesh {
  std::vector<tbs::Point3> positions;
  std::vector<std::array<int, 3>> faces;
  double chordal_deviation = 0;  // measured: largest distance face - surface
  std::string how;
};

// The largest side of the points' bounding box: the scale of tbs's own error figures (and of
// the paper's).
double model_size(const std::vector<tbs::Point3>& points) {
  tbs::Point3 lo = points.front(), hi = points.front();
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).maxCoeff();
}

std::string arg_value(std::vector<std::string>& args, const std::string& name, const std::string& fallback) {
  const auto it = std::find(args.begin(), args.end(), name);
  if (it == args.end()) return fallback;
  if (it + 1 == args.end()) throw std::runtime_error(name + " needs a value");
  std::string value = *(it + 1);
  args.erase(it, it + 2);
  return value;
}

Handle(Geom_Surface) read_brep_surface(const std::string& path) {
  TopoDS_Shape shape;
  BRep_Builder builder;
  if (!BRepTools::Read(shape, path.c_str(), builder))
    throw std::runtime_error(path + ": not a BRep file OpenCASCADE can read");
  TopExp_Explorer faces(shape, TopAbs_FACE);
  if (!faces.More()) throw std::runtime_error(path + ": holds no face");
  return BRep_Tool::Surface(TopoDS::Face(faces.Current()));
}

TriMesh grid_mesh(const Handle(Geom_Surface) & surface, int resolution) {
  double u0, u1, v0, v1;
  surface->Bounds(u0, u1, v0, v1);
  const int n = resolution;
  TriMesh mesh;
  mesh.positions.resize(static_cast<std::size_t>(n + 1) * (n + 1));
  auto uv = [&](double i, double j) {
    return std::pair{u0 + (u1 - u0) * i / n, v0 + (v1 - v0) * j / n};
  };
  auto value = [&](double i, double j) {
    const auto [u, v] = uv(i, j);
    const gp_Pnt p = surface->Value(u, v);
    return tbs::Point3(p.X(), p.Y(), p.Z());
  };
  tbb::parallel_for(0, n + 1, [&](int j) {
    for (int i = 0; i <= n; ++i) mesh.positions[static_cast<std::size_t>(j) * (n + 1) + i] = value(i, j);
  });
  auto index = [n](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      mesh.faces.push_back({index(i, j), index(i + 1, j), index(i + 1, j + 1)});
      mesh.faces.push_back({index(i, j), index(i + 1, j + 1), index(i, j + 1)});
    }
  // Chordal deviation at the centroid of every face (the largest gap of a flat triangle on a
  // smooth surface is near it) and at the midpoints of the diagonals.
  std::vector<double> worst(static_cast<std::size_t>(n), 0.0);
  tbb::parallel_for(0, n, [&](int j) {
    for (int i = 0; i < n; ++i) {
      const auto& a = mesh.positions[index(i, j)];
      const auto& b = mesh.positions[index(i + 1, j)];
      const auto& c = mesh.positions[index(i + 1, j + 1)];
      const auto& d = mesh.positions[index(i, j + 1)];
      const double dev = std::max({(value(i + 2.0 / 3, j + 1.0 / 3) - (a + b + c) / 3).norm(),
                                   (value(i + 1.0 / 3, j + 2.0 / 3) - (a + c + d) / 3).norm(),
                                   (value(i + 0.5, j + 0.5) - (a + c) / 2).norm()});
      worst[j] = std::max(worst[j], dev);
    }
  });
  mesh.chordal_deviation = *std::max_element(worst.begin(), worst.end());
  mesh.how = "grid " + std::to_string(n) + " x " + std::to_string(n) + " over the parameter rectangle";
  return mesh;
}

TriMesh spline_mesh(const std::string& path, double chordal_tolerance) {
  const tbs::SplineFile file = tbs::read_tbs(path);
  tbs::TessellateOptions options;
  options.chordal_tolerance = chordal_tolerance;
  options.max_resolution = 256;
  tbs::Mesh m = tbs::tessellate(file.spline, options);
  TriMesh mesh;
  mesh.positions = std::move(m.positions);
  mesh.faces = std::move(m.faces);
  mesh.chordal_deviation = m.max_chordal_deviation;
  mesh.how = "tbs::tessellate, chordal tolerance " + std::to_string(chordal_tolerance) + " of the model size";
  return mesh;
}

int distance(std::vector<std::string> args) {
  const int resolution = std::stoi(arg_value(args, "--resolution", "600"));
  const double chordal = std::stod(arg_value(args, "--chordal-tolerance", "1e-5"));
  const std::string dump = arg_value(args, "--dump", "");
  if (args.size() != 2) throw std::runtime_error("usage: tbs_peers distance SCAN SURFACE [options]");
  tbs::ScanReadOptions read;
  read.max_points = 20'000'000;
  const tbs::Scan scan = tbs::read_scan(args[0], read);
  const std::string ext = std::filesystem::path(args[1]).extension().string();
  const double size = model_size(scan.positions);
  TriMesh mesh;
  if (ext == ".tbs") {
    mesh = spline_mesh(args[1], chordal);
  } else {
    // Finer grids until the chordal deviation is within the tolerance (or 2,400 x 2,400).
    const Handle(Geom_Surface) surface = read_brep_surface(args[1]);
    for (int r = resolution;; r *= 2) {
      mesh = grid_mesh(surface, r);
      if (mesh.chordal_deviation <= chordal * size || 2 * r > 2400) break;
    }
  }

  std::vector<K::Triangle_3> triangles;
  triangles.reserve(mesh.faces.size());
  auto p3 = [](const tbs::Point3& p) { return K::Point_3(p.x(), p.y(), p.z()); };
  for (const auto& f : mesh.faces)
    triangles.emplace_back(p3(mesh.positions[f[0]]), p3(mesh.positions[f[1]]), p3(mesh.positions[f[2]]));
  using Primitive = CGAL::AABB_triangle_primitive<K, std::vector<K::Triangle_3>::const_iterator>;
  CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>> tree(triangles.begin(), triangles.end());
  tree.accelerate_distance_queries();

  const auto& points = scan.positions;
  std::vector<double> d(points.size());
  tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) {
    d[i] = std::sqrt(tree.squared_distance(p3(points[i])));
  });
  const double n = static_cast<double>(points.size());
  if (!dump.empty()) {  // x y distance/size per point, for plots
    std::FILE* out = std::fopen(dump.c_str(), "w");
    if (!out) throw std::runtime_error(dump + ": cannot write");
    for (std::size_t i = 0; i < points.size(); ++i)
      std::fprintf(out, "%.6g %.6g %.4e\n", points[i].x(), points[i].y(), d[i] / size);
    std::fclose(out);
  }
  double max = 0, sum = 0, sum2 = 0;
  for (double x : d) {
    max = std::max(max, x);
    sum += x;
    sum2 += x * x;
  }
  std::printf(
      "{\"points\": %zu, \"model_size\": %.9g, \"max\": %.6e, \"rms\": %.6e, \"mean\": %.6e, "
      "\"max_abs\": %.6e, \"rms_abs\": %.6e, \"mesh_triangles\": %zu, \"chordal_deviation\": %.3e, "
      "\"tessellation\": \"%s\"}\n",
      points.size(), size, max / size, std::sqrt(sum2 / n) / size, sum / n / size, max, std::sqrt(sum2 / n),
      mesh.faces.size(), mesh.chordal_deviation / size, mesh.how.c_str());
  return 0;
}

int points(std::vector<std::string> args) {
  if (args.size() != 2) throw std::runtime_error("usage: tbs_peers points SCAN OUT.xyz");
  tbs::ScanReadOptions read;
  read.max_points = 20'000'000;
  const tbs::Scan scan = tbs::read_scan(args[0], read);
  const std::string tmp = args[1] + ".tmp";
  std::FILE* out = std::fopen(tmp.c_str(), "w");
  if (!out) throw std::runtime_error(args[1] + ": cannot write");
  for (const auto& p : scan.positions) std::fprintf(out, "%.9g %.9g %.9g\n", p.x(), p.y(), p.z());
  if (std::fclose(out) != 0) throw std::runtime_error(args[1] + ": cannot write");
  std::filesystem::rename(tmp, args[1]);
  return 0;
}

int plate(std::vector<std::string> args) {
  const int constraints = std::stoi(arg_value(args, "--constraints", "400"));
  const double tolerance = std::stod(arg_value(args, "--tolerance", "1e-3"));
  const int max_degree = std::stoi(arg_value(args, "--max-degree", "8"));
  const int max_segments = std::stoi(arg_value(args, "--max-segments", "64"));
  const int criterion = std::stoi(arg_value(args, "--criterion", "-1"));
  if (args.size() != 2) throw std::runtime_error("usage: tbs_peers plate SCAN OUT.brep [options]");
  tbs::ScanReadOptions read;
  read.max_points = 20'000'000;
  const tbs::Scan scan = tbs::read_scan(args[0], read);
  const double size = model_size(scan.positions), tol3d = tolerance * size;
  // A random sample (fixed seed): a stride would alias with the row order of a gridded scan.
  std::vector<std::size_t> order(scan.positions.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::shuffle(order.begin(), order.end(), std::mt19937(1));
  order.resize(std::min<std::size_t>(order.size(), static_cast<std::size_t>(std::max(constraints, 3))));

  const auto start = std::chrono::steady_clock::now();
  // Degree 3, 15 points per curve, 2 iterations (OpenCASCADE's defaults); tolerances scaled to
  // the model.
  GeomPlate_BuildPlateSurface build(3, 15, 2, 1e-5, tol3d, 0.01, 0.1, Standard_False);
  int used = 0;
  for (const std::size_t i : order) {
    const auto& p = scan.positions[i];
    build.Add(new GeomPlate_PointConstraint(gp_Pnt(p.x(), p.y(), p.z()), 0, tol3d));
    ++used;
  }
  build.Perform();
  if (!build.IsDone()) throw std::runtime_error("GeomPlate_BuildPlateSurface failed");
  const double plate_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  GeomPlate_MakeApprox approx(build.Surface(), tol3d, max_segments, max_degree, 10 * tol3d, criterion);
  const Handle(Geom_BSplineSurface) surface = approx.Surface();
  if (surface.IsNull()) throw std::runtime_error("GeomPlate_MakeApprox gave no surface");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const TopoDS_Face face = BRepBuilderAPI_MakeFace(surface, 1e-7 * size);
  const std::string tmp = args[1] + ".tmp";
  if (!BRepTools::Write(face, tmp.c_str())) throw std::runtime_error(args[1] + ": cannot write");
  std::filesystem::rename(tmp, args[1]);
  std::printf(
      "{\"constraints\": %d, \"poles_u\": %d, \"poles_v\": %d, \"degree_u\": %d, \"degree_v\": %d, "
      "\"approx_error\": %.3e, \"plate_seconds\": %.3f, \"seconds\": %.3f}\n",
      used, surface->NbUPoles(), surface->NbVPoles(), surface->UDegree(), surface->VDegree(),
      approx.ApproxError() / size, plate_seconds, seconds);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (!args.empty() && args[0] == "plate") return plate({args.begin() + 1, args.end()});
    if (!args.empty() && args[0] == "distance") return distance({args.begin() + 1, args.end()});
    if (!args.empty() && args[0] == "points") return points({args.begin() + 1, args.end()});
    std::cerr << "usage: tbs_peers plate|distance|points ... (see bench/peers.cpp)\n";
    return 2;
  } catch (const Standard_Failure& e) {
    std::cerr << "tbs_peers: OpenCASCADE: " << e.GetMessageString() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "tbs_peers: " << e.what() << "\n";
  }
  return 1;
}
