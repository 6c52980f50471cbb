// Residual correlations: closed forms for an alternating residual, zeros for a constant one,
// validate_model's report holding the same numbers, and the errors for bad lengths and lags.
#include "ctid/estimation/residual_correlation.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/core/sampled_data.h"
#include "ctid/estimation/validation.h"

namespace ctid::residual_correlation_test {
namespace {

using ::testing::HasSubstr;

// e_t = (-1)^t, t = 0..n-1 (n even: mean 0, sum e^2 = n).
Eigen::VectorXd alternating(int n) {
  Eigen::VectorXd e(n);
  for (int t = 0; t < n; ++t) e(t) = t % 2 == 0 ? 1.0 : -1.0;
  return e;
}

TEST(ResidualCorrelations, AlternatingResidualMatchesTheClosedForm) {
  const int n = 40;
  const int max_lag = 6;
  const Eigen::VectorXd e = alternating(n);
  const Eigen::VectorXd u = 3.0 * e.array() + 7.0;  // the same shape, scaled and offset
  const ResidualCorrelations r = residual_correlations(e, u, max_lag);
  ASSERT_EQ(r.autocorrelation.size(), max_lag + 1);
  ASSERT_EQ(r.cross_correlation.size(), 2 * max_lag + 1);
  for (int k = 0; k <= max_lag; ++k) {
    const double expected = (k % 2 == 0 ? 1.0 : -1.0) * (n - k) / n;  // (-1)^k (n - k) / n
    EXPECT_NEAR(r.autocorrelation(k), expected, 1e-15) << "k = " << k;
  }
  for (int k = -max_lag; k <= max_lag; ++k) {
    const int lag = std::abs(k);
    const double expected = (lag % 2 == 0 ? 1.0 : -1.0) * (n - lag) / n;
    EXPECT_NEAR(r.cross_correlation(k + max_lag), expected, 1e-14) << "k = " << k;
  }
}

TEST(ResidualCorrelations, ConstantResidualGivesZeros) {
  const ResidualCorrelations r =
      residual_correlations(Eigen::VectorXd::Constant(10, 2.0), alternating(10), 3);
  EXPECT_EQ(r.autocorrelation, Eigen::VectorXd::Zero(4));
  EXPECT_EQ(r.cross_correlation, Eigen::VectorXd::Zero(7));
}

TEST(ResidualCorrelations, TheValidationReportHoldsTheSameNumbers) {
  const int n = 64;
  Eigen::VectorXd u(n);
  Eigen::VectorXd y(n);
  for (int t = 0; t < n; ++t) {
    u(t) = std::sin(0.3 * t) + 0.2 * std::cos(1.7 * t);
    y(t) = 0.5 * u(t) + 0.1 * std::sin(2.3 * t + 1.0);
  }
  const SampledData data(0.1, u, y);
  const Eigen::VectorXd modelled = 0.5 * u;
  const ValidationReport report = residual_report(data, modelled, 5);
  const ResidualCorrelations r = residual_correlations(y - modelled, u, 5);
  EXPECT_EQ(report.residual_autocorrelation, r.autocorrelation.tail(5));
  EXPECT_EQ(report.cross_correlation, r.cross_correlation);
}

TEST(ResidualCorrelations, RefusesBadLengthsAndLags) {
  try {
    residual_correlations(alternating(10), alternating(12), 3);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("the residual has 10 samples but the input has 12"));
  }
  try {
    residual_correlations(alternating(10), alternating(10), 10);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("max_lag = 10 must lie in [1, 9]"));
  }
}

}  // namespace
}  // namespace ctid::residual_correlation_test
