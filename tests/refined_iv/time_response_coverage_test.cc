// The delta-method standard errors of a step response (simulation/time_response.h) taken from
// SRIVC's covariance, against a seeded Monte Carlo of noisy fits of a first-order system: the
// DC gain's reported standard error matches the spread of the estimates, and the pointwise 95 %
// band covers the true step response in most runs.
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"
#include "ctid/simulation/time_response.h"
#include "support/sanitizers.h"

namespace ctid::time_response_coverage_test {
namespace {

TEST(TimeResponseMonteCarlo, BandCoversTheTrueStepAndDcGainErrorMatchesTheSpread) {
  CTID_SKIP_UNDER_SANITIZERS("200 SRIVC fits; the library test covers the same code");
  // 2 / (0.5 p + 1), sampled at h = 0.05 with white noise of 10 % of the output's size.
  const AdditiveModel truth({Submodel{Polynomial({1.0, 0.5}), Polynomial({2.0}), 0}});
  const int n = 400;
  const int runs = 200;
  TimeResponseOptions options;
  options.final_time = 2.0;
  options.points = 9;  // t = 0, 0.25, ..., 2
  const Eigen::VectorXd truth_step = time_response(truth, {}, options).output;
  std::vector<int> covered(static_cast<std::size_t>(options.points), 0);
  double gain_sum = 0.0;
  double gain_square_sum = 0.0;
  double reported_variance_sum = 0.0;
  for (int run = 0; run < runs; ++run) {
    const auto seed = static_cast<std::uint64_t>(run);
    const Eigen::VectorXd u = white_noise(n, 1.0, 7000 + seed);
    const Eigen::VectorXd y = simulate(truth, u, 0.05) + white_noise(n, 0.2, 8000 + seed);
    RefinedIvOptions fit;
    fit.initial_model = truth.with_parameters(truth.parameters() * 1.1);
    const EstimationResult r = srivc(SampledData(0.05, u, y), SubmodelOrder{1, 0}, fit);
    ASSERT_TRUE(r.converged()) << "run " << run << ": " << r.message;
    const TimeResponse step = time_response(r.model, r.covariance, options);
    for (Eigen::Index k = 1; k < truth_step.size(); ++k) {
      if (step.lower(k) <= truth_step(k) && truth_step(k) <= step.upper(k)) {
        ++covered[static_cast<std::size_t>(k)];
      }
    }
    const ResponseEstimate gain = step.characteristics.dc_gain;
    gain_sum += gain.value;
    gain_square_sum += gain.value * gain.value;
    reported_variance_sum += gain.standard_error * gain.standard_error;
  }
  for (Eigen::Index k = 1; k < truth_step.size(); ++k) {
    EXPECT_GE(covered[static_cast<std::size_t>(k)], 0.9 * runs) << "t = " << 0.25 * k;
  }
  const double mean = gain_sum / runs;
  const double spread = std::sqrt((gain_square_sum - runs * mean * mean) / (runs - 1));
  const double reported = std::sqrt(reported_variance_sum / runs);
  EXPECT_NEAR(mean, 2.0, 3.0 * spread / std::sqrt(runs));
  // 200 runs estimate a standard deviation to about +-5 % (one standard deviation).
  EXPECT_GT(reported / spread, 0.8);
  EXPECT_LT(reported / spread, 1.2);
}

}  // namespace
}  // namespace ctid::time_response_coverage_test
