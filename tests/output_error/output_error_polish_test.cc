// The output-error polish: exact recovery from noise-free data with a fractional delay (ZOH
// through simulate's exact discretisation, an independent path from model_output), the
// initial state by variable projection, the prediction error with a noise model, the
// stability constraint, and bad input.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/estimation/validation.h"
#include "ctid/output_error/output_error_polish.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"

namespace ctid::output_error_polish_test {
namespace {

constexpr double kH = 0.05;

// 2 (1 + 0.3 p) / (1 + 0.4 p + 0.25 p^2), input delay tau.
AdditiveModel second_order(double tau) {
  return AdditiveModel({Submodel{Polynomial(Eigen::Vector3d(1.0, 0.4, 0.25)),
                                 Polynomial(Eigen::Vector2d(2.0, 0.6)), 0}},
                       tau);
}

AdditiveModel perturbed(const AdditiveModel& m, double relative, double tau) {
  Eigen::VectorXd beta = m.parameters();
  for (Eigen::Index i = 0; i < beta.size(); ++i) beta(i) *= 1.0 + (i % 2 == 0 ? 1 : -1) * relative;
  return AdditiveModel::from_parameters(m.orders(), beta, tau);
}

SampledData record(const AdditiveModel& truth, int n, std::uint64_t seed,
                   const Eigen::VectorXd& extra = {}) {
  const Eigen::VectorXd u = white_noise(n, 1.0, seed);
  Eigen::VectorXd y = simulate(truth, u, kH);
  if (extra.size() == y.size()) y += extra;
  return SampledData(kH, u, y);
}

TEST(OutputErrorPolish, RecoversAFractionalDelayExactlyFromNoiseFreeData) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const double tau = (2.0 + 0.13 * static_cast<double>(seed)) * kH;  // off the grid
    const AdditiveModel truth = second_order(tau);
    const SampledData data = record(truth, 800, seed);
    const OutputErrorPolishResult r = polish_output_error(data, perturbed(truth, 0.1, 2.0 * kH));
    ASSERT_TRUE(r.converged()) << r.message;
    EXPECT_EQ(r.criterion, "output error");
    const Eigen::VectorXd beta = truth.parameters();
    for (Eigen::Index i = 0; i < beta.size(); ++i) {
      EXPECT_NEAR(r.parameters(i), beta(i), 1e-8 * std::abs(beta(i))) << "seed " << seed;
    }
    EXPECT_NEAR(r.model.input_delay(), tau, 1e-8 * kH) << "seed " << seed;
    EXPECT_GT(r.start_cost, 1e-4);  // the start was well off
    EXPECT_LE(r.cost, r.start_cost);
    EXPECT_GT(r.fit_percent, verdict_thresholds::exact_fit_percent);
    EXPECT_TRUE(r.verdict.usable) << r.verdict.summary();
  }
}

TEST(OutputErrorPolish, HeldDelayStaysWhereTheStartHasIt) {
  const AdditiveModel truth = second_order(3.0 * kH);
  const SampledData data = record(truth, 600, 11);
  OutputErrorPolishOptions options;
  options.estimate_delay = false;
  const OutputErrorPolishResult r =
      polish_output_error(data, perturbed(truth, 0.05, 3.0 * kH), std::nullopt, options);
  EXPECT_EQ(r.model.input_delay(), 3.0 * kH);
  EXPECT_EQ(r.parameters.size(), truth.parameter_count());
  EXPECT_NEAR(r.parameters(0), 0.4, 1e-8);
  EXPECT_EQ(r.delay_standard_error, 0.0);
}

TEST(OutputErrorPolish, EstimatesTheInitialStateByVariableProjection) {
  const AdditiveModel truth = second_order(0.0);
  const Eigen::MatrixXd f = free_responses(truth, 500, kH);
  const Eigen::Vector2d x0(1.5, -0.7);
  const SampledData data = record(truth, 500, 21, f * x0);
  OutputErrorPolishOptions options;
  options.estimate_initial_state = true;
  options.estimate_delay = false;
  const OutputErrorPolishResult r =
      polish_output_error(data, perturbed(truth, 0.1, 0.0), std::nullopt, options);
  ASSERT_EQ(r.initial_state.size(), 2);
  EXPECT_NEAR(r.initial_state(0), x0(0), 1e-7);
  EXPECT_NEAR(r.initial_state(1), x0(1), 1e-7);
  EXPECT_NEAR(r.parameters(1), 0.25, 1e-9);
  // From rest, the same data cannot be fitted exactly.
  options.estimate_initial_state = false;
  const OutputErrorPolishResult from_rest =
      polish_output_error(data, perturbed(truth, 0.1, 0.0), std::nullopt, options);
  EXPECT_LT(from_rest.fit_percent, r.fit_percent - 1e-3);
}

// Seeded runs with coloured noise: the prediction error with the true noise structure is
// never above its start, and its 95 % intervals cover the true coefficients in most runs.
TEST(OutputErrorPolish, PredictionErrorWithANoiseModelIsCalibrated) {
  const AdditiveModel truth = second_order(0.0);
  const DiscreteTransferFunction h(Polynomial(Eigen::Vector2d(0.5, 1.0)),
                                   Polynomial(Eigen::Vector2d(-0.9, 1.0)), kH);
  int covered = 0;
  const int runs = 40;
  for (int run = 0; run < runs; ++run) {
    const auto seed = static_cast<std::uint64_t>(100 + run);
    const SampledData data = record(truth, 1500, seed, colored_noise(h, 1500, 0.01, seed + 7));
    ArmaModel start;
    start.ar = Eigen::Vector2d(1.0, -0.8);
    start.ma = Eigen::Vector2d(1.0, 0.3);
    OutputErrorPolishOptions options;
    options.estimate_delay = false;
    const OutputErrorPolishResult r =
        polish_output_error(data, perturbed(truth, 0.05, 0.0), start, options);
    ASSERT_TRUE(r.noise_model.has_value());
    EXPECT_EQ(r.criterion, "prediction error");
    EXPECT_LE(r.cost, r.start_cost);
    EXPECT_NEAR(r.noise_model->ar(1), -0.9, 0.1);
    EXPECT_NEAR(r.noise_model->ma(1), 0.5, 0.15);
    EXPECT_NEAR(r.noise_model->innovation_variance, 0.01, 0.002);
    const Eigen::VectorXd beta = truth.parameters();
    bool all = true;
    for (Eigen::Index i = 0; i < beta.size(); ++i) {
      all = all && std::abs(r.parameters(i) - beta(i)) < 1.96 * r.standard_errors(i);
    }
    covered += all ? 1 : 0;
  }
  // Four coefficients each covered with 95 %: all four together in >= ~81 % of runs.
  EXPECT_GE(covered, 28) << covered << " of " << runs;
}

TEST(OutputErrorPolish, KeepsTheModelStableAndSaysSo) {
  const AdditiveModel truth = second_order(0.0);
  const SampledData data = record(truth, 600, 31);
  // The start's denominator 1 - 0.4 p + 0.25 p^2 has its poles in the right half-plane.
  const AdditiveModel unstable({Submodel{Polynomial(Eigen::Vector3d(1.0, -0.4, 0.25)),
                                         Polynomial(Eigen::Vector2d(2.0, 0.6)), 0}});
  OutputErrorPolishOptions options;
  options.estimate_delay = false;
  const OutputErrorPolishResult r = polish_output_error(data, unstable, std::nullopt, options);
  EXPECT_TRUE(r.stability_constraint_active);
  EXPECT_TRUE(r.transfer_function.is_stable());
  EXPECT_NEAR(r.parameters(0), 0.4, 1e-8);
  EXPECT_THAT(r.verdict.active_constraints,
              ::testing::Contains(::testing::HasSubstr("stability: unstable start poles")));
  const OutputErrorPolishResult free =
      polish_output_error(data, perturbed(truth, 0.05, 0.0), std::nullopt, options);
  EXPECT_FALSE(free.stability_constraint_active);
}

// Two modes 3 / (1 + 0.2 p + 0.5 p^2) + 0.4 / (1 + 0.05 p + 0.1 p^2): static gain 3.4.
AdditiveModel two_modes() {
  return AdditiveModel({Submodel{Polynomial({1.0, 0.2, 0.5}), Polynomial({3.0}), 0},
                        Submodel{Polynomial({1.0, 0.05, 0.1}), Polynomial({0.4}), 0}});
}

TEST(OutputErrorPolish, AKnownDcGainHoldsToRounding) {
  const AdditiveModel truth = two_modes();
  const Eigen::VectorXd noise = white_noise(2000, 0.2, 52);
  const SampledData data = record(truth, 2000, 51, noise);
  OutputErrorPolishOptions options;
  options.estimate_delay = false;
  CoefficientConstraints constraints;
  constraints.dc_gain = 3.3;  // not quite the truth: the constraint must hold anyway
  const OutputErrorPolishResult r =
      polish_output_error(data, perturbed(truth, 0.05, 0.0), std::nullopt, options, constraints);
  const double gain = r.model[0].b[0] + r.model[1].b[0];
  EXPECT_NEAR(gain, 3.3, 4 * std::numeric_limits<double>::epsilon() * 3.3);
  ASSERT_EQ(r.held_parameters, std::vector<std::string>{"theta2.b0"});
  // The gain has no variance: 1' C 1 over the two b0 is zero to rounding.
  const Eigen::Index b0 = 2;
  const Eigen::Index b1 = 5;
  const double var = r.covariance(b0, b0) + r.covariance(b1, b1) + 2.0 * r.covariance(b0, b1);
  EXPECT_LT(std::abs(var), 1e-12 * r.covariance(b0, b0));
  EXPECT_GT(r.standard_errors(b0), 0.0);
  EXPECT_TRUE(r.converged()) << r.message;
}

TEST(OutputErrorPolish, HeldCoefficientsAndActiveBoundsAreReported) {
  const AdditiveModel truth = second_order(0.0);
  const SampledData data = record(truth, 800, 61);
  OutputErrorPolishOptions options;
  options.estimate_delay = false;
  CoefficientConstraints constraints;
  constraints.coefficients = {{"theta1.a1", 0.41, std::nullopt, std::nullopt},
                              {"theta1.a2", std::nullopt, std::nullopt, 0.2}};
  const OutputErrorPolishResult r =
      polish_output_error(data, perturbed(truth, 0.05, 0.0), std::nullopt, options, constraints);
  EXPECT_EQ(r.parameters(0), 0.41);
  EXPECT_EQ(r.standard_errors(0), 0.0);
  EXPECT_DOUBLE_EQ(r.parameters(1), 0.2);  // the truth 0.25 is outside: the bound is active
  EXPECT_EQ(r.held_parameters, std::vector<std::string>{"theta1.a1"});
  EXPECT_EQ(r.active_bounds, std::vector<std::string>{"theta1.a2"});
  EXPECT_LE(r.cost, r.start_cost);
}

// A bounded b0 after the DC gain's carrier (theta1.b0 carries the gain, theta2.b0 is bounded):
// the bound that acts is named as theta2.b0's.
TEST(OutputErrorPolish, ABoundedB0BesideTheDcGainCarrierIsNamedAsItself) {
  const AdditiveModel truth = two_modes();
  const SampledData data = record(truth, 2000, 81, white_noise(2000, 0.05, 82));
  OutputErrorPolishOptions options;
  options.estimate_delay = false;
  CoefficientConstraints constraints;
  constraints.dc_gain = 3.4;
  constraints.coefficients = {{"theta2.b0", std::nullopt, std::nullopt, 0.35}};  // truth 0.4
  const OutputErrorPolishResult r =
      polish_output_error(data, perturbed(truth, 0.05, 0.0), std::nullopt, options, constraints);
  EXPECT_EQ(r.held_parameters, std::vector<std::string>{"theta1.b0"});
  EXPECT_EQ(r.active_bounds, std::vector<std::string>{"theta2.b0"});
  EXPECT_DOUBLE_EQ(r.parameters(5), 0.35);
  EXPECT_NEAR(r.parameters(2) + r.parameters(5), 3.4, 1e-14);
}

// An unstable plant 1 / (1 - 10 p) (pole at +0.1 rad/s) over 20 s: the free fit is unstable,
// the constrained one stable, and it says so.
TEST(OutputErrorPolish, EnforcedStabilityOnARecordWhoseFreeFitIsUnstable) {
  const AdditiveModel truth({Submodel{Polynomial({1.0, -10.0}), Polynomial({1.0}), 0}});
  const SampledData data = record(truth, 400, 71, white_noise(400, 0.05, 72));
  OutputErrorPolishOptions options;
  options.estimate_delay = false;
  options.keep_stable = false;
  const OutputErrorPolishResult free = polish_output_error(data, truth, std::nullopt, options);
  EXPECT_FALSE(free.transfer_function.is_stable());
  EXPECT_FALSE(free.verdict.usable);
  options.keep_stable = true;
  const OutputErrorPolishResult held = polish_output_error(data, truth, std::nullopt, options);
  EXPECT_TRUE(held.transfer_function.is_stable());
  EXPECT_TRUE(held.stability_constraint_active);
  EXPECT_GT(held.cost, free.cost);
  // The verdict says so (decision 0058); the free fit's lists nothing.
  EXPECT_THAT(held.verdict.active_constraints,
              ::testing::Contains(::testing::HasSubstr("stability: ")));
  EXPECT_TRUE(free.verdict.active_constraints.empty());
}

void expect_refusal(const AdditiveModel& model, const CoefficientConstraints& constraints,
                    const std::string& fragment, bool delay_free = true) {
  try {
    validate_constraints(model, constraints, delay_free);
    ADD_FAILURE() << "accepted; expected: " << fragment;
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(OutputErrorPolish, ConstraintsThatContradictTheStructureAreRefused) {
  CoefficientConstraints c;
  c.coefficients = {{"theta3.a1", 1.0, std::nullopt, std::nullopt}};
  expect_refusal(two_modes(), c,
                 "'theta3.a1' is not in the model (its parameters: theta1.a1, theta1.a2, "
                 "theta1.b0, theta2.a1, theta2.a2, theta2.b0, tau)");
  c.coefficients = {{"theta1.a1", 1.0, std::nullopt, std::nullopt},
                    {"theta1.a1", std::nullopt, 0.0, std::nullopt}};
  expect_refusal(two_modes(), c, "'theta1.a1' is set twice");
  c.coefficients = {{"theta1.a1", 2.0, 0.0, 1.0}};
  expect_refusal(two_modes(), c, "the held value 2 of theta1.a1 is outside its bounds");
  c.coefficients = {{"tau", std::nullopt, 0.0, 1.0}};
  expect_refusal(two_modes(), c, "a setting of tau needs the delay estimated", false);
  c = {};
  c.dc_gain = 1.0;
  const AdditiveModel integrating({Submodel{Polynomial({1.0, 0.5}), Polynomial({1.0}), 1}});
  expect_refusal(integrating, c, "submodel 1 has an integrator");
  c.coefficients = {{"theta1.b0", 3.0, std::nullopt, std::nullopt},
                    {"theta2.b0", 0.5, std::nullopt, std::nullopt}};
  expect_refusal(two_modes(), c, "the known DC gain 1 contradicts the held b0 values");
  c.coefficients = {{"theta1.b0", std::nullopt, 0.0, std::nullopt},
                    {"theta2.b0", 0.5, std::nullopt, std::nullopt}};
  expect_refusal(two_modes(), c, "needs a b0 that is neither held nor bounded");
}

TEST(OutputErrorPolish, HeldCoefficientsForTheIvAreTheDeterminedOnes) {
  CoefficientConstraints c;
  c.dc_gain = 2.5;
  c.coefficients = {{"theta1.a2", 0.3, std::nullopt, std::nullopt}};
  using Held = std::vector<std::pair<Eigen::Index, double>>;
  // One submodel: b0 is the DC gain.
  EXPECT_EQ(held_coefficients(second_order(0.0), c), (Held{{1, 0.3}, {2, 2.5}}));
  // Two submodels with both b0 free: the gain couples them, so no b0 is held.
  c.coefficients.clear();
  EXPECT_EQ(held_coefficients(two_modes(), c), Held{});
  // One of them held: the other carries the rest.
  c.coefficients = {{"theta1.b0", 2.0, std::nullopt, std::nullopt}};
  EXPECT_EQ(held_coefficients(two_modes(), c), (Held{{2, 2.0}, {5, 0.5}}));
}

TEST(OutputErrorPolish, RefusesBadInputWithOneClearMessage) {
  const AdditiveModel truth = second_order(0.0);
  const SampledData data = record(truth, 40, 41);
  EXPECT_THROW(
      {
        try {
          polish_output_error(data, truth);
        } catch (const InvalidArgument& e) {
          EXPECT_NE(std::string(e.what()).find("needs 50 samples"), std::string::npos) << e.what();
          throw;
        }
      },
      InvalidArgument);
  const Eigen::VectorXd u = white_noise(200, 1.0, 3);
  const SampledData loop(kH, u, simulate(truth, u, kH), u);
  EXPECT_THROW(
      {
        try {
          polish_output_error(loop, truth);
        } catch (const InvalidArgument& e) {
          EXPECT_NE(std::string(e.what()).find("open-loop"), std::string::npos) << e.what();
          throw;
        }
      },
      InvalidArgument);
  OutputErrorPolishOptions bad;
  bad.max_iterations = 0;
  EXPECT_THROW(polish_output_error(record(truth, 200, 5), truth, std::nullopt, bad),
               InvalidArgument);
}

}  // namespace
}  // namespace ctid::output_error_polish_test
