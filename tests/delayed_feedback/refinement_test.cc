// Output-error refinement, Cramér-Rao separability report and delay scan.
#include "ctid/delayed_feedback/identification.h"

#include <cmath>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "support/de_iuliis_systems.h"
#include "support/sanitizers.h"

namespace ctid::refinement_test {
namespace {

// These records are simulated with a zero-order hold; the refinement must assume the same.
OutputErrorOptions zoh_options() {
  OutputErrorOptions o;
  o.hold = Hold::zero_order_hold;
  return o;
}

DelayedFeedbackLoop paper_loop() { return test_support::paper_feedback_loop(); }

Eigen::VectorXd fourier_samples(double delta, int samples, double period) {
  const FourierBasisInput input{12, period};
  Eigen::VectorXd u(samples);
  for (int k = 0; k < samples; ++k) u(k) = input(k * delta);
  return u;
}

TEST(FeedbackRefinement, ParametersRoundTrip) {
  const DelayedFeedbackLoop loop = paper_loop();
  const Eigen::VectorXd rho = loop_parameters(loop);
  EXPECT_EQ(rho.size(), 12);
  EXPECT_EQ(loop_parameters(loop_from_parameters(rho, 3, 3, 0.5)), rho);
  EXPECT_DOUBLE_EQ(rho(0), 3.0);  // a_F0
  EXPECT_DOUBLE_EQ(rho(9), 1.0);  // b_H0
}

TEST(FeedbackRefinement, OutputErrorRecoversLoopNoiseFree) {
  const DelayedFeedbackLoop loop = paper_loop();
  const double delta = 0.05;
  const Eigen::VectorXd u = fourier_samples(delta, 301, 10.0);
  const Eigen::VectorXd y = simulate_delayed(to_delayed_state_space(loop), u, delta,
                                             Hold::zero_order_hold, DelayedSimulationOptions{4});
  const SampledData data(delta, u, y);
  Eigen::VectorXd start = loop_parameters(loop);
  for (Eigen::Index i = 0; i < start.size(); ++i) start(i) *= (i % 2 == 0) ? 0.98 : 1.02;
  const OutputErrorResult r =
      refine_output_error(data, loop_from_parameters(start, 3, 3, 0.5), zoh_options());
  EXPECT_LT((loop_parameters(r.loop) - loop_parameters(loop)).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LT(r.residual_rms, 1e-8);
}

TEST(FeedbackRefinement, CramerRaoSaysThePaperExperimentCannotSeparate) {
  // Section 4 at 15 % NSR: σ = 0.15 mean|y| sqrt(π/2) for Gaussian noise.
  const DelayedFeedbackLoop loop = paper_loop();
  const double delta = 0.05;
  const Eigen::VectorXd u = fourier_samples(delta, 101, 5.0);
  const Eigen::VectorXd y = simulate_delayed(to_delayed_state_space(loop), u, delta,
                                             Hold::zero_order_hold, DelayedSimulationOptions{4});
  const double sigma = 0.15 * y.cwiseAbs().mean() * std::sqrt(M_PI / 2.0);
  const SeparabilityReport paper = cramer_rao_bound(loop, u, delta, Hold::zero_order_hold, sigma);
  EXPECT_FALSE(paper.separable);
  EXPECT_GT(paper.standard_deviations.maxCoeff(), 100.0);
  EXPECT_THAT(paper.message, ::testing::HasSubstr("NOT"));
  // A 60 s record of a random binary input with noise sd 5e-4 separates them.
  std::mt19937_64 rng(5);
  Eigen::VectorXd prbs(1201);
  for (Eigen::Index k = 0; k < prbs.size(); ++k) prbs(k) = (rng() % 2) ? 1.0 : -1.0;
  const SeparabilityReport good =
      cramer_rao_bound(loop, prbs, delta, Hold::zero_order_hold, 0.0005);
  EXPECT_TRUE(good.separable) << good.message;
  // The bound scales with σ: same experiment, 10x noise, 10x standard deviations.
  const SeparabilityReport noisier =
      cramer_rao_bound(loop, prbs, delta, Hold::zero_order_hold, 0.005);
  EXPECT_NEAR(noisier.standard_deviations(0) / good.standard_deviations(0), 10.0, 1e-6);
}

TEST(FeedbackRefinement, OutputErrorIsConsistentInASeededMonteCarlo) {
  CTID_SKIP_UNDER_SANITIZERS(
      "a Monte Carlo of refinements the other FeedbackRefinement tests run once");
  // Random binary input (20 s), white output noise sd 2e-4, 4 seeded runs started at the
  // truth: the mean error of every parameter must lie within 4 Cramér-Rao standard errors of
  // the mean, and the spread must be of the size the bound predicts.
  const DelayedFeedbackLoop loop = paper_loop();
  const double delta = 0.05;
  const double sigma = 2e-4;
  std::mt19937_64 input_rng(11);
  Eigen::VectorXd u(401);
  for (Eigen::Index k = 0; k < u.size(); ++k) u(k) = (input_rng() % 2) ? 1.0 : -1.0;
  const Eigen::VectorXd y = simulate_delayed(to_delayed_state_space(loop), u, delta,
                                             Hold::zero_order_hold, DelayedSimulationOptions{4});
  const SeparabilityReport crb = cramer_rao_bound(loop, u, delta, Hold::zero_order_hold, sigma);
  const Eigen::VectorXd truth = loop_parameters(loop);
  const int runs = 4;
  Eigen::MatrixXd errors(truth.size(), runs);
  for (int r = 0; r < runs; ++r) {
    std::mt19937_64 rng(1000 + static_cast<std::uint64_t>(r));
    std::normal_distribution<double> normal(0.0, sigma);
    Eigen::VectorXd noisy = y;
    for (Eigen::Index k = 0; k < noisy.size(); ++k) noisy(k) += normal(rng);
    const OutputErrorResult fit =
        refine_output_error(SampledData(delta, u, noisy), loop, zoh_options());
    errors.col(r) = loop_parameters(fit.loop) - truth;
  }
  const Eigen::VectorXd mean = errors.rowwise().mean();
  for (Eigen::Index i = 0; i < truth.size(); ++i) {
    EXPECT_LT(std::abs(mean(i)), 4.0 * crb.standard_deviations(i) / std::sqrt(runs)) << i;
    const double spread = std::sqrt((errors.row(i).array() - mean(i)).square().sum() / (runs - 1));
    EXPECT_LT(spread, 3.0 * crb.standard_deviations(i)) << i;
  }
}

TEST(FeedbackRefinement, BadInputIsNamed) {
  const DelayedFeedbackLoop loop = paper_loop();
  const SampledData data(0.05, Eigen::VectorXd::Ones(8), Eigen::VectorXd::Ones(8));
  EXPECT_THAT([&] { refine_output_error(data, loop); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("too few samples")));
  EXPECT_THAT(
      [&] { cramer_rao_bound(loop, Eigen::VectorXd::Ones(50), 0.05, Hold::zero_order_hold, -1.0); },
      ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("noise_sd")));
  FeedbackDelayScanOptions scan;
  scan.max_delay = -1.0;
  EXPECT_THAT([&] { scan.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("max_delay")));
}

}  // namespace
}  // namespace ctid::refinement_test
