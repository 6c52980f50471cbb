// The whole delayed-feedback identification (step 1, separation candidates, output-error
// refinement from each) on an informative experiment: a smooth multisine (8 harmonics of a
// 15 s period, two periods) sampled at 50 ms and continued linearly, so that the simulated
// data and the refinement's model of the input agree exactly.
#include <cmath>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/delayed_feedback/identification.h"
#include "support/de_iuliis_systems.h"
#include "support/sanitizers.h"

namespace ctid::pipeline_test {
namespace {

using test_support::feedback_record;
using test_support::smooth_multisine;

DelayedFeedbackLoop paper_loop() { return test_support::paper_feedback_loop(); }

SampledData informative_data(const DelayedFeedbackLoop& loop) { return feedback_record(loop); }

FeedbackIdentificationOptions foh_options() {
  FeedbackIdentificationOptions o;
  o.output_error.hold = Hold::first_order_hold;
  return o;
}

TEST(FeedbackPipeline, NoiseFreeInformativeRecordRecoversFAndH) {
  const DelayedFeedbackLoop loop = paper_loop();
  const FeedbackIdentificationResult r =
      identify_delayed_feedback(informative_data(loop), 3, 3, 0.5, foh_options());
  ASSERT_TRUE(r.best_candidate.has_value()) << r.message;
  const Eigen::VectorXd truth = loop_parameters(loop);
  const Eigen::VectorXd error = loop_parameters(r.loop) - truth;
  EXPECT_LT(error.cwiseAbs().maxCoeff(), 1e-6 * truth.cwiseAbs().maxCoeff()) << r.message;
  EXPECT_LT(r.output_rms, 1e-9);
  EXPECT_TRUE(r.verdict.usable) << r.verdict.summary();
  EXPECT_DOUBLE_EQ(r.loop.delay, 0.5);
  // Candidates of every kind were tried, and the chosen one has the smallest refined cost.
  bool gcd = false, kronecker = false;
  for (const SeparationCandidateReport& c : r.candidates) {
    gcd = gcd || c.source == "gcd";
    kronecker = kronecker || c.source.rfind("kronecker", 0) == 0;
    EXPECT_GE(c.refined_rms, r.output_rms) << c.source;
  }
  EXPECT_TRUE(gcd);
  EXPECT_TRUE(kronecker);
  // Frequency responses agree too.
  for (double w : {0.1, 1.0, 3.0}) {
    EXPECT_LT(std::abs(r.loop.forward.frequency_response(w) - loop.forward.frequency_response(w)),
              1e-6)
        << w;
    EXPECT_LT(std::abs(r.loop.feedback.frequency_response(w) - loop.feedback.frequency_response(w)),
              1e-6)
        << w;
  }
}

TEST(FeedbackPipeline, NoisyRecordLandsWithinThreeCramerRaoDeviations) {
  CTID_SKIP_UNDER_SANITIZERS(
      "NoiseFreeInformativeRecordRecoversFAndH runs the same pipeline; this adds a statistical "
      "bound");
  // White output noise sd 1e-4 (y rms 1.6), one seeded run: every parameter error within
  // 3 standard deviations of the bound reported at the estimate, and the fit at noise level.
  const DelayedFeedbackLoop loop = paper_loop();
  const SampledData clean = informative_data(loop);
  const double sigma = 1e-4;
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> normal(0.0, sigma);
  Eigen::VectorXd y = clean.output();
  for (Eigen::Index k = 0; k < y.size(); ++k) y(k) += normal(rng);
  const FeedbackIdentificationResult r = identify_delayed_feedback(
      SampledData(clean.sample_time(), clean.input(), y), 3, 3, 0.5, foh_options());
  ASSERT_EQ(r.cramer_rao.standard_deviations.size(), 12) << r.message;
  const Eigen::VectorXd error = loop_parameters(r.loop) - loop_parameters(loop);
  for (Eigen::Index i = 0; i < error.size(); ++i)
    EXPECT_LT(std::abs(error(i)), 3.0 * r.cramer_rao.standard_deviations(i)) << i;
  EXPECT_LT(r.output_rms, 1.1 * sigma);
  EXPECT_GT(r.output_rms, 0.8 * sigma);
}

TEST(FeedbackPipeline, JointRefinementFindsAFractionalDelay) {
  // Δ = 0.523 s (not a multiple of δ = 0.05 s); the refinement starts at Δ = 0.56 s with F and H
  // perturbed by 2 %, and must land within δ/10 of the truth with the other parameters.
  DelayedFeedbackLoop loop = paper_loop();
  loop.delay = 0.523;
  const double delta = 0.05;
  const Eigen::VectorXd u = smooth_multisine(20.0, 10.0, 8, delta);
  const Eigen::VectorXd y = simulate_delayed(to_delayed_state_space(loop), u, delta,
                                             Hold::first_order_hold, DelayedSimulationOptions{4});
  Eigen::VectorXd start = loop_parameters(loop);
  for (Eigen::Index i = 0; i < start.size(); ++i) start(i) *= (i % 2 == 0) ? 0.98 : 1.02;
  OutputErrorOptions options;
  options.hold = Hold::first_order_hold;
  options.estimate_delay = true;
  const OutputErrorResult fit = refine_output_error(
      SampledData(delta, u, y), loop_from_parameters(start, 3, 3, 0.56), options);
  EXPECT_LT(std::abs(fit.loop.delay - 0.523), delta / 10.0) << fit.message;
  EXPECT_LT((loop_parameters(fit.loop) - loop_parameters(loop)).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(FeedbackPipeline, DelayScanFindsTheDelayFromAGridThatMissesIt) {
  CTID_SKIP_UNDER_SANITIZERS(
      "FeedbackFractionalDelay.ScanFindsTheDelayNoiseFreeAndReportsEachGridPoint runs the same "
      "scan and joint refinement");
  // Grid 0.44, 0.48, 0.52 s (none is the true 0.5 s): refined-output-error criterion, the
  // pipeline at the best grid point, then the joint (ρ, Δ) refinement; Δ within δ/10.
  const DelayedFeedbackLoop loop = paper_loop();
  DelayIdentificationOptions options;
  options.identification = foh_options();
  options.scan.min_delay = 0.44;
  options.scan.max_delay = 0.52;
  options.scan.points = 3;
  options.scan.hold = Hold::first_order_hold;
  options.scan.regressors = options.identification.regressors;
  const DelayIdentificationResult r =
      identify_delayed_feedback_with_delay_scan(informative_data(loop), 3, 3, options);
  EXPECT_NE(r.scan.delay, 0.5);
  EXPECT_LT(std::abs(r.delay - 0.5), 0.005) << r.identification.message;
  EXPECT_DOUBLE_EQ(r.identification.loop.delay, r.delay);
  EXPECT_LT((loop_parameters(r.identification.loop) - loop_parameters(loop)).cwiseAbs().maxCoeff(),
            1e-5);
}

TEST(FeedbackPipeline, BadInputIsNamed) {
  const SampledData data(0.05, Eigen::VectorXd::Ones(200), Eigen::VectorXd::Ones(200));
  EXPECT_THAT([&] { identify_delayed_feedback(data, 0, 3, 0.5); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("orders")));
  EXPECT_THAT([&] { identify_delayed_feedback(data, 3, 3, -0.1); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("delay")));
  EXPECT_THROW(identify_delayed_feedback(data, 3, 3, 20.0), InvalidArgument);
  const SampledData tiny(0.05, Eigen::VectorXd::Ones(12), Eigen::VectorXd::Ones(12));
  EXPECT_THROW(identify_delayed_feedback(tiny, 3, 3, 0.1), InvalidArgument);
  FeedbackIdentificationOptions o;
  o.screening_iterations = 0;
  EXPECT_THAT([&] { o.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(
                                         ::testing::HasSubstr("screening_iterations")));
  // A nested field is named by its full path, value and rule.
  o.screening_iterations = 15;
  o.output_error.substeps = 0;
  EXPECT_THAT([&] { o.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::StrEq(
                  "FeedbackIdentificationOptions.output_error.substeps is 0; it must be >= 1")));
  // The IV stage follows output_error's hold: a contradicting one is rejected, not overwritten.
  o.output_error.substeps = 4;
  o.output_error.hold = Hold::first_order_hold;
  o.iv.hold = Hold::zero_order_hold;
  EXPECT_THAT([&] { o.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr(
                  "FeedbackIdentificationOptions.iv.hold is zero_order_hold; it must be empty or "
                  "first_order_hold")));
  o.iv.hold = Hold::first_order_hold;
  EXPECT_NO_THROW(o.validate());
  DelayIdentificationOptions d;
  d.scan.hold = Hold::zero_order_hold;
  EXPECT_THAT([&] { d.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr(
                  "DelayIdentificationOptions.scan.hold is zero_order_hold; it must equal "
                  "identification.output_error.hold")));
}

TEST(FeedbackPipeline, AFailedFitIsAResultNotAnException) {
  // An all-zero record: step 1 is singular and no candidate can be refined.
  const SampledData zero(0.05, Eigen::VectorXd::Zero(200), Eigen::VectorXd::Zero(200));
  FeedbackIdentificationOptions o;
  o.iv_filter_poles = {};
  const FeedbackIdentificationResult r = identify_delayed_feedback(zero, 2, 1, 0.5, o);
  EXPECT_EQ(r.step1.termination, Termination::singular_equations);
  EXPECT_NE(r.termination, Termination::not_run);
  EXPECT_FALSE(r.message.empty());
  // Nothing usable came out, and the verdict says so.
  EXPECT_FALSE(r.verdict.usable);
  EXPECT_FALSE(r.verdict.reasons.empty());
  EXPECT_FALSE(r.verdict.advice.empty());
}

}  // namespace
}  // namespace ctid::pipeline_test
