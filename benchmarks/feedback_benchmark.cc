// The delayed-feedback identification pieces on the informative record of
// tests/estimation/feedback_pipeline_test.cc (F, H of De Iuliis et al. 2017 Section 4,
// Δ = 0.5 s, δ = 50 ms, smooth multisine continued linearly, 30 s): step 1 by batch QR and by
// RLS, the two separations on the step-1 polynomials, one output-error refinement from a start
// 2 % off, and the whole pipeline. Time per call.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "ctid/estimation/feedback_refinement.h"
#include "ctid/study/monte_carlo.h"

namespace {

ctid::DelayedFeedbackLoop paper_loop() {
  return {
      ctid::TransferFunction(ctid::Polynomial{2.0, 1.0, 2.0}, ctid::Polynomial{3.0, 2.0, 3.0, 1.0}),
      ctid::TransferFunction(ctid::Polynomial{1.0, 5.0, 1.0}, ctid::Polynomial{2.0, 2.0, 3.0, 1.0}),
      0.5};
}

const ctid::SampledData& record() {
  static const ctid::SampledData data = [] {
    const double delta = 0.05;
    const int samples = 601;
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> phase(0.0, 2.0 * M_PI);
    std::vector<double> phases(8);
    for (double& p : phases) p = phase(rng);
    Eigen::VectorXd u(samples);
    for (int k = 0; k < samples; ++k) {
      double sum = 0.0;
      for (int j = 1; j <= 8; ++j)
        sum +=
            std::cos(2.0 * M_PI * j * k * delta / 15.0 + phases[static_cast<std::size_t>(j - 1)]);
      u(k) = sum / 2.0;
    }
    const Eigen::VectorXd y =
        ctid::simulate_delayed(ctid::to_delayed_state_space(paper_loop()), u, delta,
                               ctid::InputHold::kFirstOrder, ctid::DelayedSimulationOptions{4});
    return ctid::SampledData(delta, u, y);
  }();
  return data;
}

const ctid::FeedbackRegression& regression() {
  static const ctid::FeedbackRegression reg = [] {
    ctid::FeedbackRegressorOptions o;
    o.filter = ctid::RegressorFilter::kLinearIntegralFilter;
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
  o.hold = ctid::InputHold::kFirstOrder;
  const ctid::DelayedFeedbackLoop loop = ctid::loop_from_parameters(start, 3, 3, 0.5);
  for (auto _ : state) benchmark::DoNotOptimize(ctid::refine_output_error(record(), loop, o));
}
BENCHMARK(BM_OutputErrorRefinement)->Unit(benchmark::kMillisecond)->Iterations(2);

void BM_Pipeline(benchmark::State& state) {
  ctid::FeedbackIdentificationOptions o;
  o.output_error.hold = ctid::InputHold::kFirstOrder;
  for (auto _ : state)
    benchmark::DoNotOptimize(ctid::identify_delayed_feedback(record(), 3, 3, 0.5, o));
}
BENCHMARK(BM_Pipeline)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

// Monte Carlo of consistency: M noisy copies of the record (white output noise of sd σ, run
// r seeded by ctid::run_seed(2024, level, r), runs in parallel with results stored by index
// so the outcome equals the serial one), the whole pipeline on each at the true Δ. Printed per
// parameter: mean error over its standard error σ_CR/√M (no bias: |z| < 3) and the sample
// variance over the Cramér-Rao variance at the truth (efficiency: ≈ 1). Run with
//   build/benchmarks/feedback_benchmark --benchmark_filter=MonteCarlo
void BM_PipelineMonteCarlo(benchmark::State& state) {
  const double sigma = static_cast<double>(state.range(0)) * 1e-5;
  const int runs = static_cast<int>(state.range(1));
  const ctid::DelayedFeedbackLoop loop = paper_loop();
  const Eigen::VectorXd truth = ctid::loop_parameters(loop);
  const ctid::SeparabilityReport crb = ctid::cramer_rao_bound(
      loop, record().input(), record().sample_time(), ctid::InputHold::kFirstOrder, sigma);
  ctid::FeedbackIdentificationOptions o;
  o.output_error.hold = ctid::InputHold::kFirstOrder;
  Eigen::MatrixXd errors(truth.size(), runs);
  for (auto _ : state) {
    ctid::parallel_for(runs, 2, [&](int r) {
      std::mt19937_64 rng(ctid::run_seed(2024, static_cast<int>(state.range(0)), r));
      std::normal_distribution<double> normal(0.0, sigma);
      Eigen::VectorXd y = record().output();
      for (Eigen::Index k = 0; k < y.size(); ++k) y(k) += normal(rng);
      const ctid::FeedbackIdentificationResult fit = ctid::identify_delayed_feedback(
          ctid::SampledData(record().sample_time(), record().input(), y), 3, 3, 0.5, o);
      errors.col(r) = ctid::loop_parameters(fit.loop) - truth;
    });
  }
  const Eigen::VectorXd mean = errors.rowwise().mean();
  const Eigen::MatrixXd centred = errors.colwise() - mean;
  const Eigen::VectorXd variance = centred.rowwise().squaredNorm() / (runs - 1);
  double max_z = 0.0, min_ratio = 1e300, max_ratio = 0.0;
  std::printf("sigma %.1e, %d runs\n  i   truth   mean error   z(mean)   var/CR var\n", sigma,
              runs);
  for (Eigen::Index i = 0; i < truth.size(); ++i) {
    const double z = mean(i) / (crb.standard_deviations(i) / std::sqrt(runs));
    const double ratio = variance(i) / (crb.standard_deviations(i) * crb.standard_deviations(i));
    std::printf("%3d %7.3f %12.3e %9.2f %10.2f\n", static_cast<int>(i), truth(i), mean(i), z,
                ratio);
    max_z = std::max(max_z, std::abs(z));
    min_ratio = std::min(min_ratio, ratio);
    max_ratio = std::max(max_ratio, ratio);
  }
  state.counters["max_abs_z"] = max_z;
  state.counters["min_var_ratio"] = min_ratio;
  state.counters["max_var_ratio"] = max_ratio;
}
// σ in units of 1e-5 (10: 1e-4, 30: 3e-4, 100: 1e-3), runs.
BENCHMARK(BM_PipelineMonteCarlo)
    ->Args({10, 40})
    ->Args({30, 40})
    ->Args({100, 20})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
