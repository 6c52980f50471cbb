// Noise-free recovery by every refined IV estimator: on exact ZOH data the true parameters are
// the fixed point of (29)/(30), so each estimator must return them to rounding accuracy.
#include <cmath>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/estimation/validation.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"
#include "support/paper_systems.h"

namespace ctid::refined_iv_test {
namespace {

// beta * (1 + U(-0.05, 0.05)), the paper's initialisation.
Eigen::VectorXd perturbed(const Eigen::VectorXd& beta, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-0.05, 0.05);
  Eigen::VectorXd out = beta;
  for (Eigen::Index k = 0; k < out.size(); ++k) out(k) *= 1.0 + uniform(rng);
  return out;
}

double relative_error(const Eigen::VectorXd& estimate, const Eigen::VectorXd& truth) {
  return (estimate - truth).norm() / truth.norm();
}

// Parameters of one unfactored submodel B/(p^l A) with A anti-monic.
Eigen::VectorXd unfactored_beta(const TransferFunction& g, int n, int m, int l) {
  const double scale = g.denominator()[l];
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(n + m + 1);
  for (int k = 1; k <= n; ++k) beta(k - 1) = g.denominator()[l + k] / scale;
  for (int k = 0; k <= g.numerator().degree(); ++k) beta(n + k) = g.numerator()[k] / scale;
  return beta;
}

class OpenLoopFourModes : public ::testing::Test {
 protected:
  OpenLoopFourModes()
      : truth(testing::open_loop_four_modes()),
        u(white_noise(3000, 1.0, 11)),
        data(0.05, u, simulate(truth, u, 0.05)) {}
  AdditiveModel truth;
  Eigen::VectorXd u;
  SampledData data;
};

TEST_F(OpenLoopFourModes, AdditiveRecoversTheTrueParametersFromNoiseFreeData) {
  RefinedIvOptions options;
  options.initial_model = truth.with_parameters(perturbed(truth.parameters(), 1));
  options.record_history = true;
  const EstimationResult r = additive_srivc(data, truth.orders(), options);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_LT(relative_error(r.parameters, truth.parameters()), 1e-9);
  EXPECT_LT(r.off_diagonal_norm, 1e-9);  // Lemma 4.4
  EXPECT_GT(r.fit_percent, 99.9999);
  EXPECT_EQ(static_cast<int>(r.history.size()), r.iterations);
  ASSERT_EQ(r.modes.size(), 4u);
  EXPECT_NEAR(r.modes[0].value.gain, 3.0, 1e-8);
}

TEST_F(OpenLoopFourModes, SrivcRecoversTheUnfactoredModel) {
  const TransferFunction g = truth.to_transfer_function();
  RefinedIvOptions options;
  // The paper: the unfactored estimator starts from the perturbed additive system.
  options.initial_model = truth.with_parameters(perturbed(truth.parameters(), 2));
  const EstimationResult r = srivc(data, {8, 6, 0}, options);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_LT(relative_error(r.parameters, unfactored_beta(g, 8, 6, 0)), 1e-9);
  ASSERT_TRUE(r.additive_view.has_value());
  EXPECT_EQ(r.modes.size(), 4u);
}

TEST(RefinedIv, RaoGarnierBenchmarkWithPrbs) {
  // G(s) = (-6400 s + 1600) / (s^4 + 5 s^3 + 408 s^2 + 416 s + 1600), Ts = 0.01 s.
  const TransferFunction g(Polynomial{1600.0, -6400.0}, Polynomial{1600.0, 416.0, 408.0, 5.0, 1.0});
  PrbsOptions prbs_options;
  prbs_options.register_length = 10;
  prbs_options.samples_per_bit = 7;
  const Eigen::VectorXd u = prbs(4000, prbs_options);
  const SampledData data(0.01, u, simulate(g, u, 0.01));
  const Eigen::VectorXd truth = unfactored_beta(g, 4, 1, 0);
  RefinedIvOptions options;
  options.initial_model = AdditiveModel::from_parameters({{4, 1, 0}}, perturbed(truth, 3));
  const EstimationResult r = srivc(data, {4, 1, 0}, options);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_LT(relative_error(r.parameters, truth), 1e-9);

  // The same system as two second-order modes with first-order numerators.
  const AdditiveModel modes = AdditiveModel::from_transfer_function(g);
  ASSERT_EQ(modes.size(), 2);
  RefinedIvOptions additive_options;
  additive_options.initial_model = modes.with_parameters(perturbed(modes.parameters(), 4));
  const EstimationResult a = additive_srivc(data, {{2, 1, 0}, {2, 1, 0}}, additive_options);
  ASSERT_TRUE(a.converged()) << a.message;
  EXPECT_LT(relative_error(a.parameters, modes.parameters()), 1e-9);
}

TEST(RefinedIv, IntegratorSubmodelIsRecovered) {
  // 1/(p (1 + 0.5 p)) + 2/(1 + 0.2 p + 0.04 p^2): Remark 5, eqs. (31)-(32).
  const AdditiveModel truth({{Polynomial{1.0, 0.5}, Polynomial{1.0}, 1},
                             {Polynomial{1.0, 0.2, 0.04}, Polynomial{2.0}, 0}});
  const Eigen::VectorXd u = white_noise(2000, 1.0, 5);
  const SampledData data(0.02, u, simulate(truth, u, 0.02));
  RefinedIvOptions options;
  options.initial_model = truth.with_parameters(perturbed(truth.parameters(), 6));
  const EstimationResult r = additive_srivc(data, truth.orders(), options);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_LT(relative_error(r.parameters, truth.parameters()), 1e-9);

  // The unfactored model with the integrator kept out of A.
  const TransferFunction g = truth.to_transfer_function();
  RefinedIvOptions unfactored;
  unfactored.initial_model = options.initial_model;
  const EstimationResult s = srivc(data, {3, 2, 1}, unfactored);
  ASSERT_TRUE(s.converged()) << s.message;
  EXPECT_LT(relative_error(s.parameters, unfactored_beta(g, 3, 2, 1)), 1e-9);
}

TEST(RefinedIv, BiproperSubmodelIsRecovered) {
  const AdditiveModel truth({{Polynomial{1.0, 0.4}, Polynomial{0.5, 0.3}, 0},
                             {Polynomial{1.0, 0.1, 0.01}, Polynomial{2.0}, 0}});
  const Eigen::VectorXd u = white_noise(2000, 1.0, 8);
  const SampledData data(0.01, u, simulate(truth, u, 0.01));
  RefinedIvOptions options;
  options.initial_model = truth.with_parameters(perturbed(truth.parameters(), 9));
  const EstimationResult r = additive_srivc(data, truth.orders(), options);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_LT(relative_error(r.parameters, truth.parameters()), 1e-9);
}

TEST(RefinedIv, ClosedLoopEstimatorsRecoverSection62System) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const DiscreteTransferFunction controller = testing::closed_loop_pid();
  const Eigen::VectorXd r = white_noise(3000, 1.0, 21);
  const ClosedLoopSimulation loop = simulate_closed_loop(truth, controller, r);
  const SampledData data(0.05, loop.input, loop.output, r);
  RefinedIvOptions options;
  options.initial_model = truth.with_parameters(perturbed(truth.parameters(), 22));
  const EstimationResult a = additive_clsrivc(data, controller, truth.orders(), options);
  ASSERT_TRUE(a.converged()) << a.message;
  EXPECT_LT(relative_error(a.parameters, truth.parameters()), 1e-9);
  EXPECT_EQ(a.sensitivity_fallbacks, 0);

  const EstimationResult c = clsrivc(data, controller, {4, 2, 0}, options);
  ASSERT_TRUE(c.converged()) << c.message;
  EXPECT_LT(relative_error(c.parameters, unfactored_beta(truth.to_transfer_function(), 4, 2, 0)),
            1e-9);
}

TEST(RefinedIv, KnownInputDelayIsHonoured) {
  const AdditiveModel truth = testing::closed_loop_two_modes().with_input_delay(3 * 0.05);
  const Eigen::VectorXd u = white_noise(2000, 1.0, 31);
  const SampledData data(0.05, u, simulate(truth, u, 0.05));
  RefinedIvOptions options;
  options.input_delay_samples = 3;
  options.initial_model = truth.with_parameters(perturbed(truth.parameters(), 32));
  const EstimationResult r = additive_srivc(data, truth.orders(), options);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_LT(relative_error(r.parameters, truth.parameters()), 1e-9);
  EXPECT_EQ(r.input_delay_samples, 3);
  EXPECT_NEAR(r.model.input_delay(), 0.15, 1e-12);
}

}  // namespace
}  // namespace ctid::refined_iv_test
