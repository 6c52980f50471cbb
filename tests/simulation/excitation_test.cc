// Excitation signals: PRBS period and balance, multisine spectrum flat on its band and zero
// off it, white noise moments, reproducibility from the seed.
#include "ctid/simulation/excitation.h"

#include <cmath>
#include <complex>
#include <numbers>
#include <set>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unsupported/Eigen/FFT>

#include "ctid/core/error.h"

namespace ctid::excitation_test {
namespace {

using ::testing::HasSubstr;

TEST(Prbs, MaximumLengthPeriodAndBalanceForEveryRegister) {
  for (int n = 2; n <= 16; ++n) {
    PrbsOptions options;
    options.register_length = n;
    const int period = (1 << n) - 1;
    ASSERT_EQ(prbs_period(options), period);
    const Eigen::VectorXd u = prbs(2 * period, options);
    // Periodic with period 2^n - 1 ...
    EXPECT_EQ(u.head(period), u.tail(period)) << "n = " << n;
    // ... and with no shorter period: all 2^n - 1 windows of n bits differ (each is a
    // non-zero register state).
    std::set<std::uint32_t> windows;
    for (int k = 0; k < period; ++k) {
      std::uint32_t w = 0;
      for (int j = 0; j < n; ++j) w = (w << 1) | (u(k + j) > 0.0 ? 1U : 0U);
      windows.insert(w);
    }
    EXPECT_EQ(static_cast<int>(windows.size()), period) << "n = " << n;
    // One more +1 than -1 per period.
    const int plus = static_cast<int>((u.head(period).array() > 0.0).count());
    EXPECT_EQ(plus, 1 << (n - 1)) << "n = " << n;
    EXPECT_EQ(period - plus, (1 << (n - 1)) - 1) << "n = " << n;
    EXPECT_DOUBLE_EQ(u.head(period).sum(), 1.0) << "n = " << n;
  }
}

TEST(Prbs, LongRegistersHaveFullPeriod) {
  for (int n : {17, 20}) {
    PrbsOptions options;
    options.register_length = n;
    const int period = (1 << n) - 1;
    const Eigen::VectorXd u = prbs(period + 64, options);
    EXPECT_EQ(u.head(64), u.tail(64)) << "n = " << n;
    EXPECT_DOUBLE_EQ(u.head(period).sum(), 1.0) << "n = " << n;
  }
}

TEST(Prbs, AmplitudeHoldAndInitialState) {
  PrbsOptions options;
  options.register_length = 5;
  options.amplitude = 0.5;
  options.samples_per_bit = 3;
  EXPECT_EQ(prbs_period(options), 93);
  const Eigen::VectorXd u = prbs(186, options);
  EXPECT_EQ(u.head(93), u.tail(93));
  for (int k = 0; k < 186; ++k) {
    EXPECT_EQ(std::abs(u(k)), 0.5);
    EXPECT_EQ(u(k), u(k - k % 3));
  }
  // A different start is a cyclic shift of the same sequence.
  PrbsOptions shifted = options;
  shifted.samples_per_bit = 1;
  options.samples_per_bit = 1;
  shifted.initial_state = 7;
  const Eigen::VectorXd a = prbs(62, options);
  const Eigen::VectorXd b = prbs(31, shifted);
  bool found = false;
  for (int s = 0; s < 31 && !found; ++s) found = a.segment(s, 31) == b;
  EXPECT_TRUE(found);
}

TEST(Prbs, ValidatesOptions) {
  PrbsOptions options;
  options.register_length = 25;
  try {
    prbs(10, options);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(),
                HasSubstr("PrbsOptions.register_length is 25; it must be in [2, 24]"));
  }
  options = PrbsOptions{};
  options.initial_state = 0;
  EXPECT_THROW(prbs(10, options), InvalidArgument);
  options = PrbsOptions{};
  options.samples_per_bit = 0;
  EXPECT_THROW(prbs(10, options), InvalidArgument);
  options = PrbsOptions{};
  options.register_length = 3;
  options.initial_state = 8;
  EXPECT_THAT([&] { prbs(10, options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("PrbsOptions.initial_state is 8; it must be < 2^register_length = 8")));
}

std::vector<std::complex<double>> dft(const Eigen::VectorXd& x) {
  std::vector<double> in(x.data(), x.data() + x.size());
  std::vector<std::complex<double>> out;
  Eigen::FFT<double> fft;
  fft.fwd(out, in);
  return out;
}

void expect_flat_on_band(const Multisine& m, const std::set<int>& expected_lines) {
  const int n = m.period_length;
  ASSERT_EQ(std::set<int>(m.lines.begin(), m.lines.end()), expected_lines);
  const std::vector<std::complex<double>> spectrum = dft(m.signal.head(n));
  const double line = 0.5 * n * m.amplitude;
  for (int k = 0; 2 * k <= n; ++k) {
    const double magnitude = std::abs(spectrum[static_cast<std::size_t>(k)]);
    if (expected_lines.count(k) > 0) {
      EXPECT_NEAR(magnitude, line, 1e-10 * line) << "line " << k;
    } else {
      EXPECT_LT(magnitude, 1e-10 * line) << "line " << k;
    }
  }
}

TEST(Multisine, FlatOnFullBandAndZeroOffIt) {
  MultisineOptions options;
  options.period_length = 1000;
  options.sample_time = 0.01;  // lines every 0.1 Hz
  options.min_frequency = 2.0;
  options.max_frequency = 7.5;
  options.rms = 2.0;
  options.periods = 3;
  options.seed = 42;
  const Multisine m = multisine(options);
  std::set<int> lines;
  for (int k = 20; k <= 75; ++k) lines.insert(k);
  expect_flat_on_band(m, lines);
  ASSERT_EQ(m.signal.size(), 3000);
  EXPECT_EQ(m.signal.segment(0, 1000), m.signal.segment(2000, 1000));
  EXPECT_NEAR(std::sqrt(m.signal.squaredNorm() / 3000.0), 2.0, 1e-12);
  // Phases are the ones reported.
  const std::vector<std::complex<double>> spectrum = dft(m.signal.head(1000));
  EXPECT_NEAR(std::arg(spectrum[20]), std::remainder(m.phases(0), 2.0 * std::numbers::pi), 1e-10);
}

TEST(Multisine, OddGridExcitesOnlyOddLines) {
  MultisineOptions options;
  options.period_length = 512;
  options.sample_time = 1.0 / 512.0;  // lines every 1 Hz, Nyquist 256 Hz
  options.min_frequency = 10.0;
  options.grid = FrequencyGrid::odd;
  const Multisine m = multisine(options);
  std::set<int> lines;
  for (int k = 11; k < 256; k += 2) lines.insert(k);
  expect_flat_on_band(m, lines);
}

TEST(Multisine, SeedGivesReproducibleAndDistinctPhases) {
  MultisineOptions options;
  options.seed = 1;
  const Multisine a = multisine(options);
  const Multisine b = multisine(options);
  options.seed = 2;
  const Multisine c = multisine(options);
  EXPECT_EQ(a.signal, b.signal);
  EXPECT_NE(a.signal, c.signal);
}

TEST(Multisine, RejectsEmptyBandAndBadOptions) {
  MultisineOptions options;
  options.period_length = 100;
  options.sample_time = 0.1;  // lines every 0.1 Hz
  options.min_frequency = 1.01;
  options.max_frequency = 1.09;
  try {
    multisine(options);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("no DFT line"));
  }
  options = MultisineOptions{};
  options.rms = -1.0;
  try {
    multisine(options);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("MultisineOptions.rms is -1; it must be finite and > 0"));
  }
  options = MultisineOptions{};
  options.min_frequency = 0.3;
  options.max_frequency = 0.2;
  EXPECT_THROW(multisine(options), InvalidArgument);
  options.min_frequency = 0.5;
  options.max_frequency = 0.25;
  EXPECT_THAT([&] { multisine(options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("MultisineOptions.max_frequency is 0.25; it must be 0 (Nyquist) or >= "
                            "min_frequency (0.5)")));
}

TEST(WhiteNoise, SeededMomentsWithinStatisticalBounds) {
  const int n = 40000;
  const Eigen::VectorXd e = white_noise(n, 3.0, 7);
  EXPECT_EQ(e, white_noise(n, 3.0, 7));
  // Mean: standard error 3 / sqrt(n) = 0.015; variance: relative standard error sqrt(2/n).
  EXPECT_LT(std::abs(e.mean()), 4.0 * 3.0 / std::sqrt(n));
  const double variance = (e.array() - e.mean()).square().sum() / (n - 1);
  EXPECT_NEAR(variance / 9.0, 1.0, 4.0 * std::sqrt(2.0 / n));
  // Lag-1 correlation of white noise: standard error 1 / sqrt(n).
  const double lag1 = (e.head(n - 1).array() * e.tail(n - 1).array()).sum() / (n * variance);
  EXPECT_LT(std::abs(lag1), 4.0 / std::sqrt(n));
  EXPECT_THROW(white_noise(10, -1.0, 0), InvalidArgument);
}

TEST(RepeatPeriodic, Copies) {
  const Eigen::VectorXd p = Eigen::VectorXd::LinSpaced(4, 1.0, 4.0);
  const Eigen::VectorXd r = repeat_periodic(p, 3);
  ASSERT_EQ(r.size(), 12);
  for (int k = 0; k < 12; ++k) EXPECT_EQ(r(k), p(k % 4));
  EXPECT_THROW(repeat_periodic(p, 0), InvalidArgument);
}

}  // namespace
}  // namespace ctid::excitation_test

namespace ctid::excitation_test {
namespace {

TEST(OrthogonalMultisines, HadamardPhasedExperimentsForThreeInputs) {
  MultisineOptions options;
  options.period_length = 128;
  options.sample_time = 0.1;
  options.max_frequency = 2.0;
  options.periods = 2;
  options.seed = 7;
  const OrthogonalMultisines o = orthogonal_multisines(options, 3);
  ASSERT_EQ(o.experiments.size(), 4u);  // the next power of two
  EXPECT_EQ(o.hadamard.transpose() * o.hadamard, 4.0 * Eigen::MatrixXd::Identity(4, 4));
  const Multisine first = multisine(options);
  EXPECT_EQ(o.lines, first.lines);
  options.seed = 9;
  const Multisine third = multisine(options);
  for (int e = 0; e < 4; ++e) {
    ASSERT_EQ(o.experiments[static_cast<std::size_t>(e)].rows(), 256);
    ASSERT_EQ(o.experiments[static_cast<std::size_t>(e)].cols(), 3);
    EXPECT_EQ(o.experiments[static_cast<std::size_t>(e)].col(0), first.signal);
    EXPECT_EQ(o.experiments[static_cast<std::size_t>(e)].col(2), o.hadamard(e, 2) * third.signal);
  }
  EXPECT_THROW(orthogonal_multisines(options, 0), InvalidArgument);
}

}  // namespace
}  // namespace ctid::excitation_test
