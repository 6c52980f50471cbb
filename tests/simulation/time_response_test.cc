// Closed forms of step and impulse responses and their characteristics, and the delta-method
// standard errors against their analytic gradients.
#include "ctid/simulation/time_response.h"

#include <cmath>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"

namespace ctid::time_response_test {
namespace {

using ::testing::HasSubstr;

// K / (T p + 1).
AdditiveModel first_order(double gain, double time_constant, double delay = 0.0) {
  return AdditiveModel({Submodel{Polynomial({1.0, time_constant}), Polynomial({gain}), 0}}, delay);
}

// K w^2 / (p^2 + 2 zeta w p + w^2), written anti-monic.
AdditiveModel second_order(double gain, double zeta, double omega) {
  return AdditiveModel({Submodel{Polynomial({1.0, 2.0 * zeta / omega, 1.0 / (omega * omega)}),
                                 Polynomial({gain}), 0}});
}

TEST(StepResponse, FirstOrderClosedForm) {
  const double k = 2.5;
  const double t = 0.7;
  const Eigen::VectorXd times = Eigen::VectorXd::LinSpaced(50, 0.0, 5.0);
  const Eigen::VectorXd y = step_response(first_order(k, t), times);
  for (Eigen::Index i = 0; i < times.size(); ++i) {
    EXPECT_NEAR(y(i), k * (1.0 - std::exp(-times(i) / t)), 1e-13) << "t = " << times(i);
  }
  TimeResponseOptions options;
  options.final_time = 5.0;
  options.points = 501;
  const TimeResponse grid = time_response(first_order(k, t), {}, options);
  for (Eigen::Index i = 0; i < grid.time.size(); ++i) {
    EXPECT_NEAR(grid.output(i), k * (1.0 - std::exp(-grid.time(i) / t)), 1e-12);
  }
  EXPECT_EQ(grid.standard_deviation.size(), 0);
}

TEST(StepCharacteristics, FirstOrderRiseAndSettlingTimes) {
  const double t = 0.7;
  const StepCharacteristics c = step_characteristics(first_order(3.0, t));
  EXPECT_TRUE(c.stable);
  EXPECT_TRUE(c.defined());
  EXPECT_NEAR(c.dc_gain.value, 3.0, 1e-14);
  EXPECT_NEAR(c.rise_time.value, t * std::log(9.0), 1e-12);
  EXPECT_NEAR(c.settling_time.value, t * std::log(50.0), 1e-12);
  EXPECT_EQ(c.overshoot_percent.value, 0.0);
  EXPECT_EQ(c.undershoot_percent.value, 0.0);
  EXPECT_TRUE(std::isnan(c.peak_time.value));
  EXPECT_TRUE(std::isnan(c.rise_time.standard_error));  // no covariance
  const StepCharacteristics five = step_characteristics(first_order(3.0, t), {}, 0.05);
  EXPECT_NEAR(five.settling_time.value, t * std::log(20.0), 1e-12);
}

TEST(StepCharacteristics, SecondOrderOvershootAndPeakTime) {
  for (double zeta : {0.05, 0.3, 0.7}) {
    const double omega = 4.0;
    const StepCharacteristics c = step_characteristics(second_order(-1.5, zeta, omega));
    const double damped = omega * std::sqrt(1.0 - zeta * zeta);
    EXPECT_NEAR(c.dc_gain.value, -1.5, 1e-14);
    EXPECT_NEAR(c.overshoot_percent.value,
                100.0 * std::exp(-std::numbers::pi * zeta / std::sqrt(1.0 - zeta * zeta)), 1e-9)
        << "zeta = " << zeta;
    EXPECT_NEAR(c.peak_time.value, std::numbers::pi / damped, 1e-9) << "zeta = " << zeta;
    // Settling: the last time |e(t)| = 0.02, e(t) = exp(-zeta w t) cos(w_d t - phi)/sqrt(1-z^2).
    const double s = c.settling_time.value;
    const double phi = std::atan(zeta / std::sqrt(1.0 - zeta * zeta));
    const auto error = [&](double x) {
      return std::exp(-zeta * omega * x) * std::cos(damped * x - phi) /
             std::sqrt(1.0 - zeta * zeta);
    };
    EXPECT_NEAR(std::abs(error(s)), 0.02, 1e-9) << "zeta = " << zeta;
    for (double x = s + 1e-6; x < s + 20.0 / (zeta * omega); x += 0.01) {
      ASSERT_LE(std::abs(error(x)), 0.02) << "zeta = " << zeta << ", t = " << x;
    }
  }
}

TEST(StepCharacteristics, DelayShiftsTheResponse) {
  const double tau = 0.35;
  const AdditiveModel plain = second_order(1.0, 0.2, 3.0);
  const AdditiveModel delayed = plain.with_input_delay(tau);
  const Eigen::VectorXd times = Eigen::VectorXd::LinSpaced(40, 0.0, 4.0);
  const Eigen::VectorXd y = step_response(delayed, times);
  const Eigen::VectorXd shifted = step_response(plain, (times.array() - tau).max(0.0).matrix());
  for (Eigen::Index i = 0; i < times.size(); ++i) {
    EXPECT_NEAR(y(i), times(i) < tau ? 0.0 : shifted(i), 1e-13) << "t = " << times(i);
  }
  const StepCharacteristics a = step_characteristics(plain);
  const StepCharacteristics b = step_characteristics(delayed);
  EXPECT_NEAR(b.rise_time.value, a.rise_time.value, 1e-11);
  EXPECT_NEAR(b.settling_time.value, a.settling_time.value + tau, 1e-11);
  EXPECT_NEAR(b.peak_time.value, a.peak_time.value + tau, 1e-11);
  EXPECT_NEAR(b.overshoot_percent.value, a.overshoot_percent.value, 1e-9);
  // The uniform grid (state carried from the first sample after the delay) agrees.
  TimeResponseOptions options;
  options.final_time = 4.0;
  options.points = 41;
  const TimeResponse grid = time_response(delayed, {}, options);
  for (Eigen::Index i = 0; i < grid.time.size(); ++i) {
    EXPECT_NEAR(grid.output(i), step_response(delayed, grid.time.segment(i, 1))(0), 1e-12);
  }
}

TEST(ImpulseResponse, IsTheDerivativeOfTheStepResponse) {
  const AdditiveModel g({Submodel{Polynomial({1.0, 0.2, 0.04}), Polynomial({1.0, 0.3}), 0},
                         Submodel{Polynomial({1.0, 0.5}), Polynomial({-0.4}), 0}},
                        0.1);
  const Eigen::VectorXd times = Eigen::VectorXd::LinSpaced(30, 0.15, 3.0);
  const double d = 1e-6;
  const Eigen::VectorXd slope = (step_response(g, (times.array() + d).matrix()) -
                                 step_response(g, (times.array() - d).matrix())) /
                                (2.0 * d);
  const Eigen::VectorXd impulse = impulse_response(g, times);
  for (Eigen::Index i = 0; i < times.size(); ++i) {
    EXPECT_NEAR(impulse(i), slope(i), 1e-7 * (1.0 + std::abs(slope(i)))) << "t = " << times(i);
  }
  // First order: K/T e^{-t/T}.
  const Eigen::VectorXd h = impulse_response(first_order(2.0, 0.5), times);
  for (Eigen::Index i = 0; i < times.size(); ++i) {
    EXPECT_NEAR(h(i), 4.0 * std::exp(-times(i) / 0.5), 1e-12);
  }
  TimeResponseOptions options;
  options.kind = ResponseKind::impulse;
  options.final_time = 3.0;
  const TimeResponse grid = time_response(first_order(2.0, 0.5), {}, options);
  EXPECT_NEAR(grid.output(0), 4.0, 1e-12);
  EXPECT_NEAR(grid.output(grid.time.size() - 1), 4.0 * std::exp(-6.0), 1e-12);
  EXPECT_EQ(grid.dirac_weight, 0.0);
}

TEST(StepCharacteristics, NonMinimumPhaseUndershoot) {
  // (1 - s)/(1 + s)^2: y = 1 - e^-t - 2 t e^-t, trough at t = 0.5 of 1 - 2 e^-0.5.
  const AdditiveModel g({Submodel{Polynomial({1.0, 2.0, 1.0}), Polynomial({1.0, -1.0}), 0}});
  const StepCharacteristics c = step_characteristics(g);
  EXPECT_NEAR(c.undershoot_percent.value, -100.0 * (1.0 - 2.0 * std::exp(-0.5)), 1e-9);
  EXPECT_EQ(c.overshoot_percent.value, 0.0);
  const Eigen::VectorXd y = step_response(g, Eigen::VectorXd::Constant(1, 2.0));
  EXPECT_NEAR(y(0), 1.0 - 5.0 * std::exp(-2.0), 1e-13);
}

TEST(StepCharacteristics, IntegratorAndUnstableModelsSayWhy) {
  const AdditiveModel integrator({Submodel{Polynomial({1.0}), Polynomial({2.0}), 1}});
  const StepCharacteristics c = step_characteristics(integrator);
  EXPECT_FALSE(c.stable);
  EXPECT_FALSE(c.defined());
  EXPECT_THAT(c.not_defined_reason, HasSubstr("integrator"));
  EXPECT_TRUE(std::isnan(c.dc_gain.value));
  EXPECT_TRUE(std::isnan(c.rise_time.value));
  // 2/s: a ramp of slope 2.
  const Eigen::VectorXd y = step_response(integrator, Eigen::VectorXd::Constant(1, 1.5));
  EXPECT_NEAR(y(0), 3.0, 1e-13);
  TimeResponseOptions options;  // default final time from the slowest pole: 10 s here
  EXPECT_NEAR(time_response(integrator, {}, options).time.tail(1)(0), 10.0, 1e-12);

  const AdditiveModel unstable({Submodel{Polynomial({1.0, -0.5}), Polynomial({1.0}), 0}});
  const StepCharacteristics u = step_characteristics(unstable);
  EXPECT_FALSE(u.stable);
  EXPECT_THAT(u.not_defined_reason, HasSubstr("not stable"));
  EXPECT_TRUE(std::isnan(u.settling_time.value));
}

TEST(StepCharacteristics, StandardErrorsMatchTheAnalyticDeltaMethod) {
  // theta = [a1, b0] of b0 / (1 + a1 p): DC gain b0, rise a1 ln 9, settling a1 ln 50.
  const double a1 = 0.8;
  const double b0 = 1.7;
  Eigen::MatrixXd p(2, 2);
  p << 4e-4, -1e-4, -1e-4, 9e-4;
  const StepCharacteristics c = step_characteristics(first_order(b0, a1), p, 0.02, 0.01);
  EXPECT_NEAR(c.dc_gain.standard_error, std::sqrt(p(1, 1)), 1e-9);
  EXPECT_NEAR(c.rise_time.standard_error, std::log(9.0) * std::sqrt(p(0, 0)), 1e-7);
  // The delay's standard error adds in quadrature to the times counted from the step.
  EXPECT_NEAR(c.settling_time.standard_error, std::hypot(std::log(50.0) * std::sqrt(p(0, 0)), 0.01),
              1e-7);

  // Two submodels: the DC gain is b_10 + b_20, its variance the sum of their block.
  const AdditiveModel two({Submodel{Polynomial({1.0, 0.2, 0.04}), Polynomial({1.0, 0.3}), 0},
                           Submodel{Polynomial({1.0, 0.5}), Polynomial({-0.4}), 0}});
  // theta = [a11 a12 b10 b11 | a21 b20]: b10 at 2, b20 at 5.
  Eigen::MatrixXd q = Eigen::MatrixXd::Identity(6, 6) * 1e-4;
  q(2, 5) = q(5, 2) = 3e-5;
  q(2, 0) = q(0, 2) = -2e-5;
  const StepCharacteristics s = step_characteristics(two, q);
  EXPECT_NEAR(s.dc_gain.value, 0.6, 1e-14);
  EXPECT_NEAR(s.dc_gain.standard_error, std::sqrt(q(2, 2) + q(5, 5) + 2.0 * q(2, 5)), 1e-9);
}

TEST(TimeResponse, BandIsTheDeltaMethodOfTheResponse) {
  const double a1 = 0.8;
  const double b0 = 1.7;
  Eigen::MatrixXd p(2, 2);
  p << 4e-4, -1e-4, -1e-4, 9e-4;
  TimeResponseOptions options;
  options.final_time = 4.0;
  options.points = 81;
  options.confidence = 0.9;
  const TimeResponse r = time_response(first_order(b0, a1), p, options);
  EXPECT_NEAR(r.z, 1.6448536269514722, 1e-12);
  for (Eigen::Index i = 0; i < r.time.size(); ++i) {
    const double t = r.time(i);
    const double e = std::exp(-t / a1);
    Eigen::RowVector2d g(-b0 * e * t / (a1 * a1), 1.0 - e);
    const double sd = std::sqrt(g.dot(p * g.transpose()));
    EXPECT_NEAR(r.standard_deviation(i), sd, 1e-8) << "t = " << t;
    EXPECT_NEAR(r.upper(i) - r.lower(i), 2.0 * r.z * sd, 1e-7);
  }
}

TEST(TimeResponse, BadInputIsRefusedBeforeAllocating) {
  TimeResponseOptions options;
  options.final_time = 1e6;
  options.sample_time = 1e-3;
  EXPECT_THAT([&] { time_response(first_order(1.0, 1.0), {}, options); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("at most 1000000")));
  options = {};
  options.final_time = 0.0;
  EXPECT_THAT([&] { time_response(first_order(1.0, 1.0), {}, options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("TimeResponseOptions.final_time is 0; it must be finite and > 0")));
  options = {};
  options.points = 2'000'000;
  EXPECT_THAT([&] { time_response(first_order(1.0, 1.0), {}, options); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("points is 2000000")));
  EXPECT_THAT([&] { time_response(first_order(1.0, 1.0), Eigen::MatrixXd::Identity(3, 3)); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("model has 2 parameters")));
  const TransferFunction improper(Polynomial({0.0, 0.0, 1.0}), Polynomial({1.0, 1.0}));
  EXPECT_THAT([&] { step_response(improper, Eigen::VectorXd::Zero(1)); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("the model is improper")));
}

}  // namespace
}  // namespace ctid::time_response_test
