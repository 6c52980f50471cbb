// The Bode band of an additive model: the first-order magnitude and phase standard deviations
// against their closed forms for G = b / (1 + a p), and the errors for a covariance that does
// not fit the model.
#include "ctid/frequency/response_band.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/frequency/response.h"

namespace ctid::response_band_test {
namespace {

using ::testing::HasSubstr;

// theta = [a, b] of b / (1 + a p).
AdditiveModel first_order(double a, double b) {
  return AdditiveModel::from_parameters({{1, 0, 0}}, Eigen::Vector2d(a, b));
}

TEST(FrequencyResponseBand, FirstOrderMatchesTheClosedForm) {
  const double a = 0.4;
  const double b = 2.5;
  Eigen::Matrix2d p;
  p << 4e-4, -1e-4, -1e-4, 9e-4;  // correlated parameters
  const Eigen::Vector4d omegas(0.1, 1.0, 2.5, 40.0);
  const FrequencyResponseBand band = frequency_response_band(first_order(a, b), omegas, p);
  EXPECT_LT((band.response - frequency_response(first_order(a, b), omegas)).norm(), 1e-15);
  for (int i = 0; i < omegas.size(); ++i) {
    const double w = omegas(i);
    const double q = 1.0 + a * a * w * w;
    // |G| = b / sqrt(q), arg G = -atan(a w).
    const Eigen::Vector2d g_magnitude(-b * a * w * w / std::pow(q, 1.5), 1.0 / std::sqrt(q));
    const Eigen::Vector2d g_phase(-w / q, 0.0);
    const double magnitude_sigma = std::sqrt(g_magnitude.dot(p * g_magnitude));
    const double phase_sigma = std::sqrt(g_phase.dot(p * g_phase));
    EXPECT_NEAR(band.magnitude_sigma(i), magnitude_sigma, 1e-8 * magnitude_sigma) << "w = " << w;
    EXPECT_NEAR(band.phase_sigma(i), phase_sigma, 1e-8 * phase_sigma) << "w = " << w;
  }
}

TEST(FrequencyResponseBand, ZeroCovarianceGivesZeroBand) {
  const FrequencyResponseBand band = frequency_response_band(
      first_order(0.4, 2.5), Eigen::Vector2d(1.0, 3.0), Eigen::Matrix2d::Zero());
  EXPECT_EQ(band.magnitude_sigma, Eigen::Vector2d::Zero());
  EXPECT_EQ(band.phase_sigma, Eigen::Vector2d::Zero());
}

TEST(FrequencyResponseBand, RefusesACovarianceThatDoesNotFitTheModel) {
  const AdditiveModel g = first_order(0.4, 2.5);
  try {
    frequency_response_band(g, Eigen::Vector2d(1.0, 3.0), Eigen::Matrix3d::Identity());
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("the covariance is 3x3 but the model has 2 parameters"));
  }
  Eigen::Matrix2d p = Eigen::Matrix2d::Identity();
  p(0, 1) = std::nan("");
  EXPECT_THROW(frequency_response_band(g, Eigen::Vector2d(1.0, 3.0), p), InvalidArgument);
}

}  // namespace
}  // namespace ctid::response_band_test
