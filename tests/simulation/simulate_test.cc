// Open-loop ZOH simulation against closed-form responses and against equivalent models.
#include "ctid/simulation/simulate.h"

#include <cmath>
#include <complex>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "support/paper_systems.h"

namespace ctid::simulate_test {
namespace {

using ::testing::HasSubstr;

double max_abs(const Eigen::VectorXd& v) { return v.cwiseAbs().maxCoeff(); }

Eigen::VectorXd gaussian(int n, std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> normal;
  Eigen::VectorXd v(n);
  for (int k = 0; k < n; ++k) v(k) = normal(engine);
  return v;
}

TEST(Simulate, FirstOrderStepResponseMatchesClosedForm) {
  const double gain = 2.5;
  const double time_constant = 0.8;
  const double h = 0.05;
  const TransferFunction g(Polynomial{gain}, Polynomial{1.0, time_constant});
  const int n = 400;
  const Eigen::VectorXd y = simulate(g, Eigen::VectorXd::Ones(n), h);
  for (int k = 0; k < n; ++k) {
    const double expected = -gain * std::expm1(-k * h / time_constant);
    EXPECT_NEAR(y(k), expected, 1e-12 * gain) << "k = " << k;
  }
}

TEST(Simulate, SecondOrderModeStepResponseMatchesClosedForm) {
  const double sigma = 0.25;
  const double omega_d = 1.39;
  const double gain = 3.0;
  const AdditiveModel g({testing::mode_from_pole(-sigma, omega_d, gain)});
  const double h = 0.05;
  const int n = 800;
  const Eigen::VectorXd y = simulate(g, Eigen::VectorXd::Ones(n), h);
  for (int k = 0; k < n; ++k) {
    const double t = k * h;
    const double expected =
        gain * (1.0 - std::exp(-sigma * t) *
                          (std::cos(omega_d * t) + sigma / omega_d * std::sin(omega_d * t)));
    EXPECT_NEAR(y(k), expected, 1e-12 * gain) << "k = " << k;
  }
}

TEST(Simulate, PulseResponseOfModeIsDifferenceOfShiftedSteps) {
  // A unit pulse on [t_3, t_4) gives s(t - t_3) - s(t - t_4), s the step response.
  const double sigma = 0.5;
  const double omega_d = 9.99;
  const double h = 0.05;
  const AdditiveModel g({testing::mode_from_pole(-sigma, omega_d, 1.0)});
  Eigen::VectorXd u = Eigen::VectorXd::Zero(200);
  u(3) = 1.0;
  const Eigen::VectorXd y = simulate(g, u, h);
  auto step = [&](double t) {
    if (t <= 0.0) return 0.0;
    return 1.0 -
           std::exp(-sigma * t) * (std::cos(omega_d * t) + sigma / omega_d * std::sin(omega_d * t));
  };
  for (int k = 0; k < 200; ++k) {
    EXPECT_NEAR(y(k), step((k - 3) * h) - step((k - 4) * h), 1e-12) << "k = " << k;
  }
}

TEST(Simulate, AdditivePaperSystemEqualsUnfactoredEquivalent) {
  const AdditiveModel additive = testing::open_loop_four_modes();
  const TransferFunction unfactored = additive.to_transfer_function();
  ASSERT_EQ(unfactored.denominator().degree(), 8);
  const double h = 0.05;
  const Eigen::VectorXd u = gaussian(5000, 11);
  const Eigen::VectorXd y_additive = simulate(additive, u, h);
  const Eigen::VectorXd y_unfactored = simulate(unfactored, u, h);
  EXPECT_LT(max_abs(y_additive - y_unfactored), 1e-12 * max_abs(y_additive));
  // And through the block-diagonal ZOH equivalent.
  const Eigen::VectorXd y_equivalent = simulate_discrete(zoh_equivalent(additive, h), u);
  EXPECT_LT(max_abs(y_additive - y_equivalent), 1e-12 * max_abs(y_additive));
}

TEST(Simulate, SubmodelColumnsSumToModelResponse) {
  const AdditiveModel g = testing::open_loop_four_modes();
  const Eigen::VectorXd u = gaussian(1000, 5);
  const Eigen::MatrixXd parts = simulate_submodels(g, u, 0.05);
  ASSERT_EQ(parts.cols(), 4);
  const Eigen::VectorXd y = simulate(g, u, 0.05);
  EXPECT_LT(max_abs(parts.rowwise().sum() - y), 1e-13 * max_abs(y));
  // Each column is its submodel alone.
  const Eigen::VectorXd second = simulate(AdditiveModel({g[1]}), u, 0.05);
  EXPECT_EQ(Eigen::VectorXd(parts.col(1)), second);
}

TEST(Simulate, IntegratorSubmodelRampAndLag) {
  // 1/p + 1/(1 + p): step response t + 1 - e^{-t}.
  const AdditiveModel g({Submodel{Polynomial{1.0}, Polynomial{1.0}, 1},
                         Submodel{Polynomial{1.0, 1.0}, Polynomial{1.0}}});
  const double h = 0.1;
  const Eigen::VectorXd y = simulate(g, Eigen::VectorXd::Ones(300), h);
  for (int k = 0; k < 300; ++k) {
    const double t = k * h;
    EXPECT_NEAR(y(k), t - std::expm1(-t), 1e-12 * (1.0 + t)) << "k = " << k;
  }
  // The unfactored equivalent (a pole at the origin) gives the same samples.
  const Eigen::VectorXd y_tf = simulate(g.to_transfer_function(), Eigen::VectorXd::Ones(300), h);
  EXPECT_LT(max_abs(y - y_tf), 1e-11 * max_abs(y));
}

TEST(Simulate, BiproperOutputIncludesFeedthroughAtSample) {
  // (1 + 2p)/(1 + p) = 2 - 1/(1 + p): step response 1 + e^{-t}, y_0 = 2.
  const TransferFunction g(Polynomial{1.0, 2.0}, Polynomial{1.0, 1.0});
  const double h = 0.05;
  const Eigen::VectorXd y = simulate(g, Eigen::VectorXd::Ones(100), h);
  for (int k = 0; k < 100; ++k) EXPECT_NEAR(y(k), 1.0 + std::exp(-k * h), 1e-13) << k;
}

TEST(Simulate, IntegerInputDelayShiftsTheResponse) {
  const double h = 0.05;
  const TransferFunction g(Polynomial{1.0, 0.3}, Polynomial{1.0, 0.7, 0.2});
  const Eigen::VectorXd u = gaussian(300, 3);
  const Eigen::VectorXd y0 = simulate(g, u, h);
  const Eigen::VectorXd y4 = simulate(g.with_input_delay(4 * h), u, h);
  EXPECT_EQ(y4.head(4), Eigen::VectorXd::Zero(4));
  EXPECT_LT(max_abs(y4.tail(296) - y0.head(296)), 1e-15);
  // The delayed ZOH equivalent realises the shift as states.
  const Eigen::VectorXd y_equivalent =
      simulate_discrete(zoh_equivalent(g.with_input_delay(4 * h), h), u);
  EXPECT_LT(max_abs(y_equivalent - y4), 1e-14 * max_abs(y4));
  // Additive models carry the delay the same way.
  const AdditiveModel additive = testing::open_loop_four_modes();
  const Eigen::VectorXd ya = simulate(additive, u, h);
  const Eigen::VectorXd ya2 = simulate(additive.with_input_delay(2 * h), u, h);
  EXPECT_LT(max_abs(ya2.tail(298) - ya.head(298)), 1e-15);
}

TEST(Simulate, FractionalDelayStepResponseMatchesClosedForm) {
  // 1/(1 + T p) of a unit step delayed by tau = 2.3 h: y(t) = 1 - e^{-(t - tau)/T}, t > tau.
  const double h = 0.1;
  const double tau = 0.23;
  const double time_constant = 0.4;
  const TransferFunction g(Polynomial{1.0}, Polynomial{1.0, time_constant}, tau);
  const Eigen::VectorXd y = simulate(g, Eigen::VectorXd::Ones(40), h);
  for (int k = 0; k < 40; ++k) {
    const double t = k * h;
    const double expected = t > tau ? 1.0 - std::exp(-(t - tau) / time_constant) : 0.0;
    EXPECT_NEAR(y(k), expected, 1e-14) << "k = " << k;
  }
  const DelaySplit split = split_delay(tau, h);
  EXPECT_EQ(split.samples, 2);
  EXPECT_NEAR(split.fraction, 0.3, 1e-12);
  EXPECT_EQ(split_delay(0.15, 0.05).fraction, 0.0);
}

TEST(Simulate, FractionalDelayOfABiproperModeEqualsItsEquivalent) {
  // A biproper mode with a delay of 3.37 samples: simulate, zoh_equivalent and the
  // submodel split agree, and the ZOH equivalent has 3 + 1 extra states.
  const double h = 0.05;
  const TransferFunction g(Polynomial{0.3, 0.1, 0.02}, Polynomial{1.0, 0.05, 0.04}, 3.37 * h);
  const Eigen::VectorXd u = gaussian(300, 5);
  const Eigen::VectorXd y = simulate(g, u, h);
  const StateSpace discrete = zoh_equivalent(g, h);
  EXPECT_EQ(discrete.order(), 2 + 3 + 1);
  EXPECT_LT(max_abs(simulate_discrete(discrete, u) - y), 1e-12);
  const AdditiveModel additive = AdditiveModel::from_transfer_function(g);
  EXPECT_LT(max_abs(simulate(additive, u, h) - y), 1e-11);
  EXPECT_LT(max_abs(simulate_submodels(additive, u, h).rowwise().sum() - y), 1e-11);
}

TEST(Simulate, DelayInSamplesNamesAFractionalDelay) {
  try {
    delay_in_samples(0.12, 0.05);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("input delay tau = 0.12"));
    EXPECT_THAT(error.what(), HasSubstr("not a whole number of samples"));
  }
  EXPECT_EQ(delay_in_samples(0.15, 0.05), 3);
}

TEST(Simulate, RejectsBadInput) {
  const TransferFunction g(Polynomial{1.0}, Polynomial{1.0, 1.0});
  EXPECT_THROW(simulate(g, Eigen::VectorXd::Ones(10), 0.0), InvalidArgument);
  Eigen::VectorXd u = Eigen::VectorXd::Ones(10);
  u(7) = std::nan("");
  try {
    simulate(g, u, 0.1);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("u[7]"));
  }
  const TransferFunction improper(Polynomial{1.0, 1.0, 1.0}, Polynomial{1.0, 1.0});
  EXPECT_THROW(simulate(improper, Eigen::VectorXd::Ones(10), 0.1), InvalidArgument);
}

}  // namespace
}  // namespace ctid::simulate_test
