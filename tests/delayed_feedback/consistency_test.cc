// Consistency of the improved delayed-feedback estimator in a seeded Monte Carlo (small
// version; the full one with the whole pipeline is BM_PipelineMonteCarlo in
// benchmarks/feedback_benchmark.cc). Record: the 30 s multisine of feedback_pipeline_test.cc,
// Δ = 0.5 s, white output noise sd 1e-4. Per run: the output-error refinement from the start
// the whole pipeline chose on a separate noisy copy. Run r is replayable alone:
// its noise is seeded by std::seed_seq{seed, r}. Statistics per parameter against the
// Cramér-Rao bound at the truth: the mean error over its standard error, and the sample
// variance over the bound's variance.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/delayed_feedback/identification.h"
#include "support/de_iuliis_systems.h"
#include "support/sanitizers.h"

namespace ctid::consistency_test {
namespace {

constexpr double kSampleTime = 0.05;
constexpr double kSigma = 1e-4;

DelayedFeedbackLoop paper_loop() { return test_support::paper_feedback_loop(); }

Eigen::VectorXd multisine() { return test_support::smooth_multisine(30.0, 15.0, 8, kSampleTime); }

SampledData noisy_copy(const SampledData& clean, std::uint64_t seed, int run) {
  std::seed_seq sequence{seed, static_cast<std::uint64_t>(run)};
  std::mt19937_64 rng(sequence);
  std::normal_distribution<double> normal(0.0, kSigma);
  Eigen::VectorXd y = clean.output();
  for (Eigen::Index k = 0; k < y.size(); ++k) y(k) += normal(rng);
  return SampledData(clean.sample_time(), clean.input(), y);
}

Eigen::VectorXd estimate(const SampledData& data, const DelayedFeedbackLoop& start) {
  OutputErrorOptions oe;
  oe.hold = Hold::first_order_hold;
  return loop_parameters(refine_output_error(data, start, oe).loop);
}

TEST(FeedbackConsistency, SeededMonteCarloIsUnbiasedWithCramerRaoSpread) {
  CTID_SKIP_UNDER_SANITIZERS(
      "FeedbackPipeline.NoisyRecordLandsWithinThreeCramerRaoDeviations runs the pipeline, the "
      "refinement and the bound on a noisy record");
  const DelayedFeedbackLoop loop = paper_loop();
  const Eigen::VectorXd u = multisine();
  const SampledData clean(kSampleTime, u,
                          simulate_delayed(to_delayed_state_space(loop), u, kSampleTime,
                                           Hold::first_order_hold, DelayedSimulationOptions{4}));
  const SeparabilityReport crb =
      cramer_rao_bound(loop, u, kSampleTime, Hold::first_order_hold, kSigma);
  const Eigen::VectorXd truth = loop_parameters(loop);
  const int runs = 8;
  const std::uint64_t seed = 4242;
  // The start: the candidate the whole pipeline chose on a separate noisy copy.
  FeedbackIdentificationOptions options;
  options.output_error.hold = Hold::first_order_hold;
  const FeedbackIdentificationResult pipeline =
      identify_delayed_feedback(noisy_copy(clean, seed + 1, 0), 3, 3, 0.5, options);
  ASSERT_TRUE(pipeline.best_candidate.has_value()) << pipeline.message;
  const DelayedFeedbackLoop start = pipeline.candidates[*pipeline.best_candidate].start;
  Eigen::MatrixXd errors(truth.size(), runs);
  for (int r = 0; r < runs; ++r)
    errors.col(r) = estimate(noisy_copy(clean, seed, r), start) - truth;

  // Replayable: run 3 alone gives the same estimate.
  EXPECT_EQ(estimate(noisy_copy(clean, seed, 3), start) - truth, errors.col(3));

  const double m = runs;
  const Eigen::VectorXd mean = errors.rowwise().mean();
  const Eigen::VectorXd variance = (errors.colwise() - mean).rowwise().squaredNorm() / (m - 1.0);
  for (Eigen::Index i = 0; i < truth.size(); ++i) {
    const double sd = crb.standard_deviations(i);
    // No bias: the mean error within 3.5 standard errors (family-wise false alarm < 1 %).
    EXPECT_LT(std::abs(mean(i)), 3.5 * sd / std::sqrt(m)) << i;
    // Spread of the bound's size: (M-1) s²/σ² ~ χ²₇, P(outside [0.15, 4]) < 1 %.
    EXPECT_GT(variance(i) / (sd * sd), 0.15) << i;
    EXPECT_LT(variance(i) / (sd * sd), 4.0) << i;
  }
}

}  // namespace
}  // namespace ctid::consistency_test
