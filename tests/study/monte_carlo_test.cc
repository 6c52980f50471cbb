// The Monte Carlo engine: seed hash against the published splitmix64 sequence, log spacing,
// the index-ordered parallel loop, and MSE/slope summaries on synthetic cases with known
// answers.
#include "ctid/study/monte_carlo.h"

#include <atomic>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"

namespace ctid::monte_carlo_test {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(Splitmix64, MatchesTheReferenceGeneratorSeededWithZero) {
  // The reference generator keeps state s, adds 0x9E3779B97F4A7C15 and mixes: its first
  // outputs from s = 0 are the published values below.
  EXPECT_EQ(splitmix64(0), 0xE220A8397B1DCDAFULL);
  EXPECT_EQ(splitmix64(0x9E3779B97F4A7C15ULL), 0x6E789E6AA1B965F4ULL);
}

TEST(RunSeed, IsDeterministicAndDistinctOverAStudyGrid) {
  std::set<std::uint64_t> seen;
  for (int j = 0; j < 50; ++j) {
    for (int r = 0; r < 300; ++r) {
      EXPECT_EQ(run_seed(7, j, r), run_seed(7, j, r));
      seen.insert(run_seed(7, j, r));
    }
  }
  EXPECT_EQ(seen.size(), 50u * 300u);
  EXPECT_NE(run_seed(7, 0, 0), run_seed(8, 0, 0));
  EXPECT_NE(stream_seed(run_seed(7, 0, 0), 0), stream_seed(run_seed(7, 0, 0), 1));
  EXPECT_THROW(run_seed(1, -1, 0), InvalidArgument);
}

TEST(LogSpacedSizes, KeepsTheEndpointsAndAConstantRatio) {
  const std::vector<int> sizes = log_spaced_sizes(500, 123036, 50);
  ASSERT_EQ(sizes.size(), 50u);
  EXPECT_EQ(sizes.front(), 500);
  EXPECT_EQ(sizes.back(), 123036);
  const double ratio = std::pow(123036.0 / 500.0, 1.0 / 49.0);
  for (size_t k = 1; k < sizes.size(); ++k) {
    EXPECT_GT(sizes[k], sizes[k - 1]);
    EXPECT_NEAR(sizes[k], 500.0 * std::pow(ratio, static_cast<double>(k)), 0.5);
  }
  EXPECT_EQ(log_spaced_sizes(2000, 100000, 1), std::vector<int>{2000});
  EXPECT_THAT([] { log_spaced_sizes(10, 5, 3); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("last is 5")));
}

TEST(ParallelFor, VisitsEveryIndexOnceWhateverTheThreadCount) {
  for (int threads : {1, 2, 5}) {
    std::vector<std::atomic<int>> visits(97);
    parallel_for(97, threads, [&](int i) { visits[static_cast<size_t>(i)].fetch_add(1); });
    for (const auto& v : visits) EXPECT_EQ(v.load(), 1);
  }
  parallel_for(0, 2, [](int) { FAIL(); });
}

TEST(ParallelFor, RethrowsTheBodysException) {
  EXPECT_THROW(parallel_for(20, 3,
                            [](int i) {
                              if (i == 7) throw std::runtime_error("run 7 failed");
                            }),
               std::runtime_error);
}

TEST(SummarizeErrors, ComputesMseBiasAndPredictionSkippingNonFinite) {
  Eigen::VectorXd estimates(5);
  estimates << 1.5, 0.5, 2.0, kNaN, 1.0;  // errors 0.5, -0.5, 1.0, -, 0.0 about truth 1
  Eigen::VectorXd variances(5);
  variances << 0.2, kNaN, 0.4, 9.0, 0.6;
  const ErrorSummary s = summarize_errors(estimates, 1.0, variances);
  EXPECT_EQ(s.runs, 4);
  EXPECT_DOUBLE_EQ(s.mean_squared_error, (0.25 + 0.25 + 1.0 + 0.0) / 4.0);
  EXPECT_DOUBLE_EQ(s.bias, (0.5 - 0.5 + 1.0 + 0.0) / 4.0);
  // The run whose estimate is NaN does not count towards the prediction either.
  EXPECT_EQ(s.predicted_runs, 3);
  EXPECT_DOUBLE_EQ(s.predicted_mean_squared_error, (0.2 + 0.4 + 0.6) / 3.0);
  // MSE = bias^2 + (biased) variance.
  const double mean = 1.0 + s.bias;
  double variance = 0.0;
  for (double e : {1.5, 0.5, 2.0, 1.0}) variance += (e - mean) * (e - mean) / 4.0;
  EXPECT_NEAR(s.mean_squared_error, s.bias * s.bias + variance, 1e-15);
  EXPECT_TRUE(std::isnan(summarize_errors(Eigen::VectorXd::Constant(2, kNaN), 0.0).bias));
  EXPECT_THROW(summarize_errors(estimates, 1.0, Eigen::VectorXd(2)), InvalidArgument);
}

TEST(LogLogSlope, IsMinusOneForMseProportionalToOneOverN) {
  const std::vector<int> n = {500, 1000, 5000, 20000};
  std::vector<double> mse;
  for (int k : n) mse.push_back(3.0 / k);
  EXPECT_NEAR(log_log_slope(n, mse), -1.0, 1e-12);
  mse[1] = kNaN;  // skipped
  EXPECT_NEAR(log_log_slope(n, mse), -1.0, 1e-12);
  EXPECT_TRUE(std::isnan(log_log_slope({10}, {1.0})));
}

}  // namespace
}  // namespace ctid::monte_carlo_test
