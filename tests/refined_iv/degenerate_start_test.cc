// A degenerate model or start is a value where it is found (decision 0045, section 2): the
// loop of a model whose A lost its leading coefficient, a bandwidth whose LSSVF start is not
// finite, a peak that gives no mode and poles that do not fit the structure each give the
// verdict or fallback they gave when a deep call threw InvalidArgument and refined_iv caught
// it, now without an exception.
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/refined_iv/unstable_clsrivc.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"
#include "refined_iv/internal/refined_iv_engine.h"
#include "refined_iv/internal/refined_iv_passes.h"

namespace ctid::degenerate_start_test {
namespace {

using ::testing::HasSubstr;

constexpr double kH = 0.01;

// The message `run` throws (empty if it does not throw).
template <typename Run>
std::string thrown_message(const Run& run) {
  try {
    run();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

// [a_1, a_2, b_0] of 1 / (1 + a_1 p + a_2 p^2): a lightly damped mode, and one whose A lost
// its leading coefficient (a_2 = 1e-300: its roots -1e305 and about -1e-5 are finite, but the
// realisation of 1/A overflows, a_1 omega / a_2 with omega = 1e150 its time scale).
Eigen::VectorXd mode_parameters() { return Eigen::Vector3d(0.02, 1.0 / 400.0, 1.0); }
Eigen::VectorXd degenerate_parameters() { return Eigen::Vector3d(1e5, 1e-300, 1.0); }

DiscreteTransferFunction proportional(double gain) {
  return DiscreteTransferFunction(Polynomial{gain}, Polynomial{1.0}, kH);
}

TEST(DegenerateLoop, ControllerStabilisesIsFalseForAModelWithoutARealisation) {
  const std::vector<SubmodelOrder> orders{SubmodelOrder{2, 0, 0}};
  const internal::srivc_engine::Layout layout(orders);
  // The test behind it is real: a small gain holds the mode, the plant is realised.
  EXPECT_TRUE(internal::srivc_engine::sampled_loop_plant(layout, mode_parameters(), kH));
  EXPECT_TRUE(internal::controller_stabilises(orders, mode_parameters(), proportional(0.3), kH, 0));
  // A lost its leading coefficient, or a parameter is not finite: no plant, no loop.
  Eigen::VectorXd not_finite = mode_parameters();
  not_finite(2) = std::nan("");
  for (const Eigen::VectorXd& beta : {degenerate_parameters(), not_finite}) {
    EXPECT_FALSE(internal::srivc_engine::sampled_loop_plant(layout, beta, kH).has_value());
    bool stabilises = true;
    EXPECT_NO_THROW(stabilises =
                        internal::controller_stabilises(orders, beta, proportional(0.3), kH, 0));
    EXPECT_FALSE(stabilises);
  }
}

TEST(DegenerateLoop, RealisableFailsExactlyWhereTheIterationsFiltersCannotBeFormed) {
  // The engine steps onto no iterate that fails this check (decision 0050); its passes filter
  // with derivative_filters held by a SampledFilter, which throw where the check fails.
  using internal::srivc_engine::denominator_of;
  using internal::srivc_engine::realisable;
  const internal::srivc_engine::Layout mode(std::vector<SubmodelOrder>{SubmodelOrder{2, 0, 0}});
  for (const bool closed_loop : {false, true}) {
    EXPECT_TRUE(realisable(mode, closed_loop, kH, mode_parameters()));
    EXPECT_FALSE(realisable(mode, closed_loop, kH, degenerate_parameters()));
  }
  EXPECT_NO_THROW(SampledFilter(derivative_filters(denominator_of(mode, mode_parameters(), 0)), kH,
                                Hold::zero_order_hold));
  EXPECT_THROW(SampledFilter(derivative_filters(denominator_of(mode, degenerate_parameters(), 0)),
                             kH, Hold::zero_order_hold),
               InvalidArgument);
  // A first-order A whose a_1 is zero has no pole left: derivative_filters refuses it.
  const internal::srivc_engine::Layout pole(std::vector<SubmodelOrder>{SubmodelOrder{1, 0, 0}});
  EXPECT_TRUE(realisable(pole, false, kH, Eigen::Vector2d(0.5, 1.0)));
  EXPECT_FALSE(realisable(pole, false, kH, Eigen::Vector2d(0.0, 1.0)));
  EXPECT_THROW(derivative_filters(denominator_of(pole, Eigen::Vector2d(0.0, 1.0), 0)),
               InvalidArgument);
}

TEST(DegenerateLoop, ReflectingAsAValueIsTheSamePolynomial) {
  // The failures (a root that is not finite, coefficients that overflow) are from_roots' and
  // anti_monic's, as values in tests/core/polynomial_test.cc.
  const Polynomial a = Polynomial{1.0, 0.0, -1.0};  // roots +-1
  bool reflected = false;
  const std::optional<Polynomial> stable = internal::reflect_unstable_roots_if_finite(a, reflected);
  ASSERT_TRUE(stable.has_value());
  EXPECT_TRUE(reflected);
  EXPECT_EQ(*stable, internal::reflect_unstable_roots(a, reflected));
  EXPECT_NEAR(stable->coefficient(1), 2.0, 1e-12);  // (1 + p)^2
}

// Closed-loop data of the mode under u = 0.3 (r - y), white reference.
SampledData closed_loop_record() {
  const AdditiveModel plant =
      AdditiveModel::from_parameters({SubmodelOrder{2, 0, 0}}, mode_parameters());
  const Eigen::VectorXd r = white_noise(2000, 1.0, 7);
  const ClosedLoopSimulation loop = simulate_closed_loop(plant, proportional(0.3), r);
  return SampledData(kH, loop.input, loop.output, r);
}

TEST(DegenerateLoop, UnstableClsrivcFromADegenerateStartIsTheLoopVerdict) {
  // The start's loop cannot be formed: before, unstable_loop_pass_at caught the realisation's
  // InvalidArgument; now the realisation is none. Either way the controller "does not
  // stabilise" it and the fit says so in its termination and verdict.
  RefinedIvOptions options;
  options.initial_model =
      AdditiveModel::from_parameters({SubmodelOrder{2, 0, 0}}, degenerate_parameters());
  std::optional<EstimationResult> fit;
  ASSERT_NO_THROW(fit.emplace(
      unstable_clsrivc(closed_loop_record(), proportional(0.3), SubmodelOrder{2, 0, 0}, options)));
  const EstimationResult& r = *fit;
  EXPECT_EQ(r.termination, Termination::closed_loop_unstable);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_FALSE(r.verdict.usable);
  EXPECT_THAT(r.message, HasSubstr("does not stabilise the initial model"));
}

// Open-loop data of the mode, white input.
SampledData open_loop_record(std::uint64_t seed) {
  const AdditiveModel plant =
      AdditiveModel::from_parameters({SubmodelOrder{2, 0, 0}}, mode_parameters());
  const Eigen::VectorXd u = white_noise(4000, 1.0, seed);
  return SampledData(kH, u, simulate(plant, u, kH));
}

TEST(DegenerateStart, LssvfIsNoneAtABandwidthWhoseFilterOverflows) {
  const SampledData data = open_loop_record(3);
  const SubmodelOrder order{2, 0, 0};
  const std::optional<TransferFunction> start = internal::lssvf_if_finite(data, order, 20.0, 0);
  ASSERT_TRUE(start.has_value());
  const TransferFunction thrown = lssvf(data, order, 20.0);
  EXPECT_EQ(start->numerator(), thrown.numerator());
  EXPECT_EQ(start->denominator(), thrown.denominator());
  // (1 + p / 1e-200)^2: its coefficient 1e400 overflows.
  EXPECT_FALSE(internal::lssvf_if_finite(data, order, 1e-200, 0).has_value());
  EXPECT_THAT(thrown_message([&] { lssvf(data, order, 1e-200); }),
              HasSubstr("has no finite realisation"));
}

TEST(DegenerateStart, ABandwidthWithoutAStartIsSkippedWithoutAnException) {
  const SampledData data = open_loop_record(4);
  const SubmodelOrder order{2, 0, 0};
  InitializationOptions one;
  one.method = StartMethod::lssvf;
  one.filter_bandwidths = {20.0};
  InitializationOptions with_degenerate = one;
  with_degenerate.filter_bandwidths = {1e-200, 20.0};
  const TransferFunction expected = initial_transfer_function(data, order, one);
  TransferFunction start = expected;
  ASSERT_NO_THROW(start = initial_transfer_function(data, order, with_degenerate));
  EXPECT_EQ(start.numerator(), expected.numerator());
  EXPECT_EQ(start.denominator(), expected.denominator());
  // With no bandwidth giving a start, the screen names it (as before).
  with_degenerate.filter_bandwidths = {1e-200};
  EXPECT_THAT(thrown_message([&] { initial_transfer_function(data, order, with_degenerate); }),
              HasSubstr("no candidate start gave a finite model"));
}

TEST(DegenerateStart, APeakAtFrequencyZeroGivesNoMode) {
  ResonancePeak peak;
  peak.frequency = 2.0;
  peak.damping_ratio = 0.1;
  ASSERT_TRUE(internal::mode_from_peak_if_finite(peak).has_value());
  EXPECT_EQ(*internal::mode_from_peak_if_finite(peak), mode_from_peak(peak));
  peak.frequency = 0.0;
  EXPECT_FALSE(internal::mode_from_peak_if_finite(peak).has_value());
  EXPECT_THROW(mode_from_peak(peak), InvalidArgument);
}

TEST(DegenerateStart, FrfPeakStartIsTheSameStartOrNoneWithoutAReasonForTooFewPeaks) {
  const SampledData data = open_loop_record(5);
  std::string failure;
  const std::optional<TransferFunction> start =
      internal::frf_peak_start_if_formed(data, SubmodelOrder{2, 0, 0}, 0, &failure);
  ASSERT_TRUE(start.has_value());
  EXPECT_TRUE(failure.empty());
  const std::optional<TransferFunction> thrown = frf_peak_start(data, SubmodelOrder{2, 0, 0});
  ASSERT_TRUE(thrown.has_value());
  EXPECT_EQ(start->denominator(), thrown->denominator());
  EXPECT_EQ(start->numerator(), thrown->numerator());
  // One mode in the data, three pairs asked for: too few peaks, no reason to report.
  EXPECT_FALSE(internal::frf_peak_start_if_formed(data, SubmodelOrder{6, 0, 0}, 0, &failure));
  EXPECT_TRUE(failure.empty());
}

TEST(DegenerateStart, PolesThatDoNotFitTheStructureAreNoneWithTheReasonGroupingThrows) {
  const SampledData data = open_loop_record(6);
  const TransferFunction third_order(Polynomial{1.0},
                                     Polynomial{1.0, 0.5, 0.1, 0.01});  // three poles
  const std::vector<SubmodelOrder> two_poles{SubmodelOrder{2, 0, 0}};
  std::string failure;
  EXPECT_FALSE(internal::grouped_submodels(third_order, two_poles, data, 0, &failure));
  EXPECT_THAT(failure, HasSubstr("non-zero poles"));
  EXPECT_EQ(failure, thrown_message([&] { group_into_submodels(third_order, two_poles, data); }));
  // Poles that fit give the same model either way.
  const std::vector<SubmodelOrder> three_poles{SubmodelOrder{1, 0, 0}, SubmodelOrder{2, 0, 0}};
  const std::optional<AdditiveModel> grouped =
      internal::grouped_submodels(third_order, three_poles, data, 0);
  ASSERT_TRUE(grouped.has_value());
  EXPECT_EQ(grouped->parameters(),
            group_into_submodels(third_order, three_poles, data).parameters());
}

// The engine's start phase as a value (decision 0050): a start that cannot be formed is none
// with its reason, and the throwing run throws that reason.
internal::RefinedIvProblem open_loop_problem(const SampledData& data, const SubmodelOrder& order) {
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = {order};
  problem.unfactored = true;
  problem.name = "srivc";
  return problem;
}

TEST(DegenerateStart, TooFewPeaksForTheFrfStartIsNoStartAndTheThrowingRunNamesIt) {
  const SampledData data = open_loop_record(8);
  // One mode in the data, two pairs asked for.
  const internal::RefinedIvProblem problem = open_loop_problem(data, SubmodelOrder{4, 0, 0});
  RefinedIvOptions options;
  options.start = StartMethod::frf;
  std::string failure;
  std::optional<EstimationResult> fit;
  ASSERT_NO_THROW(fit = internal::run_refined_iv_if_started(problem, options, nullptr, &failure));
  EXPECT_FALSE(fit.has_value());
  EXPECT_THAT(failure, HasSubstr("fewer resonance peaks than the 2 pole pairs"));
  EXPECT_EQ(failure, thrown_message([&] { srivc(data, SubmodelOrder{4, 0, 0}, options); }));
  // The same structure from LSSVF has a start, and the run is the public estimator's.
  options.start = StartMethod::lssvf;
  fit = internal::run_refined_iv_if_started(problem, options, nullptr, &failure);
  ASSERT_TRUE(fit.has_value());
  EXPECT_EQ(fit->parameters, srivc(data, SubmodelOrder{4, 0, 0}, options).parameters);
}

TEST(DegenerateStart, ADegenerateInitialModelIsNoStartInsteadOfAFilterException) {
  const SampledData data = open_loop_record(9);
  const internal::RefinedIvProblem problem = open_loop_problem(data, SubmodelOrder{2, 0, 0});
  RefinedIvOptions options;
  options.initial_model =
      AdditiveModel::from_parameters({SubmodelOrder{2, 0, 0}}, degenerate_parameters());
  std::string failure;
  std::optional<EstimationResult> fit;
  ASSERT_NO_THROW(fit = internal::run_refined_iv_if_started(problem, options, nullptr, &failure));
  EXPECT_FALSE(fit.has_value());
  EXPECT_THAT(failure, HasSubstr("srivc: the start is degenerate"));
  EXPECT_EQ(failure, thrown_message([&] { srivc(data, SubmodelOrder{2, 0, 0}, options); }));
  // A start that is not degenerate runs.
  options.initial_model =
      AdditiveModel::from_parameters({SubmodelOrder{2, 0, 0}}, mode_parameters());
  fit = internal::run_refined_iv_if_started(problem, options, nullptr, &failure);
  ASSERT_TRUE(fit.has_value());
  EXPECT_EQ(fit->termination, Termination::converged);
}

// Closed-loop data of two overdamped submodels: their FRF has no resonance peak, so the FRF
// start method forms no start for the additive estimator from the data.
SampledData overdamped_closed_loop_record() {
  const AdditiveModel plant = AdditiveModel::from_parameters(
      {SubmodelOrder{1, 0, 0}, SubmodelOrder{1, 0, 0}}, Eigen::Vector4d(0.5, 1.0, 0.05, 0.5));
  const Eigen::VectorXd r = white_noise(3000, 1.0, 11);
  const ClosedLoopSimulation loop = simulate_closed_loop(plant, proportional(0.3), r);
  return SampledData(kH, loop.input, loop.output, r);
}

TEST(DegenerateStart, AClosedLoopAdditiveStartMethodWithoutAStartGivesNoCandidate) {
  const SampledData data = overdamped_closed_loop_record();
  const DiscreteTransferFunction controller = proportional(0.3);
  internal::RefinedIvProblem problem;
  problem.records = {&data};
  problem.orders = {SubmodelOrder{1, 0, 0}, SubmodelOrder{1, 0, 0}};
  problem.controller = &controller;
  problem.name = "clsrivc";
  RefinedIvOptions frf_only;
  frf_only.start = StartMethod::frf;
  std::string failure;
  EXPECT_FALSE(internal::run_refined_iv_if_started(problem, frf_only, nullptr, &failure));
  EXPECT_THAT(failure, HasSubstr("fewer resonance peaks"));
  // From both methods, the FRF's gives no candidate and the LSSVF's are kept: the estimate is
  // the one from LSSVF alone, chosen among the same fits.
  RefinedIvOptions automatic;
  RefinedIvOptions lssvf_only;
  lssvf_only.start = StartMethod::lssvf;
  std::optional<EstimationResult> both;
  ASSERT_NO_THROW(both.emplace(internal::run_refined_iv(problem, automatic)));
  const EstimationResult alone = internal::run_refined_iv(problem, lssvf_only);
  EXPECT_EQ(both->parameters, alone.parameters);
  EXPECT_EQ(both->message, alone.message);
  EXPECT_THAT(both->message, HasSubstr("fits from different starts"));
  // With the FRF's start method alone there is no candidate, and the plain run names why.
  EXPECT_THAT(thrown_message([&] { internal::run_refined_iv(problem, frf_only); }),
              HasSubstr("fewer resonance peaks"));
}

}  // namespace
}  // namespace ctid::degenerate_start_test
