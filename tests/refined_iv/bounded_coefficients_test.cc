// Bounds in the refined IV iteration (RefinedIvProblem::bounded_coefficients, decision 0058):
// a bound the free estimate keeps changes nothing, bit for bit; a bound it would cross holds
// the coefficient at that bound, the same fit as holding it there; the verdict lists the
// constraints that acted, enforced stability included.
#include <cstdint>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/refined_iv/refined_iv.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::bounded_coefficients_test {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr double kH = 0.05;
constexpr double kInf = std::numeric_limits<double>::infinity();

// 2 (1 + 0.3 p) / (1 + 0.4 p + 0.25 p^2): beta = [0.4, 0.25, 2, 0.6].
const AdditiveModel& truth() {
  static const AdditiveModel g({Submodel{Polynomial({1.0, 0.4, 0.25}), Polynomial({2.0, 0.6}), 0}});
  return g;
}

SampledData record(std::uint64_t seed, double noise) {
  const Eigen::VectorXd u = white_noise(1500, 1.0, seed);
  return SampledData(kH, u, simulate(truth(), u, kH) + white_noise(1500, noise, seed + 100));
}

RefinedIvProblem problem_of(const SampledData& data) {
  RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = {SubmodelOrder{2, 1, 0}};
  problem.unfactored = true;
  problem.name = "srivc";
  return problem;
}

TEST(BoundedCoefficients, ABoundTheEstimateKeepsChangesNothing) {
  const SampledData data = record(1, 0.3);
  RefinedIvProblem problem = problem_of(data);
  const EstimationResult free = estimate_refined_iv(problem);
  ASSERT_TRUE(free.converged()) << free.message;
  problem.bounded_coefficients = {{0, 0.1, 1.0}, {2, 1.0, kInf}, {3, -kInf, 5.0}};
  const EstimationResult bounded = estimate_refined_iv(problem);
  EXPECT_EQ(bounded.parameters, free.parameters);
  EXPECT_EQ(bounded.covariance, free.covariance);
  EXPECT_TRUE(bounded.verdict.active_constraints.empty());
}

TEST(BoundedCoefficients, ACrossedBoundHoldsTheCoefficientThere) {
  for (std::uint64_t seed = 2; seed <= 4; ++seed) {
    const SampledData data = record(seed, 0.3);
    RefinedIvProblem problem = problem_of(data);
    problem.bounded_coefficients = {{2, 0.5, 1.5}};  // b0 = 2 lies above
    const EstimationResult bounded = estimate_refined_iv(problem);
    problem.bounded_coefficients.clear();
    problem.held_coefficients = {{2, 1.5}};
    const EstimationResult held = estimate_refined_iv(problem);
    ASSERT_TRUE(bounded.converged()) << bounded.message;
    EXPECT_EQ(bounded.parameters(2), 1.5);
    EXPECT_LT((bounded.parameters - held.parameters).norm(), 1e-12 * held.parameters.norm())
        << "seed " << seed;
    EXPECT_LT((bounded.covariance - held.covariance).norm(), 1e-8 * held.covariance.norm());
    EXPECT_EQ(bounded.standard_errors(2), 0.0);
    EXPECT_THAT(bounded.verdict.active_constraints, ElementsAre("theta1.b0 is at its bound 1.5"));
    EXPECT_TRUE(bounded.verdict.usable) << bounded.verdict.summary();
  }
}

TEST(BoundedCoefficients, TwoCrossedBoundsAndNoiseFreeRecoveryWithinBounds) {
  const SampledData data = record(5, 0.0);
  RefinedIvProblem problem = problem_of(data);
  // Bounds that hold the truth: exact recovery.
  problem.bounded_coefficients = {{0, 0.3, 0.5}, {1, 0.0, 0.3}, {3, 0.5, 0.7}};
  const EstimationResult within = estimate_refined_iv(problem);
  ASSERT_TRUE(within.converged()) << within.message;
  EXPECT_LT((within.parameters - truth().parameters()).norm(), 1e-9);
  // a1 = 0.4 and b1 = 0.6 both outside: the fit with both held at the bounds.
  problem.bounded_coefficients = {{0, 0.45, 1.0}, {3, 0.0, 0.5}};
  const EstimationResult bounded = estimate_refined_iv(problem);
  problem.bounded_coefficients.clear();
  problem.held_coefficients = {{0, 0.45}, {3, 0.5}};
  const EstimationResult held = estimate_refined_iv(problem);
  EXPECT_EQ(bounded.parameters(0), 0.45);
  EXPECT_EQ(bounded.parameters(3), 0.5);
  EXPECT_LT((bounded.parameters - held.parameters).norm(), 1e-12 * held.parameters.norm());
  EXPECT_THAT(bounded.verdict.active_constraints,
              ElementsAre("theta1.a1 is at its bound 0.45", "theta1.b1 is at its bound 0.5"));
}

// Two modes 3 / (1 + 0.2 p + 0.5 p^2) + 0.4 / (1 + 0.05 p + 0.1 p^2): in the additive
// iteration a bounded coefficient is held in its own column, as a held one is.
TEST(BoundedCoefficients, TheAdditiveIterationBoundsInTheOwnColumn) {
  const AdditiveModel modes({Submodel{Polynomial({1.0, 0.2, 0.5}), Polynomial({3.0}), 0},
                             Submodel{Polynomial({1.0, 0.05, 0.1}), Polynomial({0.4}), 0}});
  const Eigen::VectorXd u = white_noise(3000, 1.0, 7);
  const SampledData data(kH, u, simulate(modes, u, kH) + white_noise(3000, 0.2, 8));
  RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = modes.orders();
  problem.name = "additive_srivc";
  problem.bounded_coefficients = {{5, -kInf, 0.3}};  // theta2.b0 = 0.4 lies above
  const EstimationResult bounded = estimate_refined_iv(problem);
  problem.bounded_coefficients.clear();
  problem.held_coefficients = {{5, 0.3}};
  const EstimationResult held = estimate_refined_iv(problem);
  ASSERT_TRUE(bounded.converged()) << bounded.message;
  EXPECT_LT((bounded.parameters - held.parameters).norm(), 1e-12 * held.parameters.norm());
  EXPECT_THAT(bounded.verdict.active_constraints, ElementsAre("theta2.b0 is at its bound 0.3"));
}

// Enforced stability: a start with right-half-plane poles is reflected, the model returned is
// stable, and the verdict says the constraint acted; a stable start leaves it silent.
TEST(BoundedCoefficients, TheVerdictSaysWhenStabilityWasEnforced) {
  const SampledData data = record(6, 0.3);
  RefinedIvProblem problem = problem_of(data);
  RefinedIvOptions options;
  options.initial_model =
      AdditiveModel({Submodel{Polynomial({1.0, -0.4, 0.25}), Polynomial({2.0, 0.6}), 0}});
  const EstimationResult r = estimate_refined_iv(problem, options);
  EXPECT_GE(r.unstable_reflections, 1);
  EXPECT_TRUE(r.transfer_function.is_stable());
  ASSERT_EQ(r.verdict.active_constraints.size(), 1u);
  EXPECT_THAT(r.verdict.active_constraints[0],
              HasSubstr("stability: right-half-plane poles were reflected into the left"));
  options.initial_model = truth();
  EXPECT_TRUE(estimate_refined_iv(problem, options).verdict.active_constraints.empty());
}

TEST(BoundedCoefficients, AnEmptyBoundIsRefused) {
  const SampledData data = record(7, 0.1);
  RefinedIvProblem problem = problem_of(data);
  problem.bounded_coefficients = {{1, 0.5, 0.2}};
  try {
    estimate_refined_iv(problem);
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("bounded coefficient 1 is not in beta (4 coefficients) or "
                                    "its bounds [0.5, 0.2] are empty"));
  }
}

}  // namespace
}  // namespace ctid::bounded_coefficients_test
