// A program outside the tbs source tree that uses the installed library: it fits a generated
// point set, evaluates and tessellates the spline, and writes a STEP file.
//
//   fit_consumer [OUT.step]
//
// Built by samples/fit_consumer/CMakeLists.txt against an installed tbs (find_package(tbs)); the
// Install.ConsumerUsesTheInstalledPackage test installs tbs into a temporary prefix, builds
// this program and runs it. Exit status 0 when the fit, the evaluation and the export agree
// with the known surface.
#include <tbs/cad_export.h>
#include <tbs/cad_regions.h>
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/fit.h>
#include <tbs/scan.h>
#include <tbs/tessellate.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace {

// The known surface, millimetres, over (u, v) in [0, 1]^2.
tbs::Point3 surface(double u, double v) {
  return {100 * u, 80 * v, 12 * std::sin(3 * u) * std::cos(2 * v)};
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "fit_consumer.step";
  try {
    // 1. Points with parameters (a scan would come from tbs::read_scan()).
    tbs::Scan scan;
    const int n = 60;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double u = (i + 0.5) / n, v = (j + 0.5) / n;
        scan.positions.push_back(surface(u, v));
        scan.uv.emplace_back(u, v);
      }

    // 2. Fit, reporting progress (a GUI would update a progress bar here).
    tbs::FitOptions options;
    options.degree = 3;
    options.tolerance = 1e-4;
    options.progress = [](const tbs::FitProgress& p) {
      std::printf("  %-8s %3.0f %%  %s\n", p.stage.c_str(), 100 * p.fraction, p.message.c_str());
    };
    const tbs::FitResult fit = tbs::fit(scan, options);
    std::printf("fit: %zu points, %zu domain triangles, %zu control points, max error %.2e, %s\n",
                fit.report.points, fit.report.domain_triangles, fit.report.control_points,
                fit.report.max_error, fit.report.converged ? "converged" : "not converged");

    // 3. Evaluate inside the domain and compare with the known surface.
    const tbs::Evaluator evaluator(fit.spline);
    const tbs::Point3 p = evaluator.value(tbs::Point2(0.5, 0.5));
    const double miss = (p - surface(0.5, 0.5)).norm();
    std::printf("F(0.5, 0.5) = (%.4f, %.4f, %.4f), %.2e mm from the known surface\n", p.x(), p.y(), p.z(),
                miss);

    // 4. Tessellate.
    const tbs::Mesh mesh = tbs::tessellate(fit.spline);
    std::printf("mesh: %zu vertices, %zu triangles\n", mesh.positions.size(), mesh.faces.size());

    // 5. Region faces (one trimmed B-spline face per smooth region), written as STEP.
    tbs::CadRegionOptions region_options;
    region_options.tolerance = 1e-5;
    const tbs::CadRegions regions = tbs::make_cad_regions(fit.spline, region_options);
    tbs::CadExportOptions export_options;
    export_options.product_name = "fit_consumer sample";
    const tbs::CadExportReport step = tbs::write_step(out, regions, export_options);
    std::printf("%s: %zu faces, %zu shell(s), %zu free edges\n", out.c_str(), step.faces, step.shells,
                step.free_edges);

    const bool ok = fit.report.converged && miss < 0.02 && !mesh.faces.empty() && step.shells == 1;
    return ok ? 0 : 1;
  } catch (const tbs::Error& e) {  // InvalidInput, IoError, SolverError: each says what to do
    std::fprintf(stderr, "fit_consumer: %s\n", e.what());
    return 1;
  }
}
