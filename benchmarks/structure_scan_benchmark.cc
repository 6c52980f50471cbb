// The cost of choosing the structure (issue 11: a scan over 8 structures on N = 1e4 takes
// less than 3x one fit per structure). The Section 6.1 record (four modes, coloured noise,
// h = 0.05 s, N = 1e4); eight candidates: 1-4 modes and 2, 4, 6, 8 unfactored poles (zeros
// n - 1), each from the automatic start. BM_ScanEightStructures times scan_structures;
// BM_OneFitPerStructure times identify() of each candidate on the whole record, the
// reference. Each reports, as a counter, the time of the other in the same process, and
// scan_over_fits = scan time / fits time, the ratio the target bounds.
#include <chrono>
#include <vector>

#include <benchmark/benchmark.h>

#include "ctid/identification/identification.h"
#include "ctid/identification/structure_scan.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"
#include "support/paper_systems.h"

namespace {

ctid::SampledData record() {
  constexpr int n = 10000;
  const ctid::AdditiveModel truth = ctid::testing::open_loop_four_modes();
  const Eigen::VectorXd u = ctid::white_noise(n, 1.0, 1);
  const Eigen::VectorXd y =
      ctid::simulate(truth, u, 0.05) +
      ctid::colored_noise(ctid::testing::open_loop_noise_filter(), n, 0.02, 2);
  return ctid::SampledData(0.05, u, y);
}

std::vector<ctid::ModelStructure> candidates() {
  std::vector<ctid::ModelStructure> out;
  for (int k = 1; k <= 4; ++k) out.push_back(ctid::ModelStructure::modes(k));
  for (int poles = 2; poles <= 8; poles += 2) {
    out.push_back(ctid::ModelStructure::unfactored(poles, poles - 1));
  }
  return out;
}

double seconds_since(std::chrono::steady_clock::time_point begin) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
}

double scan_seconds(const ctid::SampledData& data) {
  const auto begin = std::chrono::steady_clock::now();
  const ctid::StructureScanResult r = ctid::scan_structures(data, candidates());
  benchmark::DoNotOptimize(r.recommended);
  return seconds_since(begin);
}

double fits_seconds(const ctid::SampledData& data) {
  const auto begin = std::chrono::steady_clock::now();
  for (const ctid::ModelStructure& s : candidates()) {
    const ctid::IdentificationResult r = ctid::identify(data, s);
    benchmark::DoNotOptimize(r.estimate.parameters.data());
  }
  return seconds_since(begin);
}

void BM_ScanEightStructures(benchmark::State& state) {
  const ctid::SampledData data = record();
  double scan = 0.0;
  for (auto _ : state) scan += scan_seconds(data);
  scan /= static_cast<double>(state.iterations());
  const double fits = fits_seconds(data);
  state.counters["fits_seconds"] = fits;
  state.counters["scan_over_fits"] = scan / fits;
}

void BM_OneFitPerStructure(benchmark::State& state) {
  const ctid::SampledData data = record();
  double fits = 0.0;
  for (auto _ : state) fits += fits_seconds(data);
  fits /= static_cast<double>(state.iterations());
  state.counters["scan_seconds"] = scan_seconds(data);
  state.counters["scan_over_fits"] = state.counters["scan_seconds"] / fits;
}

}  // namespace

BENCHMARK(BM_ScanEightStructures)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_OneFitPerStructure)->Unit(benchmark::kMillisecond)->Iterations(3);
