// Held coefficients in the refined IV iteration (RefinedIvProblem::held_coefficients, decision
// 0057): exact recovery from noise-free data; holding a coefficient at the free estimate's
// value gives the free estimate back (the same stationary point) with the covariance of the
// free coefficients given the held one; the additive iteration holds them too.
#include <cmath>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

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

// Two modes 3 / (1 + 0.2 p + 0.5 p^2) + 0.4 / (1 + 0.05 p + 0.1 p^2): the additive iteration
// (29), the coefficient held in its submodel's column and 0 in the other (Lemma 4.4).
TEST(HeldCoefficients, TheAdditiveIterationHoldsThemInTheirOwnColumn) {
  const AdditiveModel modes({Submodel{Polynomial({1.0, 0.2, 0.5}), Polynomial({3.0}), 0},
                             Submodel{Polynomial({1.0, 0.05, 0.1}), Polynomial({0.4}), 0}});
  const Eigen::VectorXd u = white_noise(3000, 1.0, 7);
  const SampledData data(kH, u, simulate(modes, u, kH) + white_noise(3000, 0.2, 8));
  RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = modes.orders();
  problem.name = "additive_srivc";
  const EstimationResult free = estimate_refined_iv(problem);
  ASSERT_TRUE(free.converged()) << free.message;
  for (const Eigen::Index j : {Eigen::Index{1}, Eigen::Index{5}}) {  // theta1.a2, theta2.b0
    problem.held_coefficients = {{j, free.parameters(j)}};
    const EstimationResult held = estimate_refined_iv(problem);
    ASSERT_TRUE(held.converged()) << held.message;
    EXPECT_EQ(held.parameters(j), free.parameters(j));
    EXPECT_LT((held.parameters - free.parameters).norm() / free.parameters.norm(), 1e-8) << j;
    EXPECT_EQ(held.standard_errors(j), 0.0);
  }
  // Noise-free with the first mode's gain held at the truth: exact.
  const SampledData exact(kH, u, simulate(modes, u, kH));
  problem.records = {&exact};
  problem.held_coefficients = {{2, 3.0}};
  const EstimationResult r = estimate_refined_iv(problem);
  EXPECT_LT((r.parameters - modes.parameters()).norm(), 1e-9);
}

}  // namespace
}  // namespace ctid::held_coefficients_test
