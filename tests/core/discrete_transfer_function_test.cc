#include "ctid/core/discrete_transfer_function.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "support/paper_systems.h"

namespace ctid::discrete_transfer_function_test {
namespace {

using ::testing::HasSubstr;

TEST(DiscreteTransferFunction, NoiseFilterImpulseResponseClosedForm) {
  // (q + 0.5)/(q - 0.85): h_0 = 1, h_k = 1.35 * 0.85^(k-1).
  const DiscreteTransferFunction f = testing::open_loop_noise_filter();
  Eigen::VectorXd impulse = Eigen::VectorXd::Zero(40);
  impulse(0) = 1.0;
  const Eigen::VectorXd h = f.filter(impulse);
  EXPECT_DOUBLE_EQ(h(0), 1.0);
  for (int k = 1; k < 40; ++k) EXPECT_NEAR(h(k), 1.35 * std::pow(0.85, k - 1), 1e-14);
  EXPECT_NEAR(f.dc_gain(), 1.5 / 0.15, 1e-12);
  EXPECT_TRUE(f.is_stable());
  EXPECT_TRUE(f.is_biproper());
}

TEST(DiscreteTransferFunction, StateSpaceAgreesWithFilter) {
  const DiscreteTransferFunction f(Polynomial({0.1, -0.4, 2.0}), Polynomial({0.2, -0.9, 1.0}), 1.0);
  const StateSpace ss = f.to_state_space();
  Eigen::VectorXd x(25);
  for (int k = 0; k < 25; ++k) x(k) = std::sin(0.7 * k) + 0.1 * k;
  const Eigen::VectorXd y = f.filter(x);
  Eigen::VectorXd state = Eigen::VectorXd::Zero(ss.order());
  for (int k = 0; k < 25; ++k) {
    const double out = ss.c.dot(state) + ss.d * x(k);
    EXPECT_NEAR(out, y(k), 1e-12);
    state = ss.a * state + ss.b * x(k);
  }
}

TEST(DiscreteTransferFunction, FrequencyResponseOnUnitCircle) {
  const DiscreteTransferFunction f(Polynomial({1.0}), Polynomial({-0.5, 1.0}), 0.1);
  const double w = 3.0;
  const std::complex<double> z = std::polar(1.0, w * 0.1);
  EXPECT_NEAR(std::abs(f.frequency_response(w) - 1.0 / (z - 0.5)), 0.0, 1e-15);
  EXPECT_NEAR(std::abs(f.frequency_response(-w) - std::conj(f.frequency_response(w))), 0.0, 1e-15);
}

TEST(DiscreteTransferFunction, RejectsNonCausalAndBadSampleTime) {
  EXPECT_THAT(
      [] {
        DiscreteTransferFunction(Polynomial({0.0, 0.0, 1.0}), Polynomial({1.0, 1.0}), 1.0);
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("proper")));
  EXPECT_THAT(
      [] {
        DiscreteTransferFunction(Polynomial({1.0}), Polynomial({1.0, 1.0}), 0.0);
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("sample time")));
  EXPECT_FALSE(
      DiscreteTransferFunction(Polynomial({1.0}), Polynomial({-1.2, 1.0}), 1.0).is_stable());
}

}  // namespace
}  // namespace ctid::discrete_transfer_function_test
