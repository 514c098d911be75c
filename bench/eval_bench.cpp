// Evaluation speed: points per second for value + both partial derivatives on a
// 1,012-triangle domain, degrees 2-4, 1 and 2 threads, shared graph vs plain recursion.
//   build/bench/tbs_eval_bench --benchmark_counters_tabular=true

#include <tbs/evaluator.h>
#include <tbs/knots.h>

#include <benchmark/benchmark.h>

#include <random>

namespace {

tbs::Spline make_spline(int degree) {
  const int nx = 23, ny = 22;  // 2 * 23 * 22 = 1,012 triangles
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> uni(-0.25, 0.25);
  std::vector<tbs::Point2> v;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      tbs::Point2 p(double(i) / nx, double(j) / ny);
      if (i > 0 && j > 0 && i < nx && j < ny) p += tbs::Point2(uni(rng) / nx, uni(rng) / ny);
      v.push_back(p);
    }
  std::vector<std::array<int, 3>> t;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 2, d = a + nx + 1;
      t.push_back({a, b, c});
      t.push_back({a, c, d});
    }
  tbs::Domain dom(v, t);
  auto knots = tbs::default_knots(dom, degree);
  tbs::Spline s = tbs::Spline::with_canonical_map(degree, std::move(dom), std::move(knots));
  std::uniform_real_distribution<double> cp(-1, 1);
  for (auto& c : s.control_points()) c = tbs::Point3(cp(rng), cp(rng), cp(rng));
  return s;
}

std::vector<tbs::Point2> points(size_t n) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<tbs::Point2> p(n);
  for (auto& q : p) q = tbs::Point2(uni(rng), uni(rng));
  return p;
}

// Args: degree, threads, mode (0 graph, 1 plain recursion).
void BM_Evaluate(benchmark::State& state) {
  const int degree = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  const auto mode = state.range(2) == 0 ? tbs::EvalMode::Graph : tbs::EvalMode::Recursion;
  const tbs::Spline s = make_spline(degree);
  const tbs::Evaluator ev(s, mode);
  const auto pts = points(mode == tbs::EvalMode::Graph ? 200000 : 20000);
  std::vector<tbs::Point3> pos(pts.size());
  std::vector<tbs::Vector3> du(pts.size()), dv(pts.size());
  for (auto _ : state) {
    ev.evaluate_batch(pts, pos, du, dv, {}, threads);
    benchmark::DoNotOptimize(pos.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * pts.size()));
  state.counters["nodes"] = static_cast<double>(ev.node_count());
  state.SetLabel(std::string(mode == tbs::EvalMode::Graph ? "graph" : "recursion") +
                 " n=" + std::to_string(degree) + " threads=" + std::to_string(threads));
}

BENCHMARK(BM_Evaluate)
    ->ArgNames({"degree", "threads", "recursion"})
    ->ArgsProduct({{2, 3, 4}, {1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);

// Building the evaluator (graph + spatial index) for the same domain.
void BM_BuildEvaluator(benchmark::State& state) {
  const tbs::Spline s = make_spline(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    tbs::Evaluator ev(s);
    benchmark::DoNotOptimize(ev.node_count());
  }
}
BENCHMARK(BM_BuildEvaluator)->ArgName("degree")->DenseRange(2, 4)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
