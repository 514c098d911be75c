// libFuzzer harness for the .tbs parser (tbs::parse_tbs). An accepted file must survive the
// round trip format -> parse unchanged, and its spline must evaluate at the centroid of a domain
// triangle. Anything but tbs::InvalidInput is a bug.

#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/io.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "tbs_fuzzer: accepted file breaks an invariant: %s\n", what);
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  tbs::SplineFile file;
  try {
    file = tbs::parse_tbs(text, "fuzz.tbs");
  } catch (const tbs::InvalidInput& e) {
    if (std::getenv("TBS_FUZZ_VERBOSE")) std::fprintf(stderr, "tbs_fuzzer: refused: %s\n", e.what());
    return 0;
  }
  const std::string again = tbs::format_tbs(file);
  const tbs::SplineFile reread = tbs::parse_tbs(again, "round-trip.tbs");
  check(tbs::format_tbs(reread) == again, "format/parse round trip");

  if (std::getenv("TBS_FUZZ_VERBOSE")) std::fprintf(stderr, "tbs_fuzzer: accepted\n");
  const tbs::Spline& spline = file.spline;
  // Keep each input cheap: the evaluator's graph grows quickly with the domain.
  if (spline.domain().triangle_count() > 64) return 0;
  const tbs::Evaluator evaluator(spline);
  const auto& tri = spline.domain().triangles().front();
  const auto& v = spline.domain().vertices();
  const tbs::Point2 centroid = (v[tri[0]] + v[tri[1]] + v[tri[2]]) / 3.0;
  try {
    const tbs::Point3 p = evaluator.value(centroid);
    check(p.allFinite(), "finite value at a triangle centroid");
  } catch (const tbs::OutsideDomain&) {
    // A centroid of a sliver can round outside its own triangle; not a parser bug.
  }
  return 0;
}
