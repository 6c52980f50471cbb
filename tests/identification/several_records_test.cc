// Several records in one estimate (identify on a list of SampledData): pieces of one noise-free
// run that start mid-motion give the exact model with an initial state per record; one record
// gives exactly the single-record estimate; with noise, a second record of the same length
// shrinks the standard errors by about 1/sqrt(2); records that do not go together are refused.
#include <cmath>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/identification/identification.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"
#include "support/paper_systems.h"

namespace ctid::several_records_test {
namespace {

using ::testing::HasSubstr;

constexpr double kH = testing::kPaperSampleTime;

// Samples [from, from + count) of a record.
SampledData piece(const SampledData& whole, int from, int count) {
  return SampledData(kH, whole.input().segment(from, count), whole.output().segment(from, count));
}

double relative_error(const Eigen::VectorXd& estimate, const Eigen::VectorXd& truth) {
  return (estimate - truth).norm() / truth.norm();
}

TEST(SeveralRecords, PiecesStartingMidMotionGiveTheExactModel) {
  // Section 6.2's two modes, one long noise-free run cut into three pieces of different
  // lengths, none of which starts at rest.
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const Eigen::VectorXd u = white_noise(5000, 1.0, 21);
  const SampledData run(kH, u, simulate(truth, u, kH));
  const std::vector<SampledData> records{piece(run, 400, 900), piece(run, 1700, 1500),
                                         piece(run, 3600, 700)};
  IdentificationOptions options;
  options.refined_iv.initial_conditions = InitialConditions::estimate;
  options.refined_iv.initial_model =
      AdditiveModel::from_parameters(truth.orders(), truth.parameters() * 1.05, 0.0);
  const EstimationResult e =
      identify(records, ModelStructure::additive(truth.orders()), options).estimate;
  ASSERT_TRUE(e.converged()) << e.message;
  EXPECT_TRUE(e.verdict.usable) << e.verdict.summary();
  EXPECT_LT(relative_error(e.parameters, truth.parameters()), 1e-9);
  EXPECT_EQ(e.initial_conditions.size(), 3 * 4);  // 4 states per record
  EXPECT_GT(e.fit_percent, 100.0 - 1e-6);
  // Each piece alone also gives the model (the pieces differ), so the joint fit is not one
  // record's: with `zero` the pieces are biased.
  options.refined_iv.initial_conditions = InitialConditions::zero;
  const EstimationResult at_rest =
      identify(records, ModelStructure::additive(truth.orders()), options).estimate;
  EXPECT_GT(relative_error(at_rest.parameters, truth.parameters()), 1e-4);
}

TEST(SeveralRecords, OneRecordIsTheSingleRecordEstimateBitForBit) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const Eigen::VectorXd u = white_noise(1200, 1.0, 22);
  const SampledData data(kH, u, simulate(truth, u, kH) + white_noise(1200, 0.1, 23));
  IdentificationOptions options;
  options.refined_iv.initial_conditions = InitialConditions::estimate;
  const EstimationResult one = identify(data, ModelStructure::modes(2), options).estimate;
  const EstimationResult list =
      identify(std::vector<SampledData>{data}, ModelStructure::modes(2), options).estimate;
  EXPECT_EQ(one.parameters, list.parameters);
  EXPECT_EQ(one.covariance, list.covariance);
  EXPECT_EQ(one.message, list.message);
}

TEST(SeveralRecords, ClosedLoopRecordsFromRestGiveTheExactModel) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const DiscreteTransferFunction pid = testing::closed_loop_pid();
  std::vector<SampledData> records;
  for (int k = 0; k < 2; ++k) {
    const Eigen::VectorXd r = white_noise(800 + 300 * k, 1.0, 30 + k);
    const ClosedLoopSimulation loop = simulate_closed_loop(truth, pid, r);
    records.emplace_back(kH, loop.input, loop.output, r);
  }
  IdentificationOptions options;
  options.controller = pid;
  options.refined_iv.initial_model =
      AdditiveModel::from_parameters(truth.orders(), truth.parameters() * 1.03, 0.0);
  const IdentificationResult result =
      identify(records, ModelStructure::additive(truth.orders()), options);
  EXPECT_EQ(result.estimator, RefinedIvEstimator::additive_clsrivc);
  ASSERT_TRUE(result.estimate.converged()) << result.estimate.message;
  EXPECT_LT(relative_error(result.estimate.parameters, truth.parameters()), 1e-9);
}

TEST(SeveralRecords, ASecondRecordShrinksTheStandardErrors) {
  // Two independent experiments of the same length and noise level: the reported standard
  // errors of the joint estimate are about 1/sqrt(2) of either one's, and the joint estimate
  // is closer to the truth on average over seeds.
  const AdditiveModel truth = testing::closed_loop_two_modes();
  double ratio_sum = 0.0;
  const int seeds = 5;
  for (int seed = 0; seed < seeds; ++seed) {
    std::vector<SampledData> records;
    for (int k = 0; k < 2; ++k) {
      const Eigen::VectorXd u = white_noise(1500, 1.0, 100 + 10 * seed + k);
      const Eigen::VectorXd y =
          simulate(truth, u, kH) + white_noise(1500, 0.2, 500 + 10 * seed + k);
      records.emplace_back(kH, u, y);
    }
    IdentificationOptions options;
    options.refined_iv.noise = NoiseAssumption::white;
    const EstimationResult first = identify(records[0], ModelStructure::modes(2), options).estimate;
    const EstimationResult both = identify(records, ModelStructure::modes(2), options).estimate;
    ASSERT_TRUE(both.converged()) << both.message;
    ratio_sum += (both.standard_errors.array() / first.standard_errors.array()).mean();
  }
  EXPECT_NEAR(ratio_sum / seeds, 1.0 / std::sqrt(2.0), 0.1);
}

TEST(SeveralRecords, EachRecordMayLagItsInputByItsOwnWholeSamples) {
  // The second experiment's output lags its input by 3 more samples than the first's (its
  // acquisition started late): with record_delay_samples {0, 3} the model is exact.
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const Eigen::VectorXd ua = white_noise(900, 1.0, 50);
  const Eigen::VectorXd ub = white_noise(1100, 1.0, 51);
  const std::vector<SampledData> records{
      SampledData(kH, ua, simulate(truth, ua, kH)),
      SampledData(kH, ub, simulate(truth.with_input_delay(3 * kH), ub, kH))};
  IdentificationOptions options;
  options.refined_iv.initial_model =
      AdditiveModel::from_parameters(truth.orders(), truth.parameters() * 1.03, 0.0);
  options.refined_iv.record_delay_samples = {0, 3};
  const EstimationResult e =
      identify(records, ModelStructure::additive(truth.orders()), options).estimate;
  ASSERT_TRUE(e.converged()) << e.message;
  EXPECT_LT(relative_error(e.parameters, truth.parameters()), 1e-9);
  EXPECT_EQ(e.model.input_delay(), 0.0);
  options.refined_iv.record_delay_samples.clear();
  const EstimationResult ignored =
      identify(records, ModelStructure::additive(truth.orders()), options).estimate;
  EXPECT_GT(relative_error(ignored.parameters, truth.parameters()), 1e-3);
  options.refined_iv.record_delay_samples = {1};
  try {
    identify(records, ModelStructure::additive(truth.orders()), options);
    ADD_FAILURE() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("record_delay_samples has 1 entries for 2 records"));
  }
}

TEST(SeveralRecords, RefusesRecordsThatDoNotGoTogether) {
  const Eigen::VectorXd u = white_noise(600, 1.0, 40);
  const Eigen::VectorXd y = simulate(testing::closed_loop_two_modes(), u, kH);
  const SampledData a(kH, u, y);
  auto refused = [&](const std::vector<SampledData>& records, const IdentificationOptions& o,
                     const std::string& fragment) {
    try {
      identify(records, ModelStructure::modes(2), o);
      ADD_FAILURE() << "no exception for " << fragment;
    } catch (const InvalidArgument& error) {
      EXPECT_THAT(error.what(), HasSubstr(fragment));
    }
  };
  IdentificationOptions o;
  refused({a, SampledData(0.0625, u, y)}, o, "record 2 is sampled every 0.0625 s");
  refused({}, o, "no data record was given");
  refused({a, a.with_input_hold(Hold::first_order_hold)}, o, "share their input hold");
  o.relocate_modes = true;
  refused({a, a}, o, "mode relocation works on one record");
  o.relocate_modes = false;
  o.controller = testing::closed_loop_pid();
  refused({SampledData(kH, u, y, u), a}, o, "record 2 has no reference");
}

}  // namespace
}  // namespace ctid::several_records_test
