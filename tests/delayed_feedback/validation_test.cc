// White-noise validation of separated models (Section 4 protocol) and its exact expectation.
#include "ctid/delayed_feedback/validation.h"
#include "support/de_iuliis_systems.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace ctid::validation_test {
namespace {

const TransferFunction kF = test_support::paper_feedback_loop().forward;

TEST(FeedbackValidation, IdenticalModelsHaveZeroError) {
  const ResponseComparison r = compare_white_noise_response(kF, kF);
  EXPECT_EQ(r.truth.size(), 1000);
  EXPECT_LT(r.mse, 1e-28);
  EXPECT_LT(r.expected_mse, 1e-28);
  EXPECT_GT(r.truth.squaredNorm(), 1.0);
}

TEST(FeedbackValidation, ExpectedMseMatchesMonteCarloAverage) {
  // A gain error of 10 %: the error system is 0.1 F. The average of 400 realisations must
  // agree with the exact expectation within 4 standard errors of the mean.
  const TransferFunction estimate(1.1 * kF.numerator(), kF.denominator());
  WhiteNoiseValidationOptions options;
  options.duration = 2.0;
  double sum = 0.0, sum2 = 0.0;
  const int runs = 400;
  double expected = 0.0;
  for (int i = 0; i < runs; ++i) {
    options.seed = 100 + static_cast<std::uint64_t>(i);
    const ResponseComparison r = compare_white_noise_response(kF, estimate, options);
    sum += r.mse;
    sum2 += r.mse * r.mse;
    expected = r.expected_mse;
  }
  const double mean = sum / runs;
  const double sem = std::sqrt((sum2 / runs - mean * mean) / runs);
  EXPECT_NEAR(mean, expected, 4.0 * sem);
  // Independent closed form for the first step: E e_1² = (0.1 C Γ)².
  EXPECT_GT(expected, 0.0);
}

TEST(FeedbackValidation, UnstableEstimateIsGuarded) {
  const TransferFunction unstable(Polynomial{1.0}, Polynomial{-50.0, 1.0});
  const ResponseComparison r = compare_white_noise_response(kF, unstable);
  EXPECT_FALSE(r.estimate_stable);
  EXPECT_TRUE(std::isinf(r.mse) || r.mse > 1e100);
  EXPECT_TRUE(std::isinf(r.expected_mse) || r.expected_mse > 1e100);
}

}  // namespace
}  // namespace ctid::validation_test
