// Coloured noise: its construction, stationarity from the first sample, its variance against
// the Lyapunov prediction, and SNR scaling.
#include "ctid/simulation/noise.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/simulation/excitation.h"
#include "support/paper_systems.h"

namespace ctid::noise_test {
namespace {

using ::testing::HasSubstr;

TEST(ColoredNoise, IsTheFilteredWhiteNoiseAfterRunIn) {
  const DiscreteTransferFunction h = testing::open_loop_noise_filter();
  const int run_in = stationary_run_in(h);
  // 0.85^run_in <= 1e-12 < 0.85^(run_in - 1).
  EXPECT_LE(std::pow(0.85, run_in), 1e-12);
  EXPECT_GT(std::pow(0.85, run_in - 1), 1e-12);
  const Eigen::VectorXd v = colored_noise(h, 500, 0.02, 9);
  const Eigen::VectorXd e = white_noise(run_in + 500, std::sqrt(0.02), 9);
  EXPECT_EQ(v, h.filter(e).tail(500));
}

TEST(ColoredNoise, StationaryVarianceMatchesClosedForm) {
  // Impulse response 1, 1.35 * 0.85^(k-1): sum of squares 1 + 1.35^2 / (1 - 0.85^2).
  const double gain = 1.0 + 1.35 * 1.35 / (1.0 - 0.85 * 0.85);
  EXPECT_NEAR(stationary_variance_gain(testing::open_loop_noise_filter()), gain, 1e-13 * gain);
}

TEST(ColoredNoise, FirstSampleAlreadyHasStationaryVariance) {
  // Across seeds, var(v_0) is the stationary variance; without run-in it would be var e.
  const DiscreteTransferFunction h = testing::open_loop_noise_filter();
  const double expected = 0.02 * stationary_variance_gain(h);
  const int runs = 4000;
  double sum_sq = 0.0;
  double sum_sq_no_run_in = 0.0;
  for (int seed = 0; seed < runs; ++seed) {
    const double v0 = colored_noise(h, 1, 0.02, static_cast<std::uint64_t>(seed))(0);
    const double w0 = colored_noise(h, 1, 0.02, static_cast<std::uint64_t>(seed), 0)(0);
    sum_sq += v0 * v0;
    sum_sq_no_run_in += w0 * w0;
  }
  // Relative standard error of a Gaussian variance estimate: sqrt(2 / runs) ~ 2.2 %.
  EXPECT_NEAR(sum_sq / runs / expected, 1.0, 4.0 * std::sqrt(2.0 / runs));
  EXPECT_NEAR(sum_sq_no_run_in / runs / 0.02, 1.0, 4.0 * std::sqrt(2.0 / runs));
}

TEST(ColoredNoise, RejectsUnstableFilter) {
  const DiscreteTransferFunction unstable(Polynomial{1.0}, Polynomial{-1.0, 1.0}, 0.1);
  try {
    colored_noise(unstable, 10, 1.0, 0);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("must be stable"));
  }
  EXPECT_THROW(colored_noise(testing::open_loop_noise_filter(), 10, -1.0, 0), InvalidArgument);
}

TEST(Snr, DefinitionAndScaling) {
  const Eigen::VectorXd signal = white_noise(2000, 2.0, 1);
  const Eigen::VectorXd noise = colored_noise(testing::open_loop_noise_filter(), 2000, 0.02, 2);
  const double var_s = (signal.array() - signal.mean()).square().sum() / 1999.0;
  const double var_n = (noise.array() - noise.mean()).square().sum() / 1999.0;
  EXPECT_NEAR(snr_db(signal, noise), 10.0 * std::log10(var_s / var_n), 1e-12);
  for (double target : {-5.0, 9.0, 60.0}) {
    const Eigen::VectorXd scaled = scale_noise_to_snr(signal, noise, target);
    EXPECT_NEAR(snr_db(signal, scaled), target, 1e-10);
    // Only a positive scale factor: the shape of the noise is kept.
    EXPECT_NEAR((scaled.array() / noise.array()).maxCoeff(),
                (scaled.array() / noise.array()).minCoeff(), 1e-9);
  }
  EXPECT_THROW(snr_db(signal, Eigen::VectorXd::Ones(2000)), InvalidArgument);
  EXPECT_THROW(snr_db(signal, noise.head(10)), InvalidArgument);
}

}  // namespace
}  // namespace ctid::noise_test
