// The spectral kernels shared by `ctid frf` and mode relocation: the periodogram on the FFT
// grid against the DFT sum, the running median floor, the excited band, the local-maximum
// test, prominence and parabolic interpolation, and periodogram peaks above their floor.
#include "ctid/frequency/peaks.h"

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/frequency/periodogram.h"
#include "ctid/simulation/excitation.h"

namespace ctid::peaks_test {
namespace {

using ::testing::HasSubstr;
constexpr double kPi = std::numbers::pi;

TEST(Periodogram, IsTheSquaredDftBelowNyquistOfTheZeroPaddedRecord) {
  const Eigen::VectorXd x = white_noise(7, 1.0, 3);
  for (int padding : {1, 2, 3}) {
    const Eigen::VectorXd p = periodogram(x, padding);
    const int length = 7 * padding;
    ASSERT_EQ(p.size(), length / 2);
    for (int k = 0; k < p.size(); ++k) {
      std::complex<double> sum = 0.0;
      for (int n = 0; n < 7; ++n) sum += x(n) * std::polar(1.0, -2.0 * kPi * k * n / length);
      EXPECT_NEAR(p(k), std::norm(sum), 1e-12) << "padding " << padding << ", bin " << k;
    }
  }
  EXPECT_EQ(periodogram(Eigen::VectorXd::Ones(1)).size(), 0);
}

TEST(Periodogram, ThrowsForZeroPadding) {
  EXPECT_THROW(periodogram(Eigen::VectorXd::Ones(8), 0), InvalidArgument);
}

TEST(RunningMedian, TakesTheMedianOfEachLinesWindowAtTheStride) {
  // Lines 0..5 at stride 2: bins 0, 2, 4, ...; the odd bins must not be read.
  Eigen::VectorXd power(12);
  power << 100, -1, 5, -1, 1, -1, 9, -1, 3, -1, 7, -1;
  const Eigen::VectorXd m = running_median(power, 6, 1, 2);
  ASSERT_EQ(m.size(), 6);
  EXPECT_EQ(m(0), 0.0);  // DC is never part of a window
  EXPECT_EQ(m(1), 5.0);  // {5, 1}: the upper median of an even count
  EXPECT_EQ(m(2), 5.0);  // {5, 1, 9}
  EXPECT_EQ(m(3), 3.0);  // {1, 9, 3}
  EXPECT_EQ(m(4), 7.0);  // {9, 3, 7}
  EXPECT_EQ(m(5), 7.0);  // {3, 7}
  EXPECT_THROW(running_median(power, 7, 1, 2), InvalidArgument);  // bin 12 is missing
  EXPECT_THROW(running_median(power, 6, 0, 2), InvalidArgument);
}

TEST(ExcitedBand, IsTheBandOfAMultisine) {
  MultisineOptions options;
  options.period_length = 1024;
  options.sample_time = 1.0;
  options.min_frequency = 100.0 / 1024;
  options.max_frequency = 300.0 / 1024;
  const Eigen::VectorXd u = multisine(options).signal;
  const std::vector<bool> band = excited_band(u, 4, 0.01);
  ASSERT_EQ(band.size(), 512u);
  EXPECT_FALSE(band[0]);
  for (int j : {110, 200, 290}) EXPECT_TRUE(band[static_cast<size_t>(j)]) << j;
  for (int j : {1, 50, 90, 310, 400, 511}) EXPECT_FALSE(band[static_cast<size_t>(j)]) << j;
  EXPECT_THROW(excited_band(u, 4, 1.5), InvalidArgument);
}

TEST(LocalMaximum, CountsAFlatTopOnceAtItsLeftEnd) {
  Eigen::VectorXd v(6);
  v << 0, 2, 2, 1, 3, 3;
  EXPECT_TRUE(is_local_maximum(v, 1));
  EXPECT_FALSE(is_local_maximum(v, 2));
  EXPECT_FALSE(is_local_maximum(v, 3));
  EXPECT_TRUE(is_local_maximum(v, 4));
}

TEST(Prominence, IsTheHeightAboveTheHigherOfTheSurroundingMinima) {
  Eigen::VectorXd v(7);
  v << 1, 5, 2, 4, 0, 6, 3;
  EXPECT_EQ(prominence(v, 3), 2.0);  // 4 over min(2) on the left, min(0) on the right
  EXPECT_EQ(prominence(v, 1), 4.0);  // left: 1; right: down to 0 before 6
  EXPECT_EQ(prominence(v, 5), 3.0);  // the grid's end on the right
}

TEST(ParabolicVertex, IsExactForAParabolaAndClamped) {
  const auto y = [](double x) { return -2.0 * (x - 1.3) * (x - 1.3) + 4.0; };
  EXPECT_NEAR(parabolic_vertex(1.0, 1.5, 2.5, y(1.0), y(1.5), y(2.5)), 1.3, 1e-12);
  EXPECT_EQ(parabolic_vertex(1.0, 2.0, 3.0, 0.0, 1.0, 5.0), 2.0);   // opens upwards
  EXPECT_EQ(parabolic_vertex(0.0, 1.0, 2.0, 0.0, 1.0, 1.99), 2.0);  // vertex beyond x2
  // Equally spaced: the offset in steps, clamped to half a step.
  EXPECT_NEAR(parabolic_vertex_offset(y(1.0), y(1.5), y(2.0)), -0.4, 1e-12);
  EXPECT_EQ(parabolic_vertex_offset(0.0, 1.0, 1.99), 0.5);
  EXPECT_EQ(parabolic_vertex_offset(1.0, 0.0, 1.0), 0.0);
  EXPECT_EQ(parabolic_vertex_offset(-INFINITY, 0.0, -1.0), 0.0);
}

class PeriodogramPeaks : public ::testing::Test {
 protected:
  // Two sinusoids between DFT lines over white noise; h = 0.01 s, N = 2048.
  PeriodogramPeaks() : x(white_noise(kN, 0.1, 5)) {
    for (int n = 0; n < kN; ++n) {
      const double t = n * kH;
      x(n) += std::sin(kStrong * t) + 0.3 * std::sin(kWeak * t + 0.4);
    }
  }
  static constexpr int kN = 2048;
  static constexpr double kH = 0.01;
  static constexpr double kLine = 2.0 * kPi / (kN * kH);
  static constexpr double kStrong = 120.4 * kLine;
  static constexpr double kWeak = 400.7 * kLine;
  Eigen::VectorXd x;
};

TEST_F(PeriodogramPeaks, FindsBothSinusoidsHighestFirst) {
  PeriodogramPeakOptions options;
  options.max_peaks = 2;
  const std::vector<PeriodogramPeak> peaks = periodogram_peaks(x, kH, options);
  ASSERT_EQ(peaks.size(), 2u);
  EXPECT_NEAR(peaks[0].frequency, kStrong, 0.1 * kLine);
  EXPECT_NEAR(peaks[1].frequency, kWeak, 0.1 * kLine);
  EXPECT_GT(peaks[0].ratio, peaks[1].ratio);
  EXPECT_GT(peaks[1].ratio, 100.0);
}

TEST_F(PeriodogramPeaks, KeepsOnlyAllowedLinesAndSeparatedPeaks) {
  PeriodogramPeakOptions options;
  options.min_separation = 5.0;
  std::vector<bool> allowed(kN / 2, true);
  for (int j = 100; j < 140; ++j) allowed[static_cast<size_t>(j)] = false;
  const std::vector<PeriodogramPeak> peaks = periodogram_peaks(x, kH, options, allowed);
  ASSERT_FALSE(peaks.empty());
  EXPECT_NEAR(peaks[0].frequency, kWeak, 0.1 * kLine);
  for (size_t i = 0; i < peaks.size(); ++i) {
    EXPECT_GE(peaks[i].ratio, options.min_peak_to_floor);
    EXPECT_GT(std::abs(peaks[i].frequency - kStrong), 15.0 * kLine);
    for (size_t j = 0; j < i; ++j) {
      EXPECT_GE(peaks[j].ratio, peaks[i].ratio);
      EXPECT_GE(std::abs(peaks[i].frequency - peaks[j].frequency), 5.0 * kLine);
    }
  }
}

TEST_F(PeriodogramPeaks, RejectsBadOptionsByFieldAndShortRecordsHaveNone) {
  PeriodogramPeakOptions options;
  options.zero_padding = 0;
  try {
    periodogram_peaks(x, kH, options);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("PeriodogramPeakOptions.zero_padding is 0; it must be >= 1"));
  }
  EXPECT_THROW(periodogram_peaks(x, 0.0), InvalidArgument);
  EXPECT_THROW(periodogram_peaks(x, kH, {}, std::vector<bool>(3, true)), InvalidArgument);
  EXPECT_TRUE(periodogram_peaks(Eigen::VectorXd::Ones(3), kH).empty());
}

}  // namespace
}  // namespace ctid::peaks_test
