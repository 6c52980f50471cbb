// The whole delayed-feedback identification with output noise, at the true Δ = 0.5 s: the
// pipeline must reach the global output-error minimum (the refinement started at the truth
// lands on the same point) and every parameter must lie within 3 Cramér-Rao standard
// deviations of the bound at the estimate. Two records: the 30 s multisine of
// feedback_pipeline_test.cc (8 harmonics of 15 s) at noise sd 3e-4, and a 40 s one with 12
// harmonics of 20 s at sd 1e-3 (its lines 0.31 rad/s apart also excite F's resonance at
// 1.05 rad/s, which falls between the lines of the first record).
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/delayed_feedback/identification.h"
#include "support/de_iuliis_systems.h"
#include "support/sanitizers.h"

namespace ctid::noise_test {
namespace {

DelayedFeedbackLoop paper_loop() { return test_support::paper_feedback_loop(); }

SampledData noisy_record(double duration, double period, int harmonics, double sigma,
                         std::uint64_t seed) {
  return test_support::with_white_noise(
      test_support::feedback_record(paper_loop(), duration, period, harmonics), sigma, seed);
}

void expect_global_and_within_bound(const SampledData& data, double sigma) {
  FeedbackIdentificationOptions o;
  o.output_error.hold = Hold::first_order_hold;
  const FeedbackIdentificationResult r = identify_delayed_feedback(data, 3, 3, 0.5, o);
  ASSERT_EQ(r.cramer_rao.standard_deviations.size(), 12) << r.message;
  const OutputErrorResult reference = refine_output_error(data, paper_loop(), o.output_error);
  EXPECT_LE(r.output_rms, reference.residual_rms * (1.0 + 1e-6)) << r.message;
  const Eigen::VectorXd error = loop_parameters(r.loop) - loop_parameters(paper_loop());
  for (Eigen::Index i = 0; i < error.size(); ++i)
    EXPECT_LT(std::abs(error(i)), 3.0 * r.cramer_rao.standard_deviations(i)) << i;
  EXPECT_LT(r.output_rms, 1.1 * sigma);
  EXPECT_GT(r.output_rms, 0.8 * sigma);
}

TEST(FeedbackNoise, ThirtySecondRecordAtSd3e4ReachesTheGlobalMinimum) {
  CTID_SKIP_UNDER_SANITIZERS(
      "FeedbackPipeline.NoisyRecordLandsWithinThreeCramerRaoDeviations runs the pipeline on a "
      "noisy record");
  // Largest relative Cramér-Rao deviation here: 11 % (b_H0); at sd 1e-3 it is 37 % and the
  // output error has local minima within 3 % of the global cost (see the docs).
  expect_global_and_within_bound(noisy_record(30.0, 15.0, 8, 3e-4, 1), 3e-4);
}

TEST(FeedbackNoise, FortySecondRecordAtSd1e3ReachesTheGlobalMinimumSeed1) {
  CTID_SKIP_UNDER_SANITIZERS(
      "FeedbackPipeline.NoisyRecordLandsWithinThreeCramerRaoDeviations runs the pipeline on a "
      "noisy record");
  expect_global_and_within_bound(noisy_record(40.0, 20.0, 12, 1e-3, 1), 1e-3);
}

TEST(FeedbackNoise, FortySecondRecordAtSd1e3ReachesTheGlobalMinimumSeed2) {
  CTID_SKIP_UNDER_SANITIZERS(
      "FeedbackPipeline.NoisyRecordLandsWithinThreeCramerRaoDeviations runs the pipeline on a "
      "noisy record");
  expect_global_and_within_bound(noisy_record(40.0, 20.0, 12, 1e-3, 2), 1e-3);
}

}  // namespace
}  // namespace ctid::noise_test
