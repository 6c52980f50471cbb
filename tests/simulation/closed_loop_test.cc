// Sampled-data closed loop: the loop equations hold at every sample, the plant output is the
// open-loop ZOH response to the simulated input, and unstable or ill-posed loops are refused.
#include "ctid/simulation/closed_loop.h"

#include <cmath>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/simulation/simulate.h"
#include "support/paper_systems.h"

namespace ctid::closed_loop_test {
namespace {

using ::testing::HasSubstr;

constexpr double kH = 0.05;

double max_abs(const Eigen::VectorXd& v) { return v.cwiseAbs().maxCoeff(); }

Eigen::VectorXd gaussian(int n, double sd, std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> normal(0.0, sd);
  Eigen::VectorXd v(n);
  for (int k = 0; k < n; ++k) v(k) = normal(engine);
  return v;
}

void expect_loop_equations(const ClosedLoopSimulation& loop, const DiscreteTransferFunction& c,
                           const Eigen::VectorXd& r, const Eigen::VectorXd& v) {
  // u = C_d(q)(r - y) at every sample, y = noise-free output + v.
  const Eigen::VectorXd u = c.filter(r - loop.output);
  EXPECT_LT(max_abs(u - loop.input), 1e-12 * max_abs(loop.input));
  EXPECT_LT(max_abs(loop.output - loop.noise_free_output - v), 1e-15 * max_abs(loop.output));
}

TEST(ClosedLoop, PaperSystemWithPidSatisfiesLoopEquations) {
  const AdditiveModel plant = testing::closed_loop_two_modes();
  const DiscreteTransferFunction pid = testing::closed_loop_pid();
  const Eigen::VectorXd r = gaussian(4000, 1.0, 1);
  const Eigen::VectorXd v = gaussian(4000, 0.1, 2);
  const ClosedLoopSimulation loop = simulate_closed_loop(plant, pid, r, v);
  expect_loop_equations(loop, pid, r, v);
  // The plant output is the open-loop ZOH response to the loop's input.
  const Eigen::VectorXd y = simulate(plant, loop.input, kH);
  EXPECT_LT(max_abs(y - loop.noise_free_output), 1e-12 * max_abs(y));
  // Same loop from the unfactored plant.
  const ClosedLoopSimulation unfactored =
      simulate_closed_loop(plant.to_transfer_function(), pid, r, v);
  EXPECT_LT(max_abs(unfactored.output - loop.output), 1e-11 * max_abs(loop.output));
}

TEST(ClosedLoop, WithoutNoiseOutputIsNoiseFree) {
  const Eigen::VectorXd r = gaussian(500, 1.0, 3);
  const ClosedLoopSimulation loop =
      simulate_closed_loop(testing::closed_loop_two_modes(), testing::closed_loop_pid(), r);
  EXPECT_EQ(loop.output, loop.noise_free_output);
  expect_loop_equations(loop, testing::closed_loop_pid(), r, Eigen::VectorXd::Zero(500));
}

TEST(ClosedLoop, BiproperPlantAndControllerAlgebraicLoop) {
  // (1 + 2p)/(1 + p) has D_g = 2; the PID has D_c = 0.02329.
  const TransferFunction plant(Polynomial{1.0, 2.0}, Polynomial{1.0, 1.0});
  const DiscreteTransferFunction pid = testing::closed_loop_pid();
  const Eigen::VectorXd r = gaussian(1000, 1.0, 4);
  const Eigen::VectorXd v = gaussian(1000, 0.05, 5);
  const ClosedLoopSimulation loop = simulate_closed_loop(plant, pid, r, v);
  expect_loop_equations(loop, pid, r, v);
  const Eigen::VectorXd y = simulate(plant, loop.input, kH);
  EXPECT_LT(max_abs(y - loop.noise_free_output), 1e-13 * max_abs(y));
  // A strong static controller makes the algebraic loop matter: y_0 = 2 u_0, u_0 = K(r_0 - y_0).
  const DiscreteTransferFunction gain(Polynomial{5.0}, Polynomial{1.0}, kH);
  const ClosedLoopSimulation strong = simulate_closed_loop(plant, gain, r);
  EXPECT_NEAR(strong.input(0), 5.0 * r(0) / (1.0 + 10.0), 1e-15);
  expect_loop_equations(strong, gain, r, Eigen::VectorXd::Zero(1000));
}

TEST(ClosedLoop, DelayedPlant) {
  const AdditiveModel plant = testing::closed_loop_two_modes().with_input_delay(2 * kH);
  const Eigen::VectorXd r = gaussian(1000, 1.0, 6);
  const ClosedLoopSimulation loop = simulate_closed_loop(plant, testing::closed_loop_pid(), r);
  expect_loop_equations(loop, testing::closed_loop_pid(), r, Eigen::VectorXd::Zero(1000));
  const Eigen::VectorXd y = simulate(plant, loop.input, kH);
  EXPECT_LT(max_abs(y - loop.noise_free_output), 1e-12 * max_abs(y));
}

TEST(ClosedLoop, PolesOfFirstOrderLoopInClosedForm) {
  // ZOH of 1/(1 + p): x+ = e^{-h} x + (1 - e^{-h}) u; with u = -K y the pole is
  // e^{-h} - K (1 - e^{-h}).
  const TransferFunction plant(Polynomial{1.0}, Polynomial{1.0, 1.0});
  for (double k : {0.5, 10.0, 60.0}) {
    const DiscreteTransferFunction gain(Polynomial{k}, Polynomial{1.0}, kH);
    const Eigen::VectorXcd poles = closed_loop_poles(zoh_equivalent(plant, kH), gain);
    ASSERT_EQ(poles.size(), 1);
    const double expected = std::exp(-kH) + k * std::expm1(-kH);
    EXPECT_NEAR(poles(0).real(), expected, 1e-13 * (1.0 + k));
    EXPECT_NEAR(poles(0).imag(), 0.0, 1e-15);
  }
}

TEST(ClosedLoop, RefusesUnstableLoop) {
  const TransferFunction plant(Polynomial{1.0}, Polynomial{1.0, 1.0});
  const DiscreteTransferFunction gain(Polynomial{60.0}, Polynomial{1.0}, kH);
  try {
    simulate_closed_loop(plant, gain, Eigen::VectorXd::Ones(10));
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("does not stabilise the loop"));
    EXPECT_THAT(error.what(), HasSubstr("|z| = "));
  }
  // An open-loop unstable plant that the controller does stabilise is accepted.
  const TransferFunction unstable(Polynomial{1.0}, Polynomial{-1.0, 1.0});  // 1/(p - 1)
  const DiscreteTransferFunction stabilising(Polynomial{3.0}, Polynomial{1.0}, kH);
  const ClosedLoopSimulation loop =
      simulate_closed_loop(unstable, stabilising, Eigen::VectorXd::Ones(400));
  EXPECT_NEAR(loop.output(399), 3.0 / 2.0, 1e-9);  // DC: 3 G(0) / (1 + 3 G(0)), G(0) = -1.
}

TEST(ClosedLoop, RefusesIllPosedLoopAndBadSignals) {
  const TransferFunction plant(Polynomial{1.0, 2.0}, Polynomial{1.0, 1.0});  // D_g = 2
  const DiscreteTransferFunction gain(Polynomial{-0.5}, Polynomial{1.0}, kH);
  try {
    simulate_closed_loop(plant, gain, Eigen::VectorXd::Ones(10));
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("ill-posed"));
  }
  const DiscreteTransferFunction pid = testing::closed_loop_pid();
  EXPECT_THROW(
      simulate_closed_loop(plant, pid, Eigen::VectorXd::Ones(10), Eigen::VectorXd::Ones(9)),
      InvalidArgument);
  Eigen::VectorXd r = Eigen::VectorXd::Ones(10);
  r(4) = std::numeric_limits<double>::infinity();
  try {
    simulate_closed_loop(plant, pid, r);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("r[4]"));
  }
}

}  // namespace
}  // namespace ctid::closed_loop_test
