#include "ctid/frequency/frf.h"

#include <cmath>
#include <complex>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/LU>

#include "ctid/core/error.h"
#include "ctid/core/transfer_function.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::frf_test {
namespace {

using Complex = std::complex<double>;
using ::testing::HasSubstr;

// The exact discrete response from u_k to y_k of the ZOH-sampled model, C (zI - A)^-1 B + D
// at z = e^{j w h}: in periodic steady state the sampled output's DFT is this times the
// input's DFT, line by line, with no approximation.
Complex zoh_response(const TransferFunction& g, double h, double omega) {
  const StateSpace d = zoh_equivalent(g, h);
  const Complex z = std::exp(Complex(0.0, omega * h));
  const Eigen::MatrixXcd lhs =
      z * Eigen::MatrixXcd::Identity(d.order(), d.order()) - d.a.cast<Complex>();
  const Eigen::VectorXcd x = lhs.partialPivLu().solve(d.b.cast<Complex>());
  return (d.c.cast<Complex>() * x)(0) + d.d;
}

// A lightly damped mode, w_n = 2 rad/s, zeta = 0.2: the transient decays as e^{-0.4 t}.
TransferFunction resonant() { return TransferFunction(Polynomial{4.0}, Polynomial{4.0, 0.8, 1.0}); }

constexpr double kH = 0.05;
constexpr int kPeriod = 512;

Multisine test_multisine(int periods, std::uint64_t seed) {
  MultisineOptions options;
  options.period_length = kPeriod;
  options.sample_time = kH;
  options.max_frequency = 5.0;
  options.periods = periods;
  options.seed = seed;
  return multisine(options);
}

TEST(PeriodicFrf, NoiseFreeEqualsZohResponseAtExcitedLines) {
  const Multisine u = test_multisine(6, 11);
  const TransferFunction g = resonant();
  const Eigen::VectorXd y = simulate(g, u.signal, kH);
  PeriodicFrfOptions options;
  options.period_length = kPeriod;
  options.transient_periods = 3;  // 76.8 s: e^{-0.4 t} < 1e-13
  const Frf frf = periodic_frf(SampledData(kH, u.signal, y), options);

  EXPECT_EQ(frf.lines, u.lines);
  EXPECT_EQ(frf.averages, 3);
  // Noise-free, the output repeats exactly with the input: coherence 1 on every line; the
  // multisine's lines all have one amplitude.
  ASSERT_EQ(frf.coherence.size(), frf.response.size());
  EXPECT_GT(frf.coherence.minCoeff(), 1.0 - 1e-12);
  ASSERT_EQ(frf.input_level.size(), frf.response.size());
  EXPECT_DOUBLE_EQ(frf.input_level.maxCoeff(), 1.0);
  EXPECT_GT(frf.input_level.minCoeff(), 1.0 - 1e-9);
  double worst = 0.0;
  for (Eigen::Index i = 0; i < frf.response.size(); ++i) {
    const int k = frf.lines[static_cast<size_t>(i)];
    EXPECT_DOUBLE_EQ(frf.frequencies(i), 2.0 * std::numbers::pi * k / (kPeriod * kH));
    worst = std::max(worst, std::abs(frf.response(i) - zoh_response(g, kH, frf.frequencies(i))));
    EXPECT_LT(frf.variance(i), 1e-20);
  }
  EXPECT_LT(worst, 1e-10);
}

TEST(PeriodicFrf, ContinuousResponseDiffersFromTheSampledOneNearNyquist) {
  // Why the reference above is the ZOH equivalent: at the top excited line the continuous
  // G(jw) differs from the sampled-data response by far more than the estimate's error.
  const Multisine u = test_multisine(5, 3);
  const TransferFunction g = resonant();
  PeriodicFrfOptions options;
  options.period_length = kPeriod;
  options.transient_periods = 3;
  const Frf frf = periodic_frf(SampledData(kH, u.signal, simulate(g, u.signal, kH)), options);
  const Eigen::Index last = frf.response.size() - 1;
  EXPECT_GT(std::abs(frf.response(last) - g.frequency_response(frf.frequencies(last))), 1e-4);
}

TEST(PeriodicFrf, NoisyErrorMatchesPredictedVariance) {
  const int periods = 10;
  const Multisine u = test_multisine(periods + 3, 5);
  const TransferFunction g = resonant();
  const double sigma = 0.05;
  const Eigen::VectorXd y =
      simulate(g, u.signal, kH) + white_noise(static_cast<int>(u.signal.size()), sigma, 77);
  PeriodicFrfOptions options;
  options.period_length = kPeriod;
  options.transient_periods = 3;
  const Frf frf = periodic_frf(SampledData(kH, u.signal, y), options);
  ASSERT_EQ(frf.averages, periods);

  // White noise of variance s^2 has DFT variance N s^2 per line, so the mean over P periods
  // of Y/U has variance N s^2 / (|U|^2 P). |U| = A N / 2 for a cosine of amplitude A.
  const double u_line = u.amplitude * kPeriod / 2.0;
  const double predicted = kPeriod * sigma * sigma / (u_line * u_line * periods);
  double error_ratio = 0.0;
  double variance_ratio = 0.0;
  const auto lines = static_cast<double>(frf.response.size());
  for (Eigen::Index i = 0; i < frf.response.size(); ++i) {
    error_ratio += std::norm(frf.response(i) - zoh_response(g, kH, frf.frequencies(i))) / predicted;
    variance_ratio += frf.variance(i) / predicted;
  }
  error_ratio /= lines;
  variance_ratio /= lines;
  // |e|^2 / predicted is Exp(1): the mean over 128 lines has standard deviation 0.09.
  EXPECT_NEAR(error_ratio, 1.0, 0.35);
  // The estimated variance is chi^2 with 2(P - 1) degrees of freedom / its mean: sd 0.03.
  EXPECT_NEAR(variance_ratio, 1.0, 0.12);
}

TEST(PeriodicFrf, ExplicitLinesAreSortedAndMustBeExcited) {
  const Multisine u = test_multisine(3, 1);
  const TransferFunction g = resonant();
  const SampledData data(kH, u.signal, simulate(g, u.signal, kH));
  PeriodicFrfOptions options;
  options.period_length = kPeriod;
  options.lines = {u.lines[4], u.lines[2], u.lines[4]};
  const Frf frf = periodic_frf(data, options);
  ASSERT_EQ(frf.lines.size(), 2U);
  EXPECT_EQ(frf.lines[0], u.lines[2]);
  EXPECT_EQ(frf.lines[1], u.lines[4]);

  options.lines = {200};  // 200 / (512 h) = 7.8 Hz, above the 5 Hz band
  EXPECT_THAT([&] { periodic_frf(data, options); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("line 200")));
}

TEST(PeriodicFrf, RejectsBadInput) {
  const Multisine u = test_multisine(3, 1);
  const SampledData whole(kH, u.signal, u.signal);
  PeriodicFrfOptions options;
  options.period_length = kPeriod;
  options.transient_periods = 1;

  const SampledData ragged = whole.segment(0, 3 * kPeriod - 7);
  EXPECT_THAT([&] { periodic_frf(ragged, options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("the record length 1529 is not a multiple of period_length 512")));

  options.transient_periods = 2;
  EXPECT_THAT([&] { periodic_frf(whole, options); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("too few samples")));

  options.period_length = 2;
  EXPECT_THAT([&] { periodic_frf(whole, options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("PeriodicFrfOptions.period_length is 2; it must be >= 4")));
  options.period_length = kPeriod;
  options.transient_periods = -1;
  EXPECT_THAT([&] { periodic_frf(whole, options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("PeriodicFrfOptions.transient_periods is -1")));
  options.transient_periods = 0;
  options.lines = {0};
  EXPECT_THAT([&] { periodic_frf(whole, options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("PeriodicFrfOptions.lines[0] is 0; it must be >= 1")));
  options.lines = {1, kPeriod};
  EXPECT_THAT([&] { periodic_frf(whole, options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("PeriodicFrfOptions.lines[1] is " + std::to_string(kPeriod) +
                            "; it must be <= period_length/2 = " + std::to_string(kPeriod / 2))));
}

TEST(WelchFrf, NoiseFreeCoherenceIsOneAndH1FollowsTheResponse) {
  // A well-damped model (zeta = 0.75) whose memory (~3 s) is short against a segment
  // (1024 h = 51 s), so the window's leakage of the segment-edge transients stays small.
  const TransferFunction g(Polynomial{4.0}, Polynomial{4.0, 3.0, 1.0});
  const Eigen::VectorXd u = white_noise(32768, 1.0, 21);
  WelchOptions options;
  options.segment_length = 1024;
  const Frf frf = welch_frf(SampledData(kH, u, simulate(g, u, kH)), options);
  EXPECT_EQ(frf.block_length, 1024);
  EXPECT_EQ(frf.averages, (32768 - 1024) / 512 + 1);
  ASSERT_EQ(frf.response.size(), 512);
  EXPECT_EQ(frf.lines.front(), 1);
  EXPECT_EQ(frf.lines.back(), 512);
  EXPECT_GT(frf.coherence.minCoeff(), 0.97);
  EXPECT_GT(frf.coherence.mean(), 0.998);
  for (Eigen::Index i = 0; i < frf.response.size(); ++i) {
    const Complex truth = zoh_response(g, kH, frf.frequencies(i));
    EXPECT_LT(std::abs(frf.response(i) - truth), 0.03 * std::abs(truth)) << "line " << i + 1;
  }
}

TEST(WelchFrf, CoherenceFallsAsPredictedByTheNoise) {
  // White input of unit variance, white output noise of variance s^2: the true squared
  // coherence is |G|^2 / (|G|^2 + s^2) line by line.
  const TransferFunction g(Polynomial{4.0}, Polynomial{4.0, 3.0, 1.0});
  const Eigen::VectorXd u = white_noise(32768, 1.0, 4);
  const double sigma = 0.3;
  const Eigen::VectorXd y = simulate(g, u, kH) + white_noise(32768, sigma, 9);
  WelchOptions options;
  options.segment_length = 128;
  const Frf frf = welch_frf(SampledData(kH, u, y), options);
  double mean_gap = 0.0;
  for (Eigen::Index i = 0; i < frf.response.size(); ++i) {
    const double g2 = std::norm(zoh_response(g, kH, frf.frequencies(i)));
    mean_gap += std::abs(frf.coherence(i) - g2 / (g2 + sigma * sigma));
  }
  mean_gap /= static_cast<double>(frf.response.size());
  EXPECT_LT(mean_gap, 0.03);
  EXPECT_GT(frf.coherence.minCoeff(), 0.0);
  EXPECT_LT(frf.coherence.maxCoeff(), 1.0);
  EXPECT_TRUE((frf.variance.array() > 0.0).all());
}

TEST(WelchFrf, RejectsBadInput) {
  const Eigen::VectorXd u = white_noise(100, 1.0, 1);
  const SampledData data(kH, u, u);
  EXPECT_THAT([&] { welch_frf(data, WelchOptions{}); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("too few samples: the record has 100 samples, fewer than "
                            "WelchOptions.segment_length = 256")));
  WelchOptions options;
  options.segment_length = 64;
  options.overlap = 1.0;
  EXPECT_THAT([&] { welch_frf(data, options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("WelchOptions.overlap is 1; it must be in [0, 1)")));
  options.overlap = 0.5;
  options.segment_length = 4;
  EXPECT_THAT([&] { welch_frf(data, options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("WelchOptions.segment_length is 4; it must be >= 8")));
}

// Two modes B/(1 + 2 zeta s / w + s^2 / w^2) evaluated directly on a grid.
Complex two_modes(double omega) {
  const Complex s(0.0, omega);
  const auto mode = [&](double w, double zeta, double gain) {
    return gain / (1.0 + 2.0 * zeta * s / w + s * s / (w * w));
  };
  return mode(2.0, 0.02, 1.0) + mode(10.0, 0.03, 0.5);
}

TEST(ResonancePeaks, FindsModesAndHalfPowerDamping) {
  const int n = 4000;
  Eigen::VectorXd w(n);
  Eigen::VectorXcd g(n);
  for (int i = 0; i < n; ++i) {
    w(i) = 0.1 * std::pow(10.0, 3.0 * i / (n - 1));  // 0.1 .. 100 rad/s
    g(i) = two_modes(w(i));
  }
  const std::vector<ResonancePeak> peaks = resonance_peaks(w, g);
  ASSERT_EQ(peaks.size(), 2U);
  // The resonance of a mode sits at w sqrt(1 - 2 zeta^2); the other mode shifts it slightly.
  EXPECT_NEAR(peaks[0].frequency, 2.0, 0.01);
  EXPECT_NEAR(peaks[1].frequency, 10.0, 0.05);
  EXPECT_NEAR(peaks[0].damping_ratio, 0.02, 0.002);
  EXPECT_NEAR(peaks[1].damping_ratio, 0.03, 0.003);
  // The second mode stands higher above its surroundings than the first above the valley.
  EXPECT_GT(peaks[1].prominence_db, peaks[0].prominence_db);
  EXPECT_DOUBLE_EQ(peaks[0].magnitude, std::abs(g(peaks[0].index)));

  PeakOptions options;
  options.max_peaks = 1;
  const auto strongest = resonance_peaks(w, g, options);
  ASSERT_EQ(strongest.size(), 1U);
  EXPECT_EQ(strongest[0].index, peaks[1].index);

  options = PeakOptions{};
  options.min_prominence_db = 200.0;
  EXPECT_TRUE(resonance_peaks(w, g, options).empty());
}

// A measured FRF as the estimators return it: two modes on an excited band, a gap in the
// test signal where Y/U divides noise by almost nothing (a 40 dB spike), and an incoherent
// spike in the band (a disturbance at one line).
Frf measured_two_modes() {
  const int n = 2000;
  Frf frf;
  frf.frequencies.resize(n);
  frf.response.resize(n);
  frf.variance = Eigen::VectorXd::Zero(n);
  frf.coherence = Eigen::VectorXd::Constant(n, 0.99);
  frf.input_level = Eigen::VectorXd::Ones(n);
  for (int i = 0; i < n; ++i) {
    frf.lines.push_back(i + 1);
    frf.frequencies(i) = 0.01 * (i + 1);  // 0.01 .. 20 rad/s
    frf.response(i) = two_modes(frf.frequencies(i));
  }
  for (int i = 600; i < 620; ++i) {  // the gap, 6 .. 6.2 rad/s
    frf.input_level(i) = 1e-4;
    frf.response(i) *= (i == 610 ? 100.0 : 1.0);
  }
  frf.response(1400) *= 30.0;  // 14 rad/s, incoherent
  frf.coherence(1400) = 0.1;
  return frf;
}

TEST(ResonancePeaks, OfAMeasuredFrfAreTheModesNotTheGapsOrIncoherentLines) {
  const Frf frf = measured_two_modes();
  // Peaks of |G| alone include the gap's spike and the incoherent line.
  EXPECT_EQ(resonance_peaks(frf.frequencies, frf.response).size(), 4U);

  // The gap is not searched; the incoherent spike stays unless coherence is asked for.
  EXPECT_EQ(resonance_peaks(frf).size(), 3U);
  PeakOptions coherent;
  coherent.min_coherence = 0.5;
  const std::vector<ResonancePeak> peaks = resonance_peaks(frf, coherent);
  ASSERT_EQ(peaks.size(), 2U);
  EXPECT_NEAR(peaks[0].frequency, 2.0, 0.01);
  EXPECT_NEAR(peaks[1].frequency, 10.0, 0.05);
  for (const ResonancePeak& p : peaks) {
    EXPECT_DOUBLE_EQ(p.coherence, 0.99);
    EXPECT_DOUBLE_EQ(p.input_level, 1.0);
    // The index refers to the FRF passed in, not to its excited subset.
    EXPECT_DOUBLE_EQ(p.magnitude, std::abs(frf.response(p.index)));
  }

  // Searching every line (threshold 0) and accepting any coherence brings both back.
  PeakOptions options;
  options.line_threshold = 0.0;
  options.min_coherence = 0.0;
  EXPECT_EQ(resonance_peaks(frf, options).size(), 4U);
  options.max_peaks = 1;
  const auto strongest = resonance_peaks(frf, options);
  ASSERT_EQ(strongest.size(), 1U);
  EXPECT_EQ(strongest[0].index, 610);  // the gap's 40 dB spike is the most prominent
}

TEST(ExcitedLines, KeepsTheLinesAboveTheThresholdWithAllTheirValues) {
  const Frf frf = measured_two_modes();
  const Frf excited = excited_lines(frf, 0.01);
  ASSERT_EQ(excited.lines.size(), frf.lines.size() - 20);
  EXPECT_EQ(excited.lines[600], 621);
  EXPECT_EQ(excited.frequencies(600), frf.frequencies(620));
  EXPECT_EQ(excited.response(600), frf.response(620));
  EXPECT_EQ(excited.coherence(1380), 0.1);
  EXPECT_EQ(excited_lines(frf, 0.0).lines, frf.lines);
  EXPECT_THAT([&] { excited_lines(frf, 1.0); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("it must be in [0, 1)")));
}

TEST(PeriodicFrf, DefaultThresholdKeepsTheMultisineLinesWhenTheInputIsMeasuredWithNoise) {
  // The measured input carries sensor noise at every line: with a threshold of 1e-6 every
  // line up to Nyquist counts as excited and Y/U there is noise over noise, full of peaks.
  const Multisine u = test_multisine(6, 5);
  const TransferFunction g = resonant();
  const Eigen::VectorXd y = simulate(g, u.signal, kH) + white_noise(u.signal.size(), 1e-4, 7);
  const Eigen::VectorXd measured = u.signal + white_noise(u.signal.size(), 1e-4, 8);
  const SampledData data(kH, measured, y);
  PeriodicFrfOptions options;
  options.period_length = kPeriod;
  options.transient_periods = 3;
  const Frf frf = periodic_frf(data, options);
  EXPECT_EQ(frf.lines, u.lines);
  PeakOptions coherent;
  coherent.min_coherence = 0.5;
  const std::vector<ResonancePeak> peaks = resonance_peaks(frf, coherent);
  ASSERT_EQ(peaks.size(), 1U);
  EXPECT_NEAR(peaks[0].frequency, 2.0, 0.1);
  EXPECT_GT(peaks[0].coherence, 0.99);

  options.line_threshold = 1e-6;
  const Frf every = periodic_frf(data, options);
  EXPECT_EQ(every.lines.size(), static_cast<size_t>(kPeriod / 2));
  EXPECT_GT(resonance_peaks(every.frequencies, every.response).size(), 10U);
}

TEST(ResonancePeaks, RejectsBadInput) {
  const Eigen::VectorXd w = Eigen::VectorXd::LinSpaced(5, 1.0, 5.0);
  const Eigen::VectorXcd g = Eigen::VectorXcd::Ones(4);
  EXPECT_THAT(
      [&] { resonance_peaks(w, g); },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("5 frequencies but 4 response values")));
  Eigen::VectorXd unordered = w;
  unordered(3) = 1.5;
  EXPECT_THAT([&] { resonance_peaks(unordered, Eigen::VectorXcd::Ones(5)); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("frequencies[3] = 1.5")));
  PeakOptions options;
  options.max_peaks = -2;
  EXPECT_THAT([&] { resonance_peaks(w, Eigen::VectorXcd::Ones(5), options); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("PeakOptions.max_peaks is -2; it must be >= 0")));
}

}  // namespace
}  // namespace ctid::frf_test
