// validate_model with ValidationOptions: the estimated initial state and the scoring window.
// The record is simulated here from a non-zero state by the ZOH equivalent of the simulation
// layer (a realisation other than the one validation uses), so exact recovery tests the span
// of the free responses, not one basis.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/estimation/validation.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::validation_initial_state_test {
namespace {

constexpr double kH = 0.05;
constexpr int kN = 2000;

// A lightly damped mode (omega_n = 2 rad/s, zeta = 0.05) beside a first-order one.
AdditiveModel two_modes() {
  return AdditiveModel({Submodel{Polynomial{1.0, 0.05, 0.25}, Polynomial{2.0}, 0},
                        Submodel{Polynomial{1.0, 0.5}, Polynomial{1.0}, 0}},
                       0.0);
}

struct Record {
  SampledData data;
  Eigen::VectorXd free;  ///< the part of y due to the initial state
};

// y = the discrete realisation's response from state x0 to the ZOH input u.
Record record_from_state(const AdditiveModel& model, const Eigen::VectorXd& x0) {
  const Eigen::VectorXd u = white_noise(kN, 1.0, 7);
  const StateSpace d = zoh_equivalent(model, kH);
  Eigen::VectorXd y(kN);
  Eigen::VectorXd free(kN);
  Eigen::VectorXd x = x0;
  Eigen::VectorXd z = x0;
  for (int k = 0; k < kN; ++k) {
    y(k) = d.c.dot(x) + d.d * u(k);
    free(k) = d.c.dot(z);
    x = d.a * x + d.b * u(k);
    z = d.a * z;
  }
  return Record{SampledData(kH, u, y), free};
}

Eigen::VectorXd start_state() {
  Eigen::VectorXd x0(3);
  x0 << 1.5, -2.0, 0.8;
  return x0;
}

TEST(ValidationInitialState, EstimatedStateRecoversANoiseFreeRecordExactly) {
  const Record rec = record_from_state(two_modes(), start_state());
  ASSERT_GT(rec.free.norm(), 0.1 * rec.data.output().norm()) << "the start must matter";
  ValidationOptions options;
  options.initial_state = InitialState::estimate;
  const ValidationReport r = validate_model(two_modes(), rec.data, options);
  EXPECT_GE(r.fit_estimated_state, 99.9999);
  EXPECT_DOUBLE_EQ(r.fit_percent, r.fit_estimated_state);
  EXPECT_EQ(r.initial_state, InitialState::estimate);
  EXPECT_EQ(r.states, 3);
  EXPECT_EQ(r.initial_state_rank, 3);
  EXPECT_EQ(r.window_samples, kN);
  // From rest the transient of the lightly damped mode is left in the residual.
  EXPECT_LT(r.fit_zero_state, 95.0);
  EXPECT_GT(r.fit_estimated_state - r.fit_zero_state, 5.0);
  // The recovered free response is the one that was simulated.
  const Eigen::VectorXd rest = model_output(two_modes(), rec.data.input(), kH);
  const Eigen::VectorXd out = validation_output(two_modes(), rec.data, options);
  EXPECT_LT((out - rest - rec.free).cwiseAbs().maxCoeff(), 1e-8 * rec.free.cwiseAbs().maxCoeff());
  EXPECT_NEAR(r.free_response_rms, rec.free.norm() / std::sqrt(double(kN)), 1e-8 * rec.free.norm());
  // The default options simulate from rest and still report the estimated fit beside it.
  const ValidationReport zero = validate_model(two_modes(), rec.data, ValidationOptions{});
  EXPECT_DOUBLE_EQ(zero.fit_percent, zero.fit_zero_state);
  EXPECT_DOUBLE_EQ(zero.fit_estimated_state, r.fit_estimated_state);
  EXPECT_EQ((validation_output(two_modes(), rec.data, ValidationOptions{}) - rest).norm(), 0.0);
}

TEST(ValidationInitialState, WindowScoresTheSliceOfTheSimulationFromTheRecordStart) {
  const Record rec = record_from_state(two_modes(), start_state());
  const Eigen::VectorXd rest = model_output(two_modes(), rec.data.input(), kH);
  ValidationOptions options;
  options.window_start = 20.0;  // sample 400
  options.window_end = 60.0;    // sample 1200
  options.max_lag = 5;
  const ValidationReport r = validate_model(two_modes(), rec.data, options);
  ASSERT_EQ(r.window_samples, 801);
  EXPECT_DOUBLE_EQ(r.window_start, 400 * kH);
  EXPECT_DOUBLE_EQ(r.window_end, 1200 * kH);
  const Eigen::VectorXd y = rec.data.output().segment(400, 801);
  const Eigen::VectorXd m = rest.segment(400, 801);
  EXPECT_DOUBLE_EQ(r.fit_zero_state, fit_percent(y, m));
  EXPECT_DOUBLE_EQ(r.fit_percent, r.fit_zero_state);
  EXPECT_NEAR(r.mean_squared_error, (y - m).squaredNorm() / 801.0, 1e-15);
  EXPECT_NEAR(r.whiteness_bound, 2.58 / std::sqrt(801.0), 1e-15);
  // Fitted on the window only, the state reproduces the window. The first-order mode's free
  // response (time constant 0.5 s) is below e^-40 of its start by t = 20 s: the window
  // cannot see it, so its direction is truncated rather than fitted to rounding noise.
  options.initial_state = InitialState::estimate;
  const ValidationReport e = validate_model(two_modes(), rec.data, options);
  EXPECT_GE(e.fit_percent, 99.9999);
  EXPECT_EQ(e.states, 3);
  EXPECT_EQ(e.initial_state_rank, 2);
  const Eigen::VectorXd out = validation_output(two_modes(), rec.data, options);
  EXPECT_LT((out - rec.data.output()).segment(400, 801).cwiseAbs().maxCoeff(),
            1e-7 * y.cwiseAbs().maxCoeff());
  // A record that does not start at t = 0: the window is on its own time axis.
  const SampledData shifted(kH, rec.data.input(), rec.data.output(), std::nullopt, 100.0);
  options.initial_state = InitialState::zero;
  options.window_start = 120.0;
  options.window_end = 160.0;
  EXPECT_DOUBLE_EQ(validate_model(two_modes(), shifted, options).fit_percent, r.fit_percent);
}

TEST(ValidationInitialState, AModeThatDiedBeforeTheWindowIsNotFittedToNoise) {
  // From t = 8 s the first-order mode (time constant 0.5 s) keeps e^-16 ~ 1e-7 of its start:
  // fitted to the window's noise it would come back ~1e7 times larger at the record's start.
  const Record rec = record_from_state(two_modes(), start_state());
  const Eigen::VectorXd noisy = rec.data.output() + white_noise(kN, 0.01, 3);
  const SampledData data(kH, rec.data.input(), noisy);
  ValidationOptions options;
  options.initial_state = InitialState::estimate;
  options.window_start = 8.0;
  const ValidationReport r = validate_model(two_modes(), data, options);
  EXPECT_EQ(r.initial_state_rank, 2);
  EXPECT_GT(r.fit_estimated_state, 95.0);
  const Eigen::VectorXd out = validation_output(two_modes(), data, options);
  EXPECT_LT(out.cwiseAbs().maxCoeff(), 2.0 * noisy.cwiseAbs().maxCoeff());
}

std::string message_of(const AdditiveModel& model, const SampledData& data,
                       const ValidationOptions& options) {
  try {
    validate_model(model, data, options);
  } catch (const InvalidArgument& error) {
    return error.what();
  }
  return "no error";
}

TEST(ValidationInitialState, AWindowOutsideTheRecordIsRefusedNamingBoth) {
  const Record rec = record_from_state(two_modes(), start_state());
  ValidationOptions options;
  options.window_start = 50.0;
  options.window_end = 120.0;  // the record ends at 99.95 s
  const std::string past_end = message_of(two_modes(), rec.data, options);
  EXPECT_NE(past_end.find("window [50, 120] s"), std::string::npos) << past_end;
  EXPECT_NE(past_end.find("2000 samples"), std::string::npos) << past_end;
  EXPECT_NE(past_end.find("99.95"), std::string::npos) << past_end;
  options.window_start = -1.0;
  options.window_end = 10.0;
  EXPECT_NE(message_of(two_modes(), rec.data, options).find("window [-1, 10] s"),
            std::string::npos);
  options.window_start = 30.0;
  options.window_end = 20.0;
  const std::string reversed = message_of(two_modes(), rec.data, options);
  EXPECT_NE(reversed.find("window_end"), std::string::npos) << reversed;
  options.window_start = 10.01;  // between samples 200 and 201: one sample is not a score
  options.window_end = 10.04;
  const std::string empty = message_of(two_modes(), rec.data, options);
  EXPECT_NE(empty.find("holds 0 samples"), std::string::npos) << empty;
}

}  // namespace
}  // namespace ctid::validation_initial_state_test
