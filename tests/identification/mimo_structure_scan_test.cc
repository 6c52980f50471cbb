// How many modes a record of several outputs holds (scan_mimo_modes, decision 0064): a record of
// two lightly damped modes seen by three sensors recommends two, the diagram marks the true
// modes stable from one count to the next, the one-mode fit scores worse on the held-out part,
// and bad counts and short records are refused with one message each.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/core/state_space.h"
#include "ctid/identification/mimo_structure_scan.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/excitation.h"

namespace ctid::mimo_structure_scan_test {
namespace {

using ::testing::HasSubstr;

constexpr double kW[2] = {3.0, 8.0};  // rad/s, damping ratio 0.03 each

// y_j = sum_i shape_ij x_i, x_i'' + 2 zeta w_i x_i' + w_i^2 x_i = w_i^2 u, ZOH-exact, plus
// `noise` times each output's rms of white sensor noise.
MimoData two_mode_record(int samples, double noise, unsigned seed) {
  const double h = 0.05;
  const Eigen::MatrixXd shapes =
      (Eigen::MatrixXd(3, 2) << 1.0, 0.4, 0.6, -1.0, -0.5, 0.8).finished();
  StateSpace ct;
  ct.a = Eigen::MatrixXd::Zero(4, 4);
  ct.b = Eigen::VectorXd::Zero(4);
  ct.c = Eigen::RowVectorXd::Zero(4);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(3, 4);
  for (int i = 0; i < 2; ++i) {
    ct.a(2 * i, 2 * i + 1) = 1.0;
    ct.a(2 * i + 1, 2 * i) = -kW[i] * kW[i];
    ct.a(2 * i + 1, 2 * i + 1) = -2.0 * 0.03 * kW[i];
    ct.b(2 * i + 1) = kW[i] * kW[i];
    c.col(2 * i) = shapes.col(i);
  }
  const StateSpace dt = discretize_zoh(ct, h);
  const Eigen::VectorXd u = white_noise(samples, 1.0, seed);
  Eigen::MatrixXd y(samples, 3);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(4);
  for (int k = 0; k < samples; ++k) {
    y.row(k) = (c * x).transpose();
    x = dt.a * x + dt.b * u(k);
  }
  std::mt19937_64 rng(seed + 1);
  std::normal_distribution<double> normal;
  for (Eigen::Index j = 0; j < 3; ++j) {
    const double sd = noise * std::sqrt(y.col(j).squaredNorm() / samples);
    for (Eigen::Index k = 0; k < samples; ++k) y(k, j) += sd * normal(rng);
  }
  return MimoData(h, u, y);
}

TEST(MimoStructureScan, TwoModesAreRecommendedAndStableInTheDiagram) {
  const MimoData data = two_mode_record(4000, 0.05, 3);
  int reported = 0;
  const MimoStructureScanResult r =
      scan_mimo_modes(data, {1, 2, 3}, {}, [&](int done, int) { reported = done; });
  EXPECT_EQ(reported, 3);
  ASSERT_EQ(r.fits.size(), 3u);
  EXPECT_EQ(r.estimation_samples, 2800);
  EXPECT_EQ(r.validation_samples, 1200);
  ASSERT_EQ(r.recommended, 1) << r.rule;
  EXPECT_THAT(r.rule, HasSubstr("fewest modes among the usable fits whose held-out error"));
  const MimoStructureFit& two = r.fits[1];
  EXPECT_TRUE(two.usable);
  ASSERT_EQ(two.validation_fit.size(), 3);
  for (Eigen::Index j = 0; j < 3; ++j) EXPECT_GT(two.validation_fit(j), 90.0) << j;
  // One mode cannot fit both resonances: its held-out error is well above the two-mode fit's.
  EXPECT_GT(r.fits[0].validation_error, 2.0 * two.validation_error);
  // The three-mode fit's modes near the true ones are stable in frequency and damping.
  for (const double w : kW) {
    bool stable = false;
    for (const StabilisationPoint& p : r.stabilisation) {
      stable = stable || (p.order == 6 && std::abs(p.frequency / w - 1.0) < 0.01 &&
                          p.stable_frequency && p.stable_damping);
    }
    EXPECT_TRUE(stable) << w;
  }
}

TEST(MimoStructureScan, BadCountsAndShortRecordsAreRefused) {
  const MimoData data = two_mode_record(400, 0.05, 4);
  const auto refused = [&](const std::vector<int>& counts, double fraction,
                           const std::string& expected) {
    MimoStructureScanOptions o;
    o.validation_fraction = fraction;
    try {
      scan_mimo_modes(data, counts, o);
      ADD_FAILURE() << "accepted; expected: " << expected;
    } catch (const InvalidArgument& e) {
      EXPECT_THAT(e.what(), HasSubstr(expected));
    }
  };
  refused({}, 0.3, "no mode count given");
  refused({0, 2}, 0.3, "a mode count is 0; each must be at least 1");
  refused({2, 2}, 0.3, "the mode count 2 is given twice");
  refused({1}, 0.99, "validation_fraction is 0.99");
  const MimoData tiny = two_mode_record(10, 0.05, 5);
  try {
    scan_mimo_modes(tiny, {1});
    ADD_FAILURE() << "a 10-sample record was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("too few samples: 10 samples split into 7 fitted and 3 held out"));
  }
}

}  // namespace
}  // namespace ctid::mimo_structure_scan_test
