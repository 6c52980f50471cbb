// Held coefficients in the refined IV iteration (RefinedIvProblem::held_coefficients, decision
// 0057): exact recovery from noise-free data; holding a coefficient at the free estimate's
// value gives the free estimate back (the same stationary point) with the covariance of the
// free coefficients given the held one; refusals.
#include <cmath>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/refined_iv/refined_iv.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::held_coefficients_test {
namespace {

constexpr double kH = 0.05;

// 2 (1 + 0.3 p) / (1 + 0.4 p + 0.25 p^2): beta = [0.4, 0.25, 2, 0.6].
const AdditiveModel& truth() {
  static const AdditiveModel g({Submodel{Polynomial({1.0, 0.4, 0.25}), Polynomial({2.0, 0.6}), 0}});
  return g;
}

SampledData record(std::uint64_t seed, double noise) {
  const Eigen::VectorXd u = white_noise(1500, 1.0, seed);
  return SampledData(kH, u, simulate(truth(), u, kH) + white_noise(1500, noise, seed + 100));
}

EstimationResult fit(const SampledData& data, std::vector<std::pair<Eigen::Index, double>> held) {
  RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = {SubmodelOrder{2, 1, 0}};
  problem.unfactored = true;
  problem.name = "srivc";
  problem.held_coefficients = std::move(held);
  return estimate_refined_iv(problem);
}

TEST(HeldCoefficients, NoiseFreeRecoveryWithAHeldDcGain) {
  const EstimationResult r = fit(record(1, 0.0), {{2, 2.0}});
  ASSERT_TRUE(r.converged()) << r.message;
  const Eigen::Vector4d beta(0.4, 0.25, 2.0, 0.6);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(r.parameters(i), beta(i), 1e-9 * beta(i)) << i;
  EXPECT_EQ(r.parameters(2), 2.0);
}

TEST(HeldCoefficients, HoldingTheFreeEstimateGivesItBackWithTheConditionalCovariance) {
  for (std::uint64_t seed = 2; seed <= 4; ++seed) {
    const SampledData data = record(seed, 0.3);
    const EstimationResult free = fit(data, {});
    ASSERT_TRUE(free.converged()) << free.message;
    for (const Eigen::Index j : {Eigen::Index{0}, Eigen::Index{2}}) {
      const EstimationResult held = fit(data, {{j, free.parameters(j)}});
      ASSERT_TRUE(held.converged()) << held.message;
      EXPECT_LT((held.parameters - free.parameters).norm() / free.parameters.norm(), 1e-8)
          << "seed " << seed << ", held " << j;
      // P_ff - P_fh P_hh^-1 P_hf of the free fit's covariance at (nearly) the same point.
      const Eigen::MatrixXd& p = free.covariance;
      for (Eigen::Index a = 0; a < 4; ++a) {
        if (a == j) {
          EXPECT_EQ(held.standard_errors(a), 0.0);
          continue;
        }
        const double expected = p(a, a) - p(a, j) * p(a, j) / p(j, j);
        EXPECT_NEAR(held.covariance(a, a), expected, 1e-5 * expected) << "seed " << seed;
      }
    }
  }
}

TEST(HeldCoefficients, AreForAnUnfactoredModel) {
  const SampledData data = record(5, 0.1);
  RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = {SubmodelOrder{2, 1, 0}};
  problem.unfactored = false;
  problem.name = "additive_srivc";
  problem.held_coefficients = {{0, 0.4}};
  try {
    estimate_refined_iv(problem);
    ADD_FAILURE() << "held coefficients of an additive problem were accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("held coefficients are for an unfactored model"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace ctid::held_coefficients_test
