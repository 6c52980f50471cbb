// persistent_excitation_order must reject degenerate inputs (constants, a few sinusoids) at
// every lag spacing and accept rich band-limited ones (Section 7's multisine).
#include <cmath>

#include <gtest/gtest.h>

#include "ctid/estimation/validation.h"
#include "ctid/simulation/excitation.h"

namespace ctid::excitation_order_test {
namespace {

Eigen::VectorXd sines(int n, std::initializer_list<double> cycles_per_sample) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  double phase = 0.3;
  for (const double f : cycles_per_sample) {
    for (int k = 0; k < n; ++k) x(k) += std::cos(2.0 * M_PI * f * k + phase);
    phase += 1.1;
  }
  return x;
}

TEST(PersistentExcitationOrder, SumsOfSinusoidsHaveTwiceTheirCountAtEverySpacing) {
  EXPECT_EQ(persistent_excitation_order(sines(4000, {0.013}), 20), 2);
  EXPECT_EQ(persistent_excitation_order(sines(4000, {0.013, 0.21, 0.37}), 20), 6);
  // A slow sine looks like a constant to unit-spacing windows, but not to wider ones.
  EXPECT_EQ(persistent_excitation_order(sines(4000, {0.001}), 20), 2);
  Eigen::VectorXd offset_sine = sines(4000, {0.05});
  offset_sine.array() += 1.5;
  EXPECT_EQ(persistent_excitation_order(offset_sine, 20), 3);
}

TEST(PersistentExcitationOrder, BandLimitedMultisineIsRich) {
  // Section 7: 0.5-500 Hz at 4096 Hz, 8192 samples (about 1000 lines).
  MultisineOptions options;
  options.period_length = 8192;
  options.sample_time = 1.0 / 4096.0;
  options.min_frequency = 0.5;
  options.max_frequency = 500.0;
  options.seed = 1;
  const Multisine u = multisine(options);
  ASSERT_GT(u.lines.size(), 900u);
  EXPECT_EQ(persistent_excitation_order(u.signal, 16), 16);
}

TEST(PersistentExcitationOrder, MultisineWithFewLinesIsLimitedByItsLineCount) {
  MultisineOptions options;
  options.period_length = 64;
  options.min_frequency = 0.1;
  options.max_frequency = 0.19;  // lines 7..12: six sinusoids
  const Multisine u = multisine(options);
  ASSERT_EQ(u.lines.size(), 6u);
  EXPECT_EQ(persistent_excitation_order(repeat_periodic(u.signal, 16), 20), 12);
}

}  // namespace
}  // namespace ctid::excitation_order_test
