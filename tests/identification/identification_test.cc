// The front door identify(): it runs exactly the estimator the structure and the loop call for
// (bit for bit the direct call), the delay scan and the relocation as the CLI always has, and
// refuses bad structures and options with the full path of the field.
#include "ctid/identification/identification.h"

#include <cstring>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"
#include "support/paper_systems.h"

namespace ctid::identification_test {
namespace {

using ::testing::HasSubstr;

bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

void expect_same(const EstimationResult& a, const EstimationResult& b) {
  EXPECT_TRUE(same_bits(a.parameters, b.parameters));
  EXPECT_TRUE(same_bits(a.covariance, b.covariance));
  EXPECT_EQ(a.termination, b.termination);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.message, b.message);
  EXPECT_EQ(a.input_delay_samples, b.input_delay_samples);
  EXPECT_EQ(std::memcmp(&a.mean_squared_error, &b.mean_squared_error, sizeof(double)), 0);
}

DiscreteTransferFunction paper_pid() {
  const Polynomial den{0.0, -1.0, 1.0};
  const Polynomial num = Polynomial{0.0115} * den +
                         Polynomial{0.0, 0.00725} * Polynomial{0.0, 1.0} +
                         Polynomial{0.00454} * Polynomial{-1.0, 1.0} * Polynomial{-1.0, 1.0};
  return DiscreteTransferFunction(num, den, 0.05);
}

// Section 6.2's plant with a 2-sample input delay, open loop and closed loop.
class Identify : public ::testing::Test {
 protected:
  Identify()
      : truth(testing::closed_loop_two_modes()),
        u(white_noise(1500, 1.0, 41)),
        open(0.05, u, simulate(truth.with_input_delay(0.1), u, 0.05)),
        controller(paper_pid()),
        r(white_noise(1500, 1.0, 42)),
        loop(simulate_closed_loop(truth, controller, r)),
        closed(0.05, loop.input, loop.output, r) {}
  AdditiveModel truth;
  Eigen::VectorXd u;
  SampledData open;
  DiscreteTransferFunction controller;
  Eigen::VectorXd r;
  ClosedLoopSimulation loop;
  SampledData closed;
};

TEST_F(Identify, ChoosesTheEstimatorFromTheStructureAndTheLoop) {
  const ModelStructure unfactored = ModelStructure::unfactored(4, 2);
  const ModelStructure additive = ModelStructure::modes(2);
  EXPECT_EQ(choose_estimator(unfactored, false), RefinedIvEstimator::srivc);
  EXPECT_EQ(choose_estimator(unfactored, true), RefinedIvEstimator::clsrivc);
  EXPECT_EQ(choose_estimator(additive, false), RefinedIvEstimator::additive_srivc);
  EXPECT_EQ(choose_estimator(additive, true), RefinedIvEstimator::additive_clsrivc);
  EXPECT_EQ(enum_name(RefinedIvEstimator::additive_clsrivc), "additive_clsrivc");
  EXPECT_EQ(additive.orders.size(), 2u);
  EXPECT_EQ(additive.orders[1].n, 2);
  EXPECT_EQ(additive.orders[1].m, 0);
  EXPECT_TRUE(additive.is_additive());
  EXPECT_FALSE(unfactored.is_additive());
}

TEST_F(Identify, RunsTheDirectEstimatorBitForBit) {
  IdentificationOptions options;
  options.refined_iv.input_delay_samples = 2;
  const auto direct_options = options.refined_iv;

  const IdentificationResult a = identify(open, ModelStructure::modes(2), options);
  EXPECT_EQ(a.estimator, RefinedIvEstimator::additive_srivc);
  EXPECT_FALSE(a.closed_loop);
  EXPECT_FALSE(a.delay_scan.has_value());
  EXPECT_FALSE(a.mode_relocation.has_value());
  expect_same(a.estimate, additive_srivc(open, truth.orders(), direct_options));

  const IdentificationResult s = identify(open, ModelStructure::unfactored(4, 2), options);
  EXPECT_EQ(s.estimator, RefinedIvEstimator::srivc);
  expect_same(s.estimate, srivc(open, {4, 2, 0}, direct_options));

  options.controller = controller;
  options.refined_iv.input_delay_samples = 0;
  const IdentificationResult c = identify(closed, ModelStructure::unfactored(4, 2), options);
  EXPECT_EQ(c.estimator, RefinedIvEstimator::clsrivc);
  EXPECT_TRUE(c.closed_loop);
  expect_same(c.estimate, clsrivc(closed, controller, {4, 2, 0}, RefinedIvOptions{}));

  const IdentificationResult ac = identify(closed, ModelStructure::modes(2), options);
  EXPECT_EQ(ac.estimator, RefinedIvEstimator::additive_clsrivc);
  expect_same(ac.estimate,
              additive_clsrivc(closed, controller, truth.orders(), RefinedIvOptions{}));
}

TEST_F(Identify, DelayScanKeepsTheBestDelayAndItsTable) {
  IdentificationOptions options;
  options.delay_scan_samples = DelayRange{0, 4};
  const IdentificationResult result = identify(open, ModelStructure::modes(2), options);
  ASSERT_TRUE(result.delay_scan.has_value());
  const InputDelayScanResult direct = additive_srivc_delay_scan(open, truth.orders(), 0, 4);
  EXPECT_EQ(result.delay_scan->delays, direct.delays);
  EXPECT_EQ(result.delay_scan->terminations, direct.terminations);
  EXPECT_EQ(result.estimate.input_delay_samples, 2);
  expect_same(result.estimate, direct.best);
  expect_same(result.delay_scan->best, direct.best);
}

TEST_F(Identify, RelocationStartsFromTheEstimateAtItsDelay) {
  IdentificationOptions options;
  options.delay_scan_samples = DelayRange{1, 3};
  options.relocate_modes = true;
  options.relocation.max_relocations = 1;
  const IdentificationResult result = identify(open, ModelStructure::modes(2), options);
  ASSERT_TRUE(result.mode_relocation.has_value());
  ASSERT_TRUE(result.delay_scan.has_value());

  RefinedIvOptions start;
  start.input_delay_samples = result.delay_scan->best.input_delay_samples;
  start.initial_model = result.delay_scan->best.model;
  const ModeRelocationResult direct =
      additive_srivc_relocated(open, truth.orders(), start, options.relocation);
  expect_same(result.estimate, direct.estimate);
  EXPECT_EQ(result.mode_relocation->message, direct.message);
  EXPECT_EQ(result.estimate.input_delay_samples, 2);
}

TEST_F(Identify, ReportsProgressOfTheScanAndTheRelocationWithoutChangingTheResult) {
  IdentificationOptions options;
  options.delay_scan_samples = DelayRange{1, 3};
  options.relocate_modes = true;
  options.relocation.max_relocations = 1;
  std::vector<std::pair<int, int>> scan;
  std::vector<std::pair<int, int>> trials;
  IdentificationProgress progress;
  progress.delay_scan = [&](int done, int total) { scan.emplace_back(done, total); };
  progress.relocation = [&](int done, int total) { trials.emplace_back(done, total); };
  const IdentificationResult reported = identify(open, ModelStructure::modes(2), options, progress);
  EXPECT_EQ(scan, (std::vector<std::pair<int, int>>{{1, 3}, {2, 3}, {3, 3}}));
  ASSERT_TRUE(reported.mode_relocation.has_value());
  ASSERT_EQ(trials.size(), reported.mode_relocation->trials.size());
  for (std::size_t k = 0; k < trials.size(); ++k) {
    EXPECT_EQ(trials[k].first, static_cast<int>(k) + 1);
    EXPECT_EQ(trials[k].second,
              options.relocation.max_relocations * options.relocation.trials_per_round);
  }
  expect_same(reported.estimate, identify(open, ModelStructure::modes(2), options).estimate);
}

void expect_refused(const SampledData& data, const ModelStructure& structure,
                    const IdentificationOptions& options, const std::string& fragment) {
  try {
    identify(data, structure, options);
    ADD_FAILURE() << "no exception; expected: " << fragment;
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr(fragment));
  }
}

TEST_F(Identify, RefusesBadStructuresAndOptionsNamingTheField) {
  const ModelStructure modes = ModelStructure::modes(2);
  ModelStructure two_unfactored = ModelStructure::unfactored(2, 0);
  two_unfactored.orders.push_back({2, 0, 0});
  expect_refused(open, two_unfactored, {},
                 "ModelStructure.orders has 2 entries; an unfactored structure has exactly one");
  expect_refused(open, ModelStructure::additive({}), {},
                 "ModelStructure.orders is empty; an additive structure has at least one");
  EXPECT_THROW(ModelStructure::modes(0), InvalidArgument);

  IdentificationOptions o;
  o.refined_iv.max_iterations = 0;
  expect_refused(open, modes, o,
                 "IdentificationOptions.refined_iv.max_iterations is 0; it must be >= 1");
  o = {};
  o.delay_scan_samples = DelayRange{5, 2};
  expect_refused(open, modes, o,
                 "IdentificationOptions.delay_scan_samples.max is 2; it must be >= min (5)");
  o.delay_scan_samples = DelayRange{-1, 2};
  expect_refused(open, modes, o,
                 "IdentificationOptions.delay_scan_samples.min is -1; it must be >= 0");
  o.delay_scan_samples = DelayRange{0, 2};
  o.refined_iv.input_delay_samples = 1;
  expect_refused(open, modes, o, "give a known delay or a scan, not both");

  o = {};
  o.relocate_modes = true;
  expect_refused(open, ModelStructure::unfactored(4, 2), o,
                 "relocate_modes is true but the structure is unfactored");
  o.controller = controller;
  expect_refused(closed, modes, o, "mode relocation is for open-loop data");
  o = {};
  o.relocation.peaks_per_round = 0;
  expect_refused(open, modes, o, "peaks_per_round is 0; it must be >= 1");
  // Data the estimator refuses: closed loop without a reference.
  o = {};
  o.controller = controller;
  EXPECT_THROW(identify(open, modes, o), InvalidArgument);
}

}  // namespace
}  // namespace ctid::identification_test
