// validate_model: residual statistics and the two correlation tests against the 99 % band.
#include <cmath>

#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/estimation/validation.h"
#include "ctid/simulation/excitation.h"

namespace ctid::validation_report_test {
namespace {

// G(s) = 2 / (1 + 0.5 s), h = 0.1 s.
AdditiveModel first_order(double gain) {
  return AdditiveModel({Submodel{Polynomial{1.0, 0.5}, Polynomial{gain}, 0}}, 0.0);
}

TEST(ValidationReport, TrueModelWithWhiteNoiseHasWhiteUncorrelatedResiduals) {
  const double h = 0.1;
  const int n = 4000;
  const Eigen::VectorXd u = white_noise(n, 1.0, 11);
  const Eigen::VectorXd v = white_noise(n, 0.05, 12);
  const Eigen::VectorXd y = model_output(first_order(2.0), u, h) + v;
  const ValidationReport r = validate_model(first_order(2.0), SampledData(h, u, y));
  // The residual is exactly v.
  EXPECT_NEAR(r.residual_mean, v.mean(), 1e-12);
  EXPECT_NEAR(r.mean_squared_error, v.squaredNorm() / n, 1e-12);
  EXPECT_EQ(r.max_lag, 20);
  ASSERT_EQ(r.residual_autocorrelation.size(), 20);
  ASSERT_EQ(r.cross_correlation.size(), 41);
  EXPECT_DOUBLE_EQ(r.whiteness_bound, 2.58 / std::sqrt(static_cast<double>(n)));
  EXPECT_TRUE(r.residual_white()) << r.max_residual_autocorrelation;
  EXPECT_TRUE(r.residual_uncorrelated_with_input()) << r.max_cross_correlation;
  EXPECT_DOUBLE_EQ(r.max_cross_correlation, r.cross_correlation.cwiseAbs().maxCoeff());
}

TEST(ValidationReport, WrongGainLeavesResidualCorrelatedWithTheInputAtTheRightLags) {
  const double h = 0.1;
  const int n = 4000;
  const Eigen::VectorXd u = white_noise(n, 1.0, 21);
  const Eigen::VectorXd y = model_output(first_order(2.0), u, h);
  const ValidationReport r = validate_model(first_order(1.0), SampledData(h, u, y), 5);
  // The residual is the output of 1/(1 + 0.5 s) to u: causal, so r_eu(k) ~ 0 for k < 0 (u
  // white) and positive for k >= 1 (ZOH response starts one sample late).
  EXPECT_FALSE(r.residual_uncorrelated_with_input());
  ASSERT_EQ(r.cross_correlation.size(), 11);
  for (int k = -5; k <= 0; ++k) {
    EXPECT_LT(std::abs(r.cross_correlation(k + 5)), r.whiteness_bound) << "lag " << k;
  }
  for (int k = 1; k <= 5; ++k) EXPECT_GT(r.cross_correlation(k + 5), 0.1) << "lag " << k;
  // Decays like exp(-h/0.5) per lag.
  EXPECT_NEAR(r.cross_correlation(7) / r.cross_correlation(6), std::exp(-0.2), 0.05);
  EXPECT_FALSE(r.residual_white());
}

TEST(ValidationReport, ShortRecordsUseFewerLagsAndBadMaxLagIsRefused) {
  const Eigen::VectorXd u = white_noise(6, 1.0, 1);
  const SampledData data(0.1, u, model_output(first_order(2.0), u, 0.1));
  const ValidationReport r = validate_model(first_order(2.0), data);
  EXPECT_EQ(r.max_lag, 5);
  EXPECT_EQ(r.cross_correlation.size(), 11);
  EXPECT_THROW(validate_model(first_order(2.0), data, 0), InvalidArgument);
}

}  // namespace
}  // namespace ctid::validation_report_test
