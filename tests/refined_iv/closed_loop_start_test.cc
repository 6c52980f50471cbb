// Starts from closed-loop data alone (initialization.h with a controller, decision 0011). The
// plant of Section 6.2 under a proportional controller close to its stability limit, with the
// paper's coloured noise: the open-loop start (LSSVF / FRF peaks refined by SRIVC on u -> y)
// is often a model the controller does not stabilise, which stops CLSRIVC before its first
// step. With the controller known, every candidate is made one it stabilises and refined by
// CLSRIVC, so the estimators run and end where a start from the true system ends.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"
#include "refined_iv/internal/refined_iv_engine.h"
#include "support/paper_systems.h"
#include "support/sanitizers.h"

namespace ctid::closed_loop_start_test {
namespace {

using ::testing::HasSubstr;

constexpr double kH = testing::kPaperSampleTime;
constexpr SubmodelOrder kUnfactored{4, 2, 0};
// Records per estimator: 20; under AddressSanitizer (scripts/test.sh's second ctest) the
// first 8, which this file's thresholds were checked to hold on, keep that step quick.
#ifdef __SANITIZE_ADDRESS__
constexpr int kSeeds = 8;
constexpr int kDestabilising = 2;
#else
constexpr int kSeeds = 20;
constexpr int kDestabilising = 3;
#endif

// u_k = 0.33 (r_k - y_k): the loop with the Section 6.2 plant loses stability at a gain of
// about 0.37 (its lightly damped mode at 6.3 rad/s), so a model whose resonance is a little
// too high is not stabilised.
DiscreteTransferFunction tight_controller() {
  return DiscreteTransferFunction(Polynomial{0.33}, Polynomial{1.0}, kH);
}

double loop_radius(const TransferFunction& g, const DiscreteTransferFunction& c) {
  return closed_loop_poles(zoh_equivalent(g, kH), c).cwiseAbs().maxCoeff();
}

// White reference, output noise (q + 0.5)/(q - 0.85) e with var e = 0.04 (none if 0).
SampledData closed_loop_data(std::uint64_t seed, int samples, double noise_variance) {
  const Eigen::VectorXd r = white_noise(samples, 1.0, seed);
  const Eigen::VectorXd v =
      noise_variance > 0.0
          ? colored_noise(testing::open_loop_noise_filter(), samples, noise_variance, 1000 + seed)
          : Eigen::VectorXd();
  const ClosedLoopSimulation loop =
      simulate_closed_loop(testing::closed_loop_two_modes(), tight_controller(), r, v);
  return SampledData(kH, loop.input, loop.output, r);
}

double relative_difference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / b.norm();
}

// The model's transfer function coefficients [numerator; denominator]: the same for the same
// additive model whatever the order of its submodels.
Eigen::VectorXd coefficients(const EstimationResult& r) {
  const TransferFunction& g = r.transfer_function;
  Eigen::VectorXd c(g.numerator().coefficients().size() + g.denominator().coefficients().size());
  c << g.numerator().coefficients(), g.denominator().coefficients();
  return c;
}

RefinedIvOptions quick_options() {
  RefinedIvOptions o;
  o.compute_covariance = false;
  return o;
}

TEST(ClosedLoopStart, TheScenarioNeedsIt) {
  // The true loop is stable, with little margin.
  const double radius =
      loop_radius(testing::closed_loop_two_modes().to_transfer_function(), tight_controller());
  EXPECT_LT(radius, 1.0);
  EXPECT_GT(radius, 0.999);
}

TEST(ClosedLoopStart, NoiseFreeDataGiveTheExactModel) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const SampledData data = closed_loop_data(7, 2000, 0.0);
  const EstimationResult u = clsrivc(data, tight_controller(), kUnfactored, quick_options());
  ASSERT_TRUE(u.converged()) << u.message;
  const TransferFunction g = truth.to_transfer_function();
  for (double w : {0.3, 2.0, 6.3, 20.0}) {
    EXPECT_LT(std::abs(u.transfer_function.frequency_response(w) - g.frequency_response(w)),
              1e-8 * std::abs(g.frequency_response(w)))
        << "w = " << w;
  }
  const EstimationResult a =
      additive_clsrivc(data, tight_controller(), truth.orders(), quick_options());
  ASSERT_TRUE(a.converged()) << a.message;
  EXPECT_LT(relative_difference(a.parameters, truth.parameters()), 1e-8);
}

TEST(ClosedLoopStart, EveryCandidateKeptIsStabilisedByTheController) {
  // The first record whose open-loop start the controller does not stabilise ...
  InitializationOptions options;
  std::uint64_t seed = 1;
  while (seed <= 10 && loop_radius(initial_transfer_function(closed_loop_data(seed, 4000, 0.04),
                                                             kUnfactored, options),
                                   tight_controller()) < 1.0) {
    ++seed;
  }
  ASSERT_LE(seed, 10u) << "no record of seeds 1-10 needs the closed-loop start";
  const SampledData data = closed_loop_data(seed, 4000, 0.04);
  // ... with the controller it is.
  options.controller = tight_controller();
  EXPECT_LT(loop_radius(initial_transfer_function(data, kUnfactored, options), tight_controller()),
            1.0);
  const AdditiveModel additive =
      initial_additive_model(data, testing::closed_loop_two_modes().orders(), options);
  EXPECT_LT(loop_radius(additive.to_transfer_function(), tight_controller()), 1.0);
}

// The several-start fit (decision 0028) screens each start method once for its additive and
// its unfactored fit: the shared start gives both exactly what screening it again gives.
TEST(ClosedLoopStart, AStartScreenedOnceGivesEveryFitWhatItsOwnScreeningGives) {
  CTID_SKIP_UNDER_SANITIZERS(
      "ClosedLoopStart.AFitTheControllerDoesNotStabiliseIsNotUsable runs the same screening");
  const SampledData data = closed_loop_data(3, 4000, 0.04);
  const std::vector<SubmodelOrder> orders = testing::closed_loop_two_modes().orders();
  InitializationOptions init;
  init.controller = tight_controller();
  const TransferFunction g = initial_transfer_function(data, unfactored_order(orders), init);
  EXPECT_EQ(additive_model_from_start(g, data, orders, init).parameters(),
            initial_additive_model(data, orders, init).parameters());

  const DiscreteTransferFunction controller = tight_controller();
  internal::RefinedIvProblem additive;
  additive.records = {&data};
  additive.orders = orders;
  additive.controller = &controller;
  internal::RefinedIvProblem unfactored = additive;
  unfactored.orders = {unfactored_order(orders)};
  unfactored.unfactored = true;
  for (StartMethod method : {StartMethod::lssvf, StartMethod::frf}) {
    RefinedIvOptions o = quick_options();
    o.start = method;
    internal::ScreenedStart shared;
    const EstimationResult a = internal::run_refined_iv_from_start(additive, o, &shared);
    ASSERT_TRUE(shared.g.has_value());
    const EstimationResult u = internal::run_refined_iv_from_start(unfactored, o, &shared);
    const EstimationResult own = internal::run_refined_iv_from_start(additive, o);
    EXPECT_EQ(a.parameters, own.parameters);
    EXPECT_EQ(a.iterations, own.iterations);
    EXPECT_EQ(u.parameters, internal::run_refined_iv_from_start(unfactored, o).parameters);
  }
}

// One estimator over kSeeds records: from the data alone it never stops at iteration 0, and it
// ends where a start from the true system ends on at least pass_rate of them. Returns the
// number of records on which the open-loop start (what the estimator started from before
// decision 0011, `open_loop_start`) is not stabilised by the controller.
template <class Estimate, class OpenLoopStart>
int compare_with_truth_start(const char* name, const Estimate& estimate,
                             const OpenLoopStart& open_loop_start, double pass_rate) {
  int destabilising = 0;
  int same = 0;
  for (std::uint64_t seed = 1; seed <= kSeeds; ++seed) {
    const SampledData data = closed_loop_data(seed, 4000, 0.04);
    const AdditiveModel old_start = open_loop_start(data);
    if (loop_radius(old_start.to_transfer_function(), tight_controller()) >= 1.0) {
      ++destabilising;
      // Before: the estimator from that start stopped at once.
      RefinedIvOptions o = quick_options();
      o.initial_model = old_start;
      EXPECT_EQ(estimate(data, o).termination, Termination::closed_loop_unstable)
          << name << ", seed " << seed;
    }
    const EstimationResult from_data = estimate(data, quick_options());
    EXPECT_NE(from_data.termination, Termination::closed_loop_unstable)
        << name << ", seed " << seed << ": " << from_data.message;
    RefinedIvOptions o = quick_options();
    o.initial_model = testing::closed_loop_two_modes();
    const EstimationResult from_truth = estimate(data, o);
    // The same stationary point: the same model, with its submodels in any order.
    if (from_data.converged() && from_truth.converged() &&
        relative_difference(coefficients(from_data), coefficients(from_truth)) < 1e-6) {
      ++same;
    }
  }
  EXPECT_GE(same, pass_rate * kSeeds) << name;
  std::printf(
      "%s: %d of %d records end at the true start's stationary point; the open-loop "
      "start is not stabilised on %d\n",
      name, same, kSeeds, destabilising);
  return destabilising;
}

// Measured: 72 of seeds 1..80 (unfactored) and 38 of seeds 1..40 (additive, from several
// starts and keeping the usable fit with the best output-error fit, decision 0028; 31 from one
// start) end at the true start's stationary point. The others are records on which CLSRIVC
// has several stationary points (the open-loop start, where the controller stabilises it,
// mostly misses too): the iteration stops at the limit or at a second fixed point. The
// additive estimator misses seeds 5 and 19 of the first 20, so at most 1 in 8 (0.875).
TEST(ClosedLoopStart, ClsrivcFromTheDataEndsWhereTheTrueStartEnds) {
  CTID_SKIP_UNDER_SANITIZERS(
      "ClosedLoopStart.EveryCandidateKeptIsStabilisedByTheController and "
      "FitCommand.ClosedLoopFitNeedsNoStartUnderATightController run the closed-loop start");
  const int destabilising = compare_with_truth_start(
      "clsrivc",
      [](const SampledData& data, const RefinedIvOptions& o) {
        return clsrivc(data, tight_controller(), kUnfactored, o);
      },
      [](const SampledData& data) {
        const TransferFunction g = initial_transfer_function(data, kUnfactored);
        const double scale = g.denominator()[0];
        return AdditiveModel(
            {Submodel{(1.0 / scale) * g.denominator(), (1.0 / scale) * g.numerator(), 0}});
      },
      0.85);
  EXPECT_GE(destabilising, kDestabilising);
}

TEST(ClosedLoopStart, AdditiveClsrivcFromTheDataEndsWhereTheTrueStartEnds) {
  CTID_SKIP_UNDER_SANITIZERS(
      "ClosedLoopStart.EveryCandidateKeptIsStabilisedByTheController and "
      "FitCommand.ClosedLoopFitNeedsNoStartUnderATightController run the closed-loop start");
  const std::vector<SubmodelOrder> orders = testing::closed_loop_two_modes().orders();
  const int destabilising = compare_with_truth_start(
      "additive_clsrivc",
      [&](const SampledData& data, const RefinedIvOptions& o) {
        return additive_clsrivc(data, tight_controller(), orders, o);
      },
      [&](const SampledData& data) { return initial_additive_model(data, orders); }, 0.875);
  EXPECT_GE(destabilising, kDestabilising);
}

// The additive CLSRIVC from the LSSVF start alone of record `seed`.
EstimationResult from_lssvf_start(const SampledData& data) {
  InitializationOptions init;
  init.controller = tight_controller();
  init.method = StartMethod::lssvf;
  const std::vector<SubmodelOrder> orders = testing::closed_loop_two_modes().orders();
  RefinedIvOptions o = quick_options();
  o.initial_model = initial_additive_model(data, orders, init);
  return additive_clsrivc(data, tight_controller(), orders, o);
}

// Records 5 and 19: from the LSSVF start the additive CLSRIVC ends at a model the controller
// does not stabilise (a loop pole at |z| > 1), which cannot be the loop that was recorded.
// From the data alone the estimator also tries the FRF-peak start and the splits of unfactored
// fits (decision 0028): on record 19 it keeps a fit the controller stabilises; on record 5
// every candidate fails a check and the result says so.
TEST(ClosedLoopStart, AFitTheControllerDoesNotStabiliseIsNotUsable) {
  const std::vector<SubmodelOrder> orders = testing::closed_loop_two_modes().orders();
  for (std::uint64_t seed : {5, 19}) {
    const SampledData data = closed_loop_data(seed, 4000, 0.04);
    const EstimationResult one = from_lssvf_start(data);
    EXPECT_GE(loop_radius(one.transfer_function, tight_controller()), 1.0) << seed;
    EXPECT_FALSE(one.verdict.usable) << seed;
    EXPECT_THAT(one.verdict.summary(),
                HasSubstr("the known controller does not stabilise the fitted model"));
    EXPECT_TRUE(std::isnan(one.closed_loop_fit_percent)) << seed;
    EXPECT_TRUE(std::isfinite(one.start_closed_loop_fit_percent)) << seed;
  }

  const SampledData data = closed_loop_data(19, 4000, 0.04);
  const EstimationResult kept = additive_clsrivc(data, tight_controller(), orders, quick_options());
  EXPECT_TRUE(kept.verdict.usable) << kept.verdict.summary();
  EXPECT_LT(loop_radius(kept.transfer_function, tight_controller()), 1.0);
  EXPECT_THAT(kept.message, HasSubstr("of 4 fits from different starts"));
  // The closed-loop fit is the fit of y by the model's output from r through the controller.
  const ClosedLoopSimulation loop = simulate_closed_loop(kept.transfer_function, tight_controller(),
                                                         data.reference(), Eigen::VectorXd());
  const Eigen::VectorXd centred = data.output().array() - data.output().mean();
  EXPECT_NEAR(kept.closed_loop_fit_percent,
              100.0 * (1.0 - (data.output() - loop.output).norm() / centred.norm()), 1e-9);

  const EstimationResult none = additive_clsrivc(closed_loop_data(5, 4000, 0.04),
                                                 tight_controller(), orders, quick_options());
  EXPECT_FALSE(none.verdict.usable);
  EXPECT_FALSE(none.verdict.reasons.empty());
}

TEST(ClosedLoopStart, SaysWhatWasTriedWhenNoStartIsStabilised) {
  const SampledData data = closed_loop_data(3, 1000, 0.0);
  // An unstable controller (pole at z = 1.5) that no small-gain model is stabilised by.
  const DiscreteTransferFunction unstable(Polynomial{0.01}, Polynomial{-1.5, 1.0}, kH);
  const EstimationResult r = clsrivc(data, unstable, kUnfactored, quick_options());
  EXPECT_EQ(r.termination, Termination::closed_loop_unstable);
  EXPECT_THAT(r.message, HasSubstr("does not stabilise any start found from the data"));
  EXPECT_THAT(r.message, HasSubstr("gain halved up to 20 times"));
  EXPECT_THAT(
      [&] {
        InitializationOptions options;
        options.controller = tight_controller();
        initial_transfer_function(SampledData(kH, data.input(), data.output()), kUnfactored,
                                  options);
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("no reference")));
}

}  // namespace
}  // namespace ctid::closed_loop_start_test
