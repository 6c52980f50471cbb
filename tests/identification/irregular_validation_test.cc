// validate_model on irregular time stamps (irregular_validation.h, decision 0053): on uniform
// stamps simulate_on_stamps is the uniform simulation with either hold; a noise-free jittered
// record with equal stamps and a gap validates at 100 % with the hold it was made with; the
// residual is the added noise exactly; the window scores the stamps inside it; what is not
// supported is refused by content.
#include "ctid/identification/irregular_validation.h"

#include <cmath>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/simulation/stamps.h"

namespace ctid::irregular_validation_test {
namespace {

using ::testing::HasSubstr;

AdditiveModel second_order() {
  return AdditiveModel({Submodel{Polynomial{1.0, 0.4, 0.25}, Polynomial{2.0, 0.3}, 0}});
}

Eigen::VectorXd gaussian(Eigen::Index n, std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> normal;
  Eigen::VectorXd v(n);
  for (Eigen::Index k = 0; k < n; ++k) v(k) = normal(engine);
  return v;
}

// Stamps 0.05 k ±30 %, every 50th repeated, stamps 200-239 missing.
IrregularRecord jittered_record(Hold hold, std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::vector<double> t;
  for (int k = 0; k < 600; ++k) {
    if (k >= 200 && k < 240) continue;
    t.push_back(0.05 * (k + (k == 0 ? 0.0 : jitter(engine))));
    if (k % 50 == 25) t.push_back(t.back());
  }
  IrregularRecord r;
  r.time = Eigen::Map<Eigen::VectorXd>(t.data(), static_cast<Eigen::Index>(t.size()));
  r.input = gaussian(r.time.size(), seed + 1);
  r.input_hold = hold;
  r.output = simulate_on_stamps(second_order(), r.time, r.input, hold);
  return r;
}

TEST(IrregularValidation, UniformStampsGiveTheUniformSimulationWithEitherHold) {
  const double h = 0.05;
  const Eigen::Index n = 500;
  const Eigen::VectorXd u = gaussian(n, 3);
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, 2.0, 2.0 + (n - 1) * h);
  for (Hold hold : {Hold::zero_order_hold, Hold::first_order_hold}) {
    const Eigen::VectorXd expected = model_output(second_order(), u, h, hold);
    const Eigen::VectorXd y = simulate_on_stamps(second_order(), t, u, hold);
    EXPECT_LT((y - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff())
        << enum_name(hold);
  }
}

TEST(IrregularValidation, UniformStampsWithADelayGiveTheUniformSimulationWithEitherHold) {
  const double h = 0.05;
  const Eigen::Index n = 400;
  const Eigen::VectorXd u = gaussian(n, 4);
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, 1.0, 1.0 + (n - 1) * h);
  for (double tau : {3 * h, 2.37 * h, 0.4 * h}) {
    const AdditiveModel g = second_order().with_input_delay(tau);
    for (Hold hold : {Hold::zero_order_hold, Hold::first_order_hold}) {
      const Eigen::VectorXd expected = model_output(g, u, h, hold);
      const Eigen::VectorXd y = simulate_on_stamps(g, t, u, hold);
      EXPECT_LT((y - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff())
          << enum_name(hold) << ", tau = " << tau;
    }
  }
}

TEST(IrregularValidation, ADelayedModelValidatesAtAHundredPercentOnItsOwnRecord) {
  IrregularRecord r = jittered_record(Hold::first_order_hold, 6);
  const AdditiveModel g = second_order().with_input_delay(0.137);
  r.output = simulate_on_stamps(g, r.time, r.input, r.input_hold);
  EXPECT_NEAR(validate_model(g, r).fit_percent, 100.0, 1e-9);
  EXPECT_LT(validate_model(second_order(), r).fit_percent, 99.0);
}

TEST(IrregularValidation, NoiseFreeRecordValidatesAtAHundredPercentWithItsHold) {
  for (Hold hold : {Hold::zero_order_hold, Hold::first_order_hold}) {
    const IrregularRecord r = jittered_record(hold, 5);
    const ValidationReport report = validate_model(second_order(), r);
    EXPECT_NEAR(report.fit_percent, 100.0, 1e-9) << enum_name(hold);
    EXPECT_EQ(report.fit_zero_state, report.fit_percent);
    EXPECT_TRUE(std::isnan(report.fit_estimated_state));
    EXPECT_EQ(report.window_samples, r.time.size());
    EXPECT_EQ(report.window_start, r.time(0));
    EXPECT_EQ(report.window_end, r.time(r.time.size() - 1));
    EXPECT_NEAR(report.whiteness_bound, 2.58 / std::sqrt(double(r.time.size())), 1e-15);
    // The other hold is a different input between the stamps: the fit is visibly worse.
    IrregularRecord wrong = r;
    wrong.input_hold =
        hold == Hold::zero_order_hold ? Hold::first_order_hold : Hold::zero_order_hold;
    EXPECT_LT(validate_model(second_order(), wrong).fit_percent, 99.0) << enum_name(hold);
  }
}

TEST(IrregularValidation, TheResidualIsTheAddedNoise) {
  IrregularRecord r = jittered_record(Hold::zero_order_hold, 8);
  const Eigen::VectorXd noise = 0.1 * gaussian(r.time.size(), 99);
  r.output += noise;
  const ValidationReport report = validate_model(second_order(), r);
  EXPECT_NEAR(report.residual_mean, noise.mean(), 1e-12);
  EXPECT_NEAR(report.mean_squared_error, noise.squaredNorm() / double(noise.size()), 1e-12);
  const Eigen::VectorXd centred = noise.array() - noise.mean();
  EXPECT_NEAR(report.residual_std, std::sqrt(centred.squaredNorm() / double(noise.size())), 1e-12);
  EXPECT_EQ(report.max_lag, 20);
  EXPECT_EQ(report.residual_autocorrelation.size(), 20);
}

TEST(IrregularValidation, TheWindowScoresTheStampsInsideIt) {
  const IrregularRecord r = jittered_record(Hold::first_order_hold, 2);
  ValidationOptions options;
  options.window_start = 5.0;
  options.window_end = 20.0;
  const ValidationReport report = validate_model(second_order(), r, options);
  int inside = 0;
  for (Eigen::Index k = 0; k < r.time.size(); ++k) inside += r.time(k) >= 5.0 && r.time(k) <= 20.0;
  EXPECT_EQ(report.window_samples, inside);
  EXPECT_GE(report.window_start, 5.0);
  EXPECT_LE(report.window_end, 20.0);
  EXPECT_NEAR(report.fit_percent, 100.0, 1e-9);
  options.window_end = 1000.0;
  try {
    validate_model(second_order(), r, options);
    FAIL() << "a window beyond the record was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("the window [5, 1000] s is not inside the record"));
  }
}

TEST(IrregularValidation, WhatIsNotSupportedIsRefusedByContent) {
  IrregularRecord r = jittered_record(Hold::zero_order_hold, 4);
  ValidationOptions options;
  options.initial_state = InitialState::estimate;
  try {
    validate_model(second_order(), r, options);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("initial_state = estimate is not supported on irregular"));
  }
  std::swap(r.time(10), r.time(11));
  try {
    validate_model(second_order(), r);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("time stamp 11"));
    EXPECT_THAT(e.what(), HasSubstr("goes back before stamp 10"));
  }
}

}  // namespace
}  // namespace ctid::irregular_validation_test
