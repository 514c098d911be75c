#include <tbs/errors.h>
#include <tbs/evaluator.h>
#include <tbs/io.h>

#include "random_spline.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>

namespace tbs {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

SplineFile sample(int n = 3, bool features = true) {
  test::GridOptions o;
  o.nx = o.ny = 4;
  if (features) o.feature_column = 2;
  SplineFile f{test::random_spline(n, o, 41), "mm", R"({"source":"io_test"})"};
  return f;
}

fs::path temp_dir() {
  const fs::path p = fs::temp_directory_path() / ("tbs_io_test_" + std::to_string(::getpid()));
  fs::create_directories(p);
  return p;
}

TEST(Io, WriteReadEvaluateIsBitIdentical) {
  for (int n : {1, 2, 3, 4, 5}) {
    const SplineFile f = sample(n);
    const fs::path path = temp_dir() / "a.tbs";
    write_tbs(path.string(), f);
    const SplineFile g = read_tbs(path.string());
    EXPECT_EQ(g.spline.knots(), f.spline.knots());
    EXPECT_EQ(g.spline.control_points(), f.spline.control_points());
    EXPECT_EQ(g.spline.control_point_map(), f.spline.control_point_map());
    EXPECT_EQ(g.spline.domain().vertices(), f.spline.domain().vertices());
    EXPECT_EQ(g.spline.domain().feature_edges(), f.spline.domain().feature_edges());
    EXPECT_EQ(g.units, "mm");
    EXPECT_EQ(json::parse(g.metadata_json)["source"], "io_test");
    const Evaluator a(f.spline), b(g.spline);
    for (const auto& u : test::random_domain_points(f.spline.domain(), 1000, 1)) {
      const SurfacePoint x = a.evaluate(u), y = b.evaluate(u);
      ASSERT_EQ(x.position, y.position);
      ASSERT_EQ(x.du, y.du);
      ASSERT_EQ(x.dv, y.dv);
    }
    EXPECT_EQ(format_tbs(g), format_tbs(f));
  }
}

TEST(Io, StoredPointsRoundTripExactly) {
  SplineFile f = sample(2);
  const auto uv = test::random_domain_points(f.spline.domain(), 50, 7);
  const Evaluator ev(f.spline);
  for (const auto& u : uv) {
    f.points.push_back(ev.value(u) + Point3(1e-3 / 3, -2e-7, 0.1));
    f.point_parameters.push_back(u);
  }
  const fs::path path = temp_dir() / "points.tbs";
  write_tbs(path.string(), f);
  const SplineFile g = read_tbs(path.string());
  EXPECT_EQ(g.points, f.points);
  EXPECT_EQ(g.point_parameters, f.point_parameters);
  // Without points the field is not written; with mismatched sizes nothing is.
  EXPECT_EQ(format_tbs(sample(2)).find("\"points\""), std::string::npos);
  f.point_parameters.pop_back();
  EXPECT_THROW(format_tbs(f), InvalidInput);
  f.point_parameters.push_back(uv.back());
  f.points[3].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(format_tbs(f), InvalidInput);
}

TEST(Io, AtomicOutputLeavesNothingBehindOnFailure) {
  const fs::path dir = temp_dir() / "atomic";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path target = dir / "x.tbs";
  write_file_atomic(target.string(), "good");
  {
    AtomicOutput out(target.string());
    std::ofstream(out.temp_path()) << "partial";
    // no commit: simulated failure
  }
  EXPECT_EQ(read_file(target.string()), "good");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  EXPECT_THROW(write_file_atomic((dir / "missing" / "x.tbs").string(), "x"), IoError);
  EXPECT_THROW(write_file_atomic(dir.string(), "x"), IoError);
}

// A symbolic link is written through: its target gets the data, the link stays a link, and no
// temporary file is left beside either.
TEST(Io, AtomicOutputWritesThroughASymbolicLink) {
  const fs::path dir = temp_dir() / "link";
  fs::remove_all(dir);
  fs::create_directories(dir / "shared");
  const fs::path real = dir / "shared" / "x.tbs", link = dir / "x.tbs";
  write_file_atomic(real.string(), "old");
  fs::create_symlink(fs::path("shared") / "x.tbs", link);
  write_file_atomic(link.string(), "new");
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(read_file(real.string()), "new");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);  // shared/, x.tbs
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "shared"), fs::directory_iterator()), 1);
  // A link to a device is refused, as the device is.
  const fs::path to_null = dir / "null.tbs";
  fs::create_symlink("/dev/null", to_null);
  EXPECT_THROW(write_file_atomic(to_null.string(), "x"), IoError);
  EXPECT_TRUE(fs::is_symlink(to_null));
}

// A process killed while writing leaves the earlier file as it was and no temporary file.
TEST(Io, SignalsRemoveTemporaryFiles) {
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    const fs::path dir = temp_dir() / ("signal" + std::to_string(sig));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path target = dir / "x.step";
    write_file_atomic(target.string(), "good");
    int ready[2];
    ASSERT_EQ(::pipe(ready), 0);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      remove_outputs_on_signal();
      AtomicOutput a(target.string()), b((dir / "y.glb").string());
      std::ofstream(a.temp_path()) << "partial";
      std::ofstream(b.temp_path()) << "partial";
      (void)!::write(ready[1], "r", 1);
      for (;;) ::pause();
    }
    char c = 0;
    ASSERT_EQ(::read(ready[0], &c, 1), 1);
    ::close(ready[0]);
    ::close(ready[1]);
    EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 3);  // x.step + 2 temporaries
    ::kill(child, sig);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "status " << status;
    EXPECT_EQ(read_file(target.string()), "good");
    EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1) << "signal " << sig;
  }
}

TEST(Io, ReadErrors) {
  EXPECT_THROW(read_tbs("/nonexistent/file.tbs"), IoError);
  EXPECT_THROW(read_tbs(temp_dir().string()), IoError);
}

// Each malformed file is rejected with InvalidInput whose message names the problem.
struct Bad {
  const char* name;
  std::function<void(json&)> edit;  // applied to a valid file's JSON
  const char* expect;               // substring of the message
};

TEST(Io, RejectsMalformedFiles) {
  const SplineFile f = sample(3);
  const std::string text = format_tbs(f);
  const json good = json::parse(text);
  const std::vector<Bad> cases = {
      {"missing control points", [](json& j) { j.erase("control_points"); }, "control_points: missing field"},
      {"missing degree", [](json& j) { j.erase("degree"); }, "degree: missing field"},
      {"too few control points", [](json& j) { j["control_points"].erase(0); }, "control_points: expected"},
      {"null coordinate (NaN)", [](json& j) { j["control_points"][5][1] = nullptr; }, "control_points[5][1]"},
      {"string coordinate", [](json& j) { j["domain"]["vertices"][2][0] = "abc"; }, "domain.vertices[2][0]: expected a number"},
      {"clockwise triangle", [](json& j) { std::swap(j["domain"]["triangles"][3][1], j["domain"]["triangles"][3][2]); }, "triangle 3"},
      {"index out of range", [](json& j) { j["domain"]["triangles"][1][0] = 100000; }, "domain.triangles[1][0]: vertex index 100000 out of range"},
      {"negative index", [](json& j) { j["control_point_map"][0][0] = -1; }, "control point map: triangle 0, beta (3,0,0): index -1 out of range"},
      {"inconsistent map", [](json& j) { std::swap(j["control_point_map"][10][0], j["control_point_map"][10][1]); }, "control point map: triangle"},
      {"degenerate knots", [](json& j) {
         // Sub-knot t_{a,1} on the segment between the other two corners of triangle 0.
         const auto& tri = j["domain"]["triangles"][0];
         const auto& b = j["domain"]["vertices"][tri[1].get<int>()];
         const auto& c = j["domain"]["vertices"][tri[2].get<int>()];
         j["sub_knots"][tri[0].get<int>()][0] = {0.5 * (b[0].get<double>() + c[0].get<double>()),
                                                 0.5 * (b[1].get<double>() + c[1].get<double>())};
       }, "knot conditions"},
      {"wrong knot count", [](json& j) { j["sub_knots"][4].erase(0); }, "sub_knots[4]: expected 3 entries"},
      {"degree zero", [](json& j) { j["degree"] = 0; }, "degree 0 is not supported"},
      {"fractional degree", [](json& j) { j["degree"] = 2.5; }, "degree: expected an integer"},
      {"future version", [](json& j) { j["version"] = 99; }, "version 99 is not supported"},
      {"wrong format", [](json& j) { j["format"] = "stl"; }, "not a tbs spline file"},
      {"unknown unit", [](json& j) { j["units"] = "furlong"; }, "unknown unit"},
      {"boundary loops mismatch", [](json& j) { j["domain"]["boundary_loops"][0].erase(0); }, "boundary_loops"},
      {"feature on the boundary", [](json& j) { j["domain"]["feature_edges"].push_back(j["domain"]["boundary_loops"][0][0]); j["domain"]["feature_edges"].back() = {j["domain"]["boundary_loops"][0][0], j["domain"]["boundary_loops"][0][1]}; }, "feature edge"},
      {"metadata not an object", [](json& j) { j["metadata"] = 3; }, "metadata"},
      {"top level array", [](json& j) { j = json::array({1, 2}); }, "expected a JSON object"},
      {"points without parameters", [](json& j) { j["points"] = {{"positions", json::array({{1, 2, 3}})}}; }, "points.parameters: missing field"},
      {"fewer parameters than points", [](json& j) { j["points"] = {{"positions", json::array({{1, 2, 3}, {4, 5, 6}})}, {"parameters", json::array({{0.1, 0.2}})}}; }, "points.parameters: expected 2 entries, got 1"},
      {"point with two coordinates", [](json& j) { j["points"] = {{"positions", json::array({{1, 2}})}, {"parameters", json::array({{0.1, 0.2}})}}; }, "points.positions[0]: expected 3 entries"},
      {"points not an object", [](json& j) { j["points"] = json::array(); }, "points: expected an object"},
  };
  for (const auto& c : cases) {
    json j = good;
    c.edit(j);
    try {
      parse_tbs(j.dump(), "bad.tbs");
      ADD_FAILURE() << c.name << ": accepted";
    } catch (const InvalidInput& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(c.expect), std::string::npos) << c.name << ": " << msg;
      EXPECT_EQ(msg.rfind("bad.tbs: ", 0), 0u) << c.name << ": " << msg;
    }
  }
}

TEST(Io, RejectsBrokenJsonText) {
  const std::string text = format_tbs(sample(2));
  const std::vector<std::pair<std::string, std::string>> cases = {
      {text.substr(0, text.size() / 2), "truncated"},
      {"", "truncated"},
      {"{\"format\": \"tbs\", \"version\": 1, \"degree\": NaN}", "not valid JSON"},
      {"{\"format\": \"tbs\", \"version\": 1, \"degree\": 3, \"domain\": {\"vertices\": [[1e400, 0]]}}", "number overflow"},
      {"{\"format\": \"tbs\", \"version\": 1, \"degree\": 3, \"domain\": {\"vertices\": [[1.1e308, 0]]}}", "larger than 1e30"},
      {std::string("\x89PNG\r\n\x1a\n\0\0", 10), "not valid JSON"},
  };
  for (const auto& [t, expect] : cases) {
    try {
      parse_tbs(t, "broken.tbs");
      ADD_FAILURE() << "accepted: " << t.substr(0, 40);
    } catch (const InvalidInput& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(expect), std::string::npos) << msg;
      for (char ch : msg)
        EXPECT_TRUE(ch >= 0x20 && ch < 0x7f) << "unprintable byte in: " << msg;
    }
  }
}

// A scan handed to a command that reads splines: say so, and what to do.
TEST(Io, AScanInsteadOfASplineSaysToFitItFirst) {
  for (const char* name : {"scan.ply", "SCAN.STL", "points.xyz"}) {
    try {
      parse_tbs("ply\nformat ascii 1.0\n", name);
      ADD_FAILURE() << name << ": accepted";
    } catch (const InvalidInput& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("not a .tbs spline but a scan"), std::string::npos) << msg;
      EXPECT_NE(msg.find(std::string("tbs fit ") + name + " -o OUT.tbs"), std::string::npos) << msg;
    }
  }
  // Valid JSON in a file with a scan's extension is still read as a spline.
  EXPECT_NO_THROW(parse_tbs(format_tbs(sample(2)), "spline.txt"));
}

TEST(Io, CanSkipTheKnotCheck) {
  json j = json::parse(format_tbs(sample(2)));
  const auto& tri = j["domain"]["triangles"][0];
  const auto b = j["domain"]["vertices"][tri[1].get<int>()];
  const auto c = j["domain"]["vertices"][tri[2].get<int>()];
  j["sub_knots"][tri[0].get<int>()][0] = {0.5 * (b[0].get<double>() + c[0].get<double>()),
                                          0.5 * (b[1].get<double>() + c[1].get<double>())};
  EXPECT_THROW(parse_tbs(j.dump()), InvalidInput);
  ReadOptions ro;
  ro.check_knots = false;
  EXPECT_NO_THROW(parse_tbs(j.dump(), "x", ro));
}

// The JSON Schema in docs/ accepts what we write (checked by Debian's python3-jsonschema).
TEST(Io, WrittenFilesMatchTheJsonSchema) {
  const fs::path path = temp_dir() / "schema.tbs";
  write_tbs(path.string(), sample(3));
  const std::string schema = std::string(TBS_SOURCE_DIR) + "/docs/tbs.schema.json";
  const std::string cmd =
      "/usr/bin/python3 -c \"import json,sys,jsonschema; "
      "jsonschema.validate(json.load(open(sys.argv[1])), json.load(open(sys.argv[2])))\" '" +
      path.string() + "' '" + schema + "' 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  // With stored points too.
  {
    SplineFile f = sample(3);
    f.points = {Point3(1, 2, 3), Point3(4, 5, 6)};
    f.point_parameters = {Point2(0.1, 0.2), Point2(0.3, 0.4)};
    const fs::path with_points = temp_dir() / "schema_points.tbs";
    write_tbs(with_points.string(), f);
    const std::string c2 = "/usr/bin/python3 -c \"import json,sys,jsonschema; "
                           "jsonschema.validate(json.load(open(sys.argv[1])), json.load(open(sys.argv[2])))\" '" +
                           with_points.string() + "' '" + schema + "' 2>&1";
    EXPECT_EQ(std::system(c2.c_str()), 0) << c2;
  }
  // And rejects a file without control points.
  json j = json::parse(read_file(path.string()));
  j.erase("control_points");
  std::ofstream(path) << j.dump();
  EXPECT_NE(std::system((cmd + " > /dev/null").c_str()), 0);
}

}  // namespace
}  // namespace tbs

namespace tbs {
namespace {

// The example in docs/format.md is a valid file and evaluates as documented (degree 1:
// piecewise linear interpolation of the vertex control points).
TEST(Io, FormatDocumentExampleIsValid) {
  const std::string doc = read_file(std::string(TBS_SOURCE_DIR) + "/docs/format.md");
  const size_t start = doc.find("```json\n");
  ASSERT_NE(start, std::string::npos);
  const size_t end = doc.find("```", start + 8);
  const SplineFile f = parse_tbs(doc.substr(start + 8, end - start - 8), "format.md");
  const Evaluator ev(f.spline);
  EXPECT_LT((ev.value({1, 1}) - Point3(10, 10, 1)).norm(), 1e-12);
  EXPECT_LT((ev.value({0.5, 0.5}) - Point3(5, 5, 0.5)).norm(), 1e-12);
  EXPECT_LT((ev.value({0.5, 0.25}) - Point3(5, 2.5, 0.25)).norm(), 1e-12);
}

}  // namespace
}  // namespace tbs
