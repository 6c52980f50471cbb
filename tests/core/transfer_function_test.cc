#include "ctid/core/transfer_function.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/LU>

#include "ctid/core/error.h"
#include "support/paper_systems.h"

namespace ctid::transfer_function_test {
namespace {

using ::testing::HasSubstr;

TEST(TransferFunction, ValueDcGainAndProperness) {
  const TransferFunction g(Polynomial({2.0, 1.0}), Polynomial({4.0, 3.0, 1.0}));
  EXPECT_DOUBLE_EQ(g.dc_gain(), 0.5);
  EXPECT_TRUE(g.is_strictly_proper());
  EXPECT_FALSE(g.is_biproper());
  const std::complex<double> s(0.3, -1.2);
  EXPECT_NEAR(std::abs(g(s) - (2.0 + s) / (4.0 + 3.0 * s + s * s)), 0.0, 1e-15);
  const TransferFunction integrator(Polynomial({1.0}), Polynomial({0.0, 1.0}));
  EXPECT_TRUE(std::isinf(integrator.dc_gain()));
  EXPECT_TRUE(TransferFunction(Polynomial({1.0, 1.0}), Polynomial({1.0, 1.0})).is_biproper());
}

TEST(TransferFunction, ConjugateSymmetryAndDelay) {
  const TransferFunction g =
      testing::open_loop_four_modes().to_transfer_function().with_input_delay(0.2);
  for (double w : {0.1, 1.39, 5.0, 30.0}) {
    EXPECT_NEAR(std::abs(g.frequency_response(-w) - std::conj(g.frequency_response(w))), 0.0,
                1e-12);
    const std::complex<double> no_delay =
        g.numerator()(std::complex<double>(0, w)) / g.denominator()(std::complex<double>(0, w));
    EXPECT_NEAR(std::abs(g.frequency_response(w) - no_delay * std::polar(1.0, -0.2 * w)), 0.0,
                1e-12);
  }
}

TEST(TransferFunction, RejectsBadInput) {
  EXPECT_THAT([] { TransferFunction(Polynomial({1.0}), Polynomial()); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("denominator")));
  EXPECT_THAT(
      [] {
        TransferFunction(Polynomial({1.0}), Polynomial({1.0, 1.0}), -0.1);
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("delay")));
  EXPECT_THAT(
      [] {
        TransferFunction(Polynomial({1.0, 1.0, 1.0}), Polynomial({1.0, 1.0})).to_state_space();
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("improper")));
}

void expect_same_response(const TransferFunction& a, const TransferFunction& b, double tol) {
  for (double w : {0.0, 0.05, 1.0, 1.39, 3.16, 5.77, 9.99, 50.0, 500.0}) {
    const std::complex<double> ga = a.frequency_response(w);
    const std::complex<double> gb = b.frequency_response(w);
    if (!std::isfinite(std::abs(ga))) continue;  // a pole at the origin, w = 0
    EXPECT_NEAR(std::abs(ga - gb), 0.0, tol * std::max(1.0, std::abs(ga))) << "w = " << w;
  }
}

TEST(TransferFunction, StateSpaceRoundTripEightPoles) {
  const TransferFunction g = testing::open_loop_four_modes().to_transfer_function();
  ASSERT_EQ(g.denominator().degree(), 8);
  const StateSpace ss = g.to_state_space();
  ss.validate();
  // Well conditioned: entries bounded by a modest multiple of the largest pole magnitude
  // (a raw companion form of this anti-monic denominator has entries ~1e4).
  EXPECT_LT(ss.a.cwiseAbs().maxCoeff(), 50.0);
  const TransferFunction back = TransferFunction::from_state_space(ss);
  expect_same_response(g, back, 1e-10);
  EXPECT_EQ(back.denominator().degree(), 8);
}

TEST(TransferFunction, StateSpaceRoundTripBiproperWithIntegratorAndFastPole) {
  // (s^2 + 3 s + 2) / (s (s + 1e3)) : a pole at the origin, one far away, and feedthrough.
  const TransferFunction g(Polynomial({2.0, 3.0, 1.0}), Polynomial({0.0, 1e3, 1.0}));
  const StateSpace ss = g.to_state_space();
  EXPECT_DOUBLE_EQ(ss.d, 1.0);
  expect_same_response(TransferFunction(g.numerator(), g.denominator()),
                       TransferFunction::from_state_space(ss), 1e-10);
  // The realisation's own response equals G at a test point.
  const std::complex<double> s(0.5, 2.0);
  const Eigen::MatrixXcd resolvent =
      (s * Eigen::MatrixXcd::Identity(2, 2) - ss.a.cast<std::complex<double>>()).inverse();
  const std::complex<double> value =
      (ss.c.cast<std::complex<double>>() * resolvent * ss.b.cast<std::complex<double>>())(0) + ss.d;
  EXPECT_NEAR(std::abs(value - g(s)), 0.0, 1e-12 * std::abs(g(s)));
}

TEST(TransferFunction, PolesAndZerosAndStability) {
  const TransferFunction g(Polynomial({-1.0, 1.0}), Polynomial({2.0, 3.0, 1.0}));
  EXPECT_TRUE(g.is_stable());
  EXPECT_NEAR(g.zeros()(0).real(), 1.0, 1e-14);
  EXPECT_FALSE(TransferFunction(Polynomial({1.0}), Polynomial({-1.0, 1.0})).is_stable());
  EXPECT_FALSE(TransferFunction(Polynomial({1.0}), Polynomial({0.0, 1.0})).is_stable());
}

TEST(TransferFunction, SumAndProduct) {
  const TransferFunction a(Polynomial({1.0}), Polynomial({1.0, 1.0}));
  const TransferFunction b(Polynomial({2.0}), Polynomial({3.0, 1.0}), 0.0);
  const std::complex<double> s(0.2, 0.9);
  EXPECT_NEAR(std::abs((a + b)(s) - (a(s) + b(s))), 0.0, 1e-15);
  EXPECT_NEAR(std::abs((a * b)(s)-a(s) * b(s)), 0.0, 1e-15);
  EXPECT_THROW(a + b.with_input_delay(1.0), InvalidArgument);
}

}  // namespace
}  // namespace ctid::transfer_function_test
