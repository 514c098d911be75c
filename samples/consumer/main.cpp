// A program outside the tbs source tree that only reads and evaluates splines, as a CAM tool
// would: it links tbs::spline alone (samples/consumer/CMakeLists.txt).
//
//   consumer FILE.tbs
//
// Reads the spline, evaluates it at the centroid of every domain triangle with the fast
// Evaluator and at a few of them with the plain-recursion reference evaluator, and runs the
// shape check (folds, stretch). Exit status 0 when both evaluators agree, 1 otherwise or on
// an error (the message says what and where).
#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/io.h>
#include <tbs/reference.h>
#include <tbs/shape_check.h>

#include <algorithm>
#include <cstdio>
#include <string>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer FILE.tbs\n");
    return 1;
  }
  try {
    const tbs::SplineFile file = tbs::read_tbs(argv[1]);
    const tbs::Spline& spline = file.spline;
    const tbs::Domain& domain = spline.domain();
    const tbs::Evaluator evaluator(spline);
    std::printf("%s: degree %d, %d domain triangles, units %s\n", argv[1], spline.degree(),
                domain.triangle_count(), file.units.c_str());

    // The fast evaluator at every centroid; the reference at every 16th (it visits every
    // triangle for each point).
    double largest_difference = 0, largest_value = 0;
    int compared = 0;
    for (int t = 0; t < domain.triangle_count(); ++t) {
      const auto& tri = domain.triangle(t);
      const tbs::Point2 c = (domain.vertex(tri[0]) + domain.vertex(tri[1]) + domain.vertex(tri[2])) / 3;
      const tbs::Point3 fast = evaluator.value(c);
      largest_value = std::max(largest_value, fast.cwiseAbs().maxCoeff());
      if (t % 16 == 0) {
        const tbs::Point3 slow = tbs::reference::value_degree_n(spline, tbs::Perturbation::standard(c));
        largest_difference = std::max(largest_difference, (fast - slow).norm());
        ++compared;
      }
    }
    std::printf("evaluated at %d centroids; at %d of them the reference evaluator differs by %.2e "
                "(values up to %.3g)\n",
                domain.triangle_count(), compared, largest_difference, largest_value);

    const tbs::ShapeCheck shape = tbs::check_shape(spline, evaluator);
    std::printf("shape: %zu folded triangles, max_stretch %.3g\n", shape.folded_triangles.size(),
                shape.max_stretch);
    return largest_difference <= 1e-9 * std::max(1.0, largest_value) ? 0 : 1;
  } catch (const tbs::Error& e) {  // InvalidInput, IoError: each says what to do
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 1;
  }
}
