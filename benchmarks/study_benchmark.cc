// Speed of the Section 6 studies (González et al.): one full study case (simulate + every
// estimator of the study + delta-method standard errors) at the paper's smallest and largest
// N, with and without covariance; and a small parallel study. The full Section 6.1 study
// is 30 x 300 cases; docs/study.md gives its measured wall time.
#include <benchmark/benchmark.h>

#include "ctid/study/paper_study.h"

namespace {

ctid::StudyOptions case_options(ctid::StudyKind kind, bool covariance, int estimator) {
  ctid::StudyOptions options = ctid::StudyOptions::paper(kind);
  options.compute_covariance = covariance;
  options.estimators = {options.active_estimators().at(static_cast<size_t>(estimator))};
  return options;
}

// Args: kind (0 open, 1 closed), size index, covariance (0/1), estimator index in the study.
void BM_StudyCase(benchmark::State& state) {
  const auto kind = state.range(0) == 0 ? ctid::StudyKind::open_loop : ctid::StudyKind::closed_loop;
  const ctid::StudyOptions options =
      case_options(kind, state.range(2) != 0, static_cast<int>(state.range(3)));
  const int size_index = static_cast<int>(state.range(1));
  int run = 0;
  long samples = 0;
  long iterations = 0;
  for (auto _ : state) {
    const auto records = ctid::run_study_case(options, size_index, run++ % options.runs);
    samples += records.front().samples;
    iterations += records.front().iterations;
    benchmark::DoNotOptimize(records);
  }
  state.SetLabel(ctid::to_string(kind) + " " + ctid::to_string(options.estimators.front()));
  state.SetItemsProcessed(state.iterations());
  state.counters["N"] = static_cast<double>(samples) / static_cast<double>(state.iterations());
  state.counters["iterations"] =
      static_cast<double>(iterations) / static_cast<double>(state.iterations());
}

// Open loop: size index 0 (N = 2000), 17 (~ 1e4) and 29 (N = 1e5); SRIVC (0), additive (1).
BENCHMARK(BM_StudyCase)
    ->ArgsProduct({{0}, {0, 17, 29}, {0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(0.5);
// Closed loop: N = 500, ~1e4 (index 31) and 123036; SRIVC, CLSRIVC, additive.
BENCHMARK(BM_StudyCase)
    ->ArgsProduct({{1}, {0, 31, 49}, {1}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(0.5);

// A whole small study on every core: 4 sizes x 8 runs, open loop, both estimators.
void BM_SmallOpenLoopStudy(benchmark::State& state) {
  ctid::StudyOptions options = ctid::StudyOptions::paper(ctid::StudyKind::open_loop);
  options.sizes = 4;
  options.runs = 8;
  options.max_samples = 10000;
  for (auto _ : state) benchmark::DoNotOptimize(ctid::run_study(options));
  state.SetItemsProcessed(state.iterations() * options.sizes * options.runs * 2);
}
BENCHMARK(BM_SmallOpenLoopStudy)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
