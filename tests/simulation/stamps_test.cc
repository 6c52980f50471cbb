// Simulation at irregular time stamps (stamps.h) against simulate() on uniform stamps and
// against closed-form step and ramp responses at jittered stamps with duplicates and a gap.
#include "ctid/simulation/stamps.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/simulation/simulate.h"

namespace ctid::stamps_test {
namespace {

using ::testing::HasSubstr;

// Stamps 0.05 k ±30 % (seeded), stamp 40 repeated twice, stamps 100-119 missing (a gap).
Eigen::VectorXd jittered_stamps(std::uint64_t seed) {
  std::mt19937_64 engine(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::vector<double> t;
  for (int k = 0; k < 300; ++k) {
    if (k >= 100 && k < 120) continue;
    t.push_back(0.05 * (k + (k == 0 ? 0.0 : jitter(engine))));
    if (k == 40) {
      t.push_back(t.back());
      t.push_back(t.back());
    }
  }
  return Eigen::Map<Eigen::VectorXd>(t.data(), static_cast<Eigen::Index>(t.size()));
}

int duplicates(const Eigen::VectorXd& t) {
  int count = 0;
  for (Eigen::Index k = 1; k < t.size(); ++k) count += t(k) == t(k - 1) ? 1 : 0;
  return count;
}

TEST(SimulateOnStamps, JitteredStampsHaveDuplicatesAndAGap) {
  const Eigen::VectorXd t = jittered_stamps(7);
  EXPECT_EQ(duplicates(t), 2);
  double largest = 0.0;
  for (Eigen::Index k = 1; k < t.size(); ++k) largest = std::max(largest, t(k) - t(k - 1));
  EXPECT_GT(largest, 20 * 0.05);
}

TEST(SimulateOnStamps, UniformStampsGiveTheZohSimulation) {
  const TransferFunction g(Polynomial{2.0, 0.3}, Polynomial{1.0, 0.4, 0.25});
  const double h = 0.05;
  std::mt19937_64 engine(11);
  std::normal_distribution<double> normal;
  const int n = 400;
  Eigen::VectorXd u(n);
  Eigen::VectorXd t(n);
  for (int k = 0; k < n; ++k) {
    u(k) = normal(engine);
    t(k) = 1.5 + k * h;
  }
  const Eigen::VectorXd expected = simulate(g, u, h);
  const Eigen::VectorXd y = simulate_on_stamps(g, t, u, Hold::zero_order_hold);
  EXPECT_LT((y - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
}

// A first-order lag K / (1 + T s) with a ZOH step switched on at the repeated stamp 40: the
// input is 0 at the first of the three equal stamps and 1 at the others, so
// y(t) = K (1 - e^{-(t - t_40) / T}) after it.
TEST(SimulateOnStamps, StepAtADuplicateStampMatchesTheClosedForm) {
  const double gain = 2.5;
  const double tc = 0.3;
  const TransferFunction g(Polynomial{gain}, Polynomial{1.0, tc});
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const Eigen::VectorXd t = jittered_stamps(seed);
    Eigen::VectorXd u = Eigen::VectorXd::Zero(t.size());
    const Eigen::Index first = 40;  // stamps 40-42 are the three copies of k = 40
    ASSERT_EQ(t(first), t(first + 2));
    u.tail(t.size() - first - 1).setOnes();
    const Eigen::VectorXd y = simulate_on_stamps(g, t, u, Hold::zero_order_hold);
    for (Eigen::Index k = 0; k < t.size(); ++k) {
      const double expected = k <= first ? 0.0 : -gain * std::expm1(-(t(k) - t(first)) / tc);
      EXPECT_NEAR(y(k), expected, 1e-10) << "seed " << seed << ", stamp " << k;
    }
  }
}

// A second-order system wn^2 / (s^2 + 2 zeta wn s + wn^2) under a ramp u = t - t_0: a
// first-order hold interpolates the ramp exactly, so y is the closed-form ramp response
// t - 2 zeta / wn + e^{-zeta wn t} (2 zeta / wn cos(wd t) + (2 zeta^2 - 1) / wd sin(wd t)).
TEST(SimulateOnStamps, FohRampMatchesTheClosedFormSecondOrderResponse) {
  const double wn = 3.0;
  const double zeta = 0.2;
  const double wd = wn * std::sqrt(1.0 - zeta * zeta);
  const AdditiveModel g(
      {Submodel{Polynomial{1.0, 2.0 * zeta / wn, 1.0 / (wn * wn)}, Polynomial{1.0}, 0}});
  const Eigen::VectorXd t = jittered_stamps(5);
  const Eigen::VectorXd u = t.array() - t(0);
  const Eigen::VectorXd y = simulate_on_stamps(g, t, u, Hold::first_order_hold);
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    const double s = t(k) - t(0);
    const double expected =
        s - 2.0 * zeta / wn +
        std::exp(-zeta * wn * s) * (2.0 * zeta / wn * std::cos(wd * s) +
                                    (2.0 * zeta * zeta - 1.0) / wd * std::sin(wd * s));
    EXPECT_NEAR(y(k), expected, 1e-10) << "stamp " << k;
  }
}

TEST(SimulateOnStamps, UniformStampsWithADelayGiveTheZohSimulation) {
  const double h = 0.05;
  std::mt19937_64 engine(12);
  std::normal_distribution<double> normal;
  const int n = 300;
  Eigen::VectorXd u(n);
  Eigen::VectorXd t(n);
  for (int k = 0; k < n; ++k) {
    u(k) = normal(engine);
    t(k) = 0.7 + k * h;
  }
  // A whole number of steps, a fraction of one, and a biproper model (D u_{k-d} at stamp k).
  for (const TransferFunction& g :
       {TransferFunction(Polynomial{2.0, 0.3}, Polynomial{1.0, 0.4, 0.25}, 3 * h),
        TransferFunction(Polynomial{2.0, 0.3}, Polynomial{1.0, 0.4, 0.25}, 2.37 * h),
        TransferFunction(Polynomial{1.0, 0.5}, Polynomial{1.0, 0.25}, 4 * h)}) {
    const Eigen::VectorXd expected = simulate(g, u, h);
    const Eigen::VectorXd y = simulate_on_stamps(g, t, u, Hold::zero_order_hold);
    EXPECT_LT((y - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff())
        << g.input_delay();
  }
}

// The same lag and ramp delayed by tau: the input reaches the model tau after each stamp.
TEST(SimulateOnStamps, ADelayedStepAndRampMatchTheirClosedForms) {
  const double gain = 2.5;
  const double tc = 0.3;
  const double tau = 0.123;
  const TransferFunction lag(Polynomial{gain}, Polynomial{1.0, tc}, tau);
  const double wn = 3.0;
  const double zeta = 0.2;
  const double wd = wn * std::sqrt(1.0 - zeta * zeta);
  const TransferFunction second(Polynomial{1.0}, Polynomial{1.0, 2.0 * zeta / wn, 1.0 / (wn * wn)},
                                tau);
  const Eigen::VectorXd t = jittered_stamps(9);
  const Eigen::VectorXd step =
      simulate_on_stamps(lag, t, Eigen::VectorXd::Ones(t.size()), Hold::zero_order_hold);
  const Eigen::VectorXd ramp =
      simulate_on_stamps(second, t, Eigen::VectorXd(t.array() - t(0)), Hold::first_order_hold);
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    const double s = std::max(t(k) - t(0) - tau, 0.0);
    EXPECT_NEAR(step(k), -gain * std::expm1(-s / tc), 1e-10) << "stamp " << k;
    const double expected =
        s - 2.0 * zeta / wn +
        std::exp(-zeta * wn * s) * (2.0 * zeta / wn * std::cos(wd * s) +
                                    (2.0 * zeta * zeta - 1.0) / wd * std::sin(wd * s));
    EXPECT_NEAR(ramp(k), expected, 1e-10) << "stamp " << k;
  }
}

// A biproper model: each of the equal stamps gets its own D u_k, the state is shared.
TEST(SimulateOnStamps, EqualStampsShareTheStateAndKeepTheirOwnFeedthrough) {
  const TransferFunction g(Polynomial{1.0, 0.5}, Polynomial{1.0, 0.25});  // D = 2
  Eigen::VectorXd t(4);
  t << 0.0, 0.1, 0.1, 0.3;
  Eigen::VectorXd u(4);
  u << 0.0, 0.0, 1.0, 1.0;
  const Eigen::VectorXd y = simulate_on_stamps(g, t, u, Hold::zero_order_hold);
  EXPECT_NEAR(y(1), 0.0, 1e-15);
  EXPECT_NEAR(y(2), 2.0, 1e-14);
  // From t = 0.1 the unit step: 1 + (2 - 1) e^{-(t - 0.1) / 0.25}.
  EXPECT_NEAR(y(3), 1.0 + std::exp(-0.2 / 0.25), 1e-12);
}

TEST(SimulateOnStamps, AStaticGainIsTheGainTimesTheInput) {
  const TransferFunction g(Polynomial{3.0}, Polynomial{1.0});
  Eigen::VectorXd t(3);
  t << 0.0, 0.2, 0.25;
  Eigen::VectorXd u(3);
  u << 1.0, -2.0, 0.5;
  const Eigen::VectorXd y = simulate_on_stamps(g, t, u);
  EXPECT_LT((y - 3.0 * u).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(SimulateOnStamps, StampsThatGoBackAreRefusedNamingTheStamp) {
  const TransferFunction g(Polynomial{1.0}, Polynomial{1.0, 0.5});
  Eigen::VectorXd t(5);
  t << 0.0, 0.1, 0.2, 0.15, 0.3;
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(5);
  try {
    simulate_on_stamps(g, t, u);
    FAIL() << "stamps going back were accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("time stamp 3 (0.15 s) goes back before stamp 2 (0.2 s)"));
  }
  t(3) = std::numeric_limits<double>::quiet_NaN();
  try {
    simulate_on_stamps(g, t, u);
    FAIL() << "a NaN stamp was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("time stamp 3 is nan"));
  }
}

TEST(SimulateOnStamps, BadInputIsRefusedWithOneClearMessage) {
  Eigen::VectorXd t(3);
  t << 0.0, 0.1, 0.2;
  const TransferFunction g(Polynomial{1.0}, Polynomial{1.0, 0.5});
  try {
    simulate_on_stamps(g, t, Eigen::VectorXd::Ones(2));
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("3 time stamps and 2 input samples"));
  }
  try {
    simulate_on_stamps(TransferFunction(Polynomial{0.0, 0.0, 1.0}, Polynomial{1.0, 1.0}), t,
                       Eigen::VectorXd::Ones(3));
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("improper"));
  }
}

}  // namespace
}  // namespace ctid::stamps_test
