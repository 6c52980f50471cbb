// The delayed-feedback identification pieces on the informative record of
// tests/delayed_feedback/pipeline_test.cc (F, H of De Iuliis et al. 2017 Section 4,
// Δ = 0.5 s, δ = 50 ms, smooth multisine continued linearly, 30 s): step 1 by batch QR and by
// RLS, the two separations on the step-1 polynomials, one output-error refinement from a start
// 2 % off, and the whole pipeline. Time per call.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "ctid/delayed_feedback/identification.h"
#include "ctid/study/monte_carlo.h"
#include "support/de_iuliis_systems.h"

namespace {

ctid::DelayedFeedbackLoop paper_loop() { return ctid::test_support::paper_feedback_loop(); }

// Noise-free record of `duration` s: the tests' smooth multisine of `harmonics` lines of a
// `period` s fundamental through the paper's loop (support/de_iuliis_systems.h).
ctid::SampledData multisine_record(double duration, double period, int harmonics) {
  return ctid::test_support::feedback_record(paper_loop(), duration, period, harmonics);
}

// 30 s, 8 harmonics of 15 s (601 samples): the record of feedback_pipeline_test.cc.
const ctid::SampledData& record() {
  static const ctid::SampledData data = multisine_record(30.0, 15.0, 8);
  return data;
}

// 40 s, 12 harmonics of 20 s (801 samples): the record of feedback_noise_test.cc, whose lines
// 0.31 rad/s apart also excite F's resonance at 1.05 rad/s.
const ctid::SampledData& long_record() {
  static const ctid::SampledData data = multisine_record(40.0, 20.0, 12);
  return data;
}

// The same multisine over 4 and 6 periods (80 s, 120 s): bias and spread against the record
// length.
// Record 4 is broadband: 40 s, 40 lines of 20 s (up to 12.6 rad/s), where e^{-Δs} is far
// from 1 and F and H separate better (Cramér-Rao deviations ~4x smaller at the same NSR).
const ctid::SampledData& monte_carlo_record(std::int64_t which) {
  static const ctid::SampledData eighty = multisine_record(80.0, 20.0, 12);
  static const ctid::SampledData hundred_twenty = multisine_record(120.0, 20.0, 12);
  static const ctid::SampledData broadband = multisine_record(40.0, 20.0, 40);
  switch (which) {
    case 0:
      return record();
    case 1:
      return long_record();
    case 2:
      return eighty;
    case 3:
      return hundred_twenty;
    default:
      return broadband;
  }
}

const ctid::FeedbackRegression& regression() {
  static const ctid::FeedbackRegression reg = [] {
    ctid::FeedbackRegressorOptions o;
    o.filter = ctid::RegressorFilter::linear_integral_filter;
    o.initial_condition_terms = true;
    return ctid::build_feedback_regression(record(), 3, 3, 0.5, o);
  }();
  return reg;
}

void BM_Step1Batch(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(ctid::estimate_closed_loop_batch(regression()));
}
BENCHMARK(BM_Step1Batch)->Unit(benchmark::kMillisecond);

void BM_Step1Rls(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(ctid::estimate_closed_loop_recursive(regression()));
}
BENCHMARK(BM_Step1Rls)->Unit(benchmark::kMillisecond);

void BM_SeparationKronecker(benchmark::State& state) {
  // Exact polynomials (the root splits all exist), so the timing covers every start.
  const ctid::DelayedFeedbackLoop loop = paper_loop();
  for (auto _ : state)
    benchmark::DoNotOptimize(
        ctid::separate_kronecker(loop.alpha(), loop.beta(), loop.gamma(), 3, 3));
}
BENCHMARK(BM_SeparationKronecker)->Unit(benchmark::kMillisecond);

void BM_SeparationGcd(benchmark::State& state) {
  const ctid::DelayedFeedbackLoop loop = paper_loop();
  for (auto _ : state)
    benchmark::DoNotOptimize(
        ctid::separate_approximate_gcd(loop.alpha(), loop.beta(), loop.gamma(), 3, 3));
}
BENCHMARK(BM_SeparationGcd)->Unit(benchmark::kMicrosecond);

void BM_OutputErrorRefinement(benchmark::State& state) {
  Eigen::VectorXd start = ctid::loop_parameters(paper_loop());
  for (Eigen::Index i = 0; i < start.size(); ++i) start(i) *= (i % 2 == 0) ? 0.98 : 1.02;
  ctid::OutputErrorOptions o;
  o.hold = ctid::Hold::first_order_hold;
  const ctid::DelayedFeedbackLoop loop = ctid::loop_from_parameters(start, 3, 3, 0.5);
  for (auto _ : state) benchmark::DoNotOptimize(ctid::refine_output_error(record(), loop, o));
}
BENCHMARK(BM_OutputErrorRefinement)->Unit(benchmark::kMillisecond)->Iterations(2);

void BM_Pipeline(benchmark::State& state) {
  ctid::FeedbackIdentificationOptions o;
  o.output_error.hold = ctid::Hold::first_order_hold;
  for (auto _ : state)
    benchmark::DoNotOptimize(ctid::identify_delayed_feedback(record(), 3, 3, 0.5, o));
}
BENCHMARK(BM_Pipeline)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

// Monte Carlo of consistency: M noisy copies of a record (white output noise of sd σ, run r
// seeded by ctid::run_seed(2024, level, r), runs in parallel with results stored by index so
// the outcome equals the serial one), the whole pipeline on each at the true Δ, and for
// comparison the output-error refinement started at the truth. Printed per parameter, for
// both: mean error over its standard error σ_CR/√M (no bias: |z| < 3) and the sample variance
// over the Cramér-Rao variance at the truth (efficiency: ≈ 1); counted: the runs where the
// pipeline ends above the cost of the refinement from the truth (local minima). Run with
//   build/benchmarks/feedback_benchmark --benchmark_filter=MonteCarlo
struct ConsistencySummary {
  double max_z = 0.0, min_ratio = 1e300, max_ratio = 0.0;
  double max_bias = 0.0;  // largest |mean error| / σ_CR
};

ConsistencySummary summarise(const char* title, const Eigen::MatrixXd& errors,
                             const Eigen::VectorXd& truth, const Eigen::VectorXd& bound_sd) {
  const auto runs = static_cast<int>(errors.cols());
  const Eigen::VectorXd mean = errors.rowwise().mean();
  const Eigen::MatrixXd centred = errors.colwise() - mean;
  const Eigen::VectorXd variance = centred.rowwise().squaredNorm() / (runs - 1);
  ConsistencySummary s;
  std::printf("%s\n  i   truth   mean error   z(mean)   var/CR var   mean/CR sd\n", title);
  for (Eigen::Index i = 0; i < truth.size(); ++i) {
    const double z = mean(i) / (bound_sd(i) / std::sqrt(runs));
    const double ratio = variance(i) / (bound_sd(i) * bound_sd(i));
    std::printf("%3d %7.3f %12.3e %9.2f %10.2f %12.2f\n", static_cast<int>(i), truth(i), mean(i), z,
                ratio, mean(i) / bound_sd(i));
    s.max_bias = std::max(s.max_bias, std::abs(mean(i)) / bound_sd(i));
    s.max_z = std::max(s.max_z, std::abs(z));
    s.min_ratio = std::min(s.min_ratio, ratio);
    s.max_ratio = std::max(s.max_ratio, ratio);
  }
  return s;
}

void BM_PipelineMonteCarlo(benchmark::State& state) {
  const double sigma = static_cast<double>(state.range(0)) * 1e-5;
  const int runs = static_cast<int>(state.range(1));
  const ctid::SampledData& data = monte_carlo_record(state.range(2));
  const ctid::DelayedFeedbackLoop loop = paper_loop();
  const Eigen::VectorXd truth = ctid::loop_parameters(loop);
  const ctid::SeparabilityReport crb = ctid::cramer_rao_bound(
      loop, data.input(), data.sample_time(), ctid::Hold::first_order_hold, sigma);
  ctid::FeedbackIdentificationOptions o;
  o.output_error.hold = ctid::Hold::first_order_hold;
  o.extra_finalists = static_cast<int>(state.range(3));
  Eigen::MatrixXd errors(truth.size(), runs), reference_errors(truth.size(), runs);
  std::vector<int> local(static_cast<std::size_t>(runs), 0);
  for (auto _ : state) {
    ctid::parallel_for(runs, 2, [&](int r) {
      std::mt19937_64 rng(ctid::run_seed(2024, static_cast<int>(state.range(0)), r));
      std::normal_distribution<double> normal(0.0, sigma);
      Eigen::VectorXd y = data.output();
      for (Eigen::Index k = 0; k < y.size(); ++k) y(k) += normal(rng);
      const ctid::SampledData noisy(data.sample_time(), data.input(), y);
      const ctid::FeedbackIdentificationResult fit =
          ctid::identify_delayed_feedback(noisy, 3, 3, 0.5, o);
      const ctid::OutputErrorResult reference =
          ctid::refine_output_error(noisy, loop, o.output_error);
      errors.col(r) = ctid::loop_parameters(fit.loop) - truth;
      reference_errors.col(r) = ctid::loop_parameters(reference.loop) - truth;
      local[static_cast<std::size_t>(r)] =
          fit.output_rms > reference.residual_rms * (1.0 + 1e-6) ? 1 : 0;
    });
  }
  std::printf("record %.0f s, sigma %.1e, %d runs\n",
              static_cast<double>(data.size() - 1) * data.sample_time(), sigma, runs);
  std::printf("pipeline above the refinement from the truth in runs:");
  int above = 0;
  for (int r = 0; r < runs; ++r)
    if (local[static_cast<std::size_t>(r)] != 0) {
      std::printf(" %d", r);
      ++above;
    }
  std::printf(" (%d of %d)\n", above, runs);
  const ConsistencySummary p = summarise("pipeline", errors, truth, crb.standard_deviations);
  const ConsistencySummary t =
      summarise("refinement from the truth", reference_errors, truth, crb.standard_deviations);
  state.counters["max_abs_z"] = p.max_z;
  state.counters["min_var_ratio"] = p.min_ratio;
  state.counters["max_var_ratio"] = p.max_ratio;
  state.counters["local_minima"] = above;
  state.counters["max_bias_over_sd"] = p.max_bias;
  state.counters["truth_max_abs_z"] = t.max_z;
  state.counters["truth_max_var_ratio"] = t.max_ratio;
}
// σ in units of 1e-5 (10: 1e-4, 30: 3e-4, 100: 1e-3), runs, record (0: 30 s / 8 lines of
// 15 s; 1, 2, 3: 40, 80, 120 s of 12 lines of 20 s; 4: 40 s of 40 lines of 20 s),
// extra_finalists of the pipeline.
BENCHMARK(BM_PipelineMonteCarlo)
    ->Args({10, 40, 0, 0})
    ->Args({30, 40, 0, 0})
    ->Args({100, 20, 0, 0})
    ->Args({100, 30, 1, 0})
    ->Args({100, 30, 2, 0})
    ->Args({100, 30, 2, 2})
    ->Args({100, 20, 3, 0})
    ->Args({100, 40, 4, 0})
    ->Args({300, 40, 4, 0})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
