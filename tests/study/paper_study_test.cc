// The Section 6 studies: the set-up matches the paper (PID, noise filter, true parameters),
// the comparison by partial fractions, replay and parallel = serial on a tiny study, the MSE
// table from hand-made records, and a small Monte Carlo whose MSE agrees with the predicted
// asymptotic covariance.
#include "ctid/study/paper_study.h"

#include <cmath>
#include <complex>
#include <cstring>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/study/monte_carlo.h"
#include "ctid/study/study_output.h"
#include "support/paper_systems.h"

namespace ctid::paper_study_test {
namespace {

// Bitwise equality, so NaN == NaN and -0 != +0: parallel must equal serial exactly.
bool same_bits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

void expect_same_record(const StudyRecord& a, const StudyRecord& b) {
  EXPECT_EQ(a.size_index, b.size_index);
  EXPECT_EQ(a.run_index, b.run_index);
  EXPECT_EQ(a.samples, b.samples);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.estimator, b.estimator);
  EXPECT_EQ(a.termination, b.termination);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.message, b.message);
  EXPECT_EQ(a.valid, b.valid);
  EXPECT_TRUE(same_bits(a.estimate, b.estimate));
  EXPECT_TRUE(same_bits(a.standard_error, b.standard_error));
  EXPECT_EQ(a.error, b.error);
}

StudyOptions tiny(StudyKind kind) {
  StudyOptions options = StudyOptions::paper(kind);
  options.runs = 3;
  options.sizes = 2;
  options.min_samples = 400;
  options.max_samples = 700;
  options.max_iterations = 30;
  return options;
}

// The library's systems and the tests' fixtures are two copies of the paper: bit for bit equal.
void expect_same_model(const AdditiveModel& a, const AdditiveModel& b) {
  ASSERT_EQ(a.size(), b.size());
  for (int i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].a, b[i].a) << "submodel " << i;
    EXPECT_EQ(a[i].b, b[i].b) << "submodel " << i;
    EXPECT_EQ(a[i].integrators, b[i].integrators) << "submodel " << i;
  }
  EXPECT_EQ(a.input_delay(), b.input_delay());
}

void expect_same_filter(const DiscreteTransferFunction& a, const DiscreteTransferFunction& b) {
  EXPECT_EQ(a.numerator(), b.numerator());
  EXPECT_EQ(a.denominator(), b.denominator());
  EXPECT_EQ(a.sample_time(), b.sample_time());
}

TEST(StudySetup, SystemsAreTheTestFixturesBitForBit) {
  const StudySetup open = study_setup(StudyKind::open_loop);
  expect_same_model(open.system, testing::open_loop_four_modes());
  ASSERT_TRUE(open.noise_filter.has_value());
  expect_same_filter(*open.noise_filter, testing::open_loop_noise_filter());
  EXPECT_EQ(open.sample_time, testing::kPaperSampleTime);
  const StudySetup closed = study_setup(StudyKind::closed_loop);
  expect_same_model(closed.system, testing::closed_loop_two_modes());
  ASSERT_TRUE(closed.controller.has_value());
  expect_same_filter(*closed.controller, testing::closed_loop_pid());
  EXPECT_EQ(closed.sample_time, testing::kPaperSampleTime);
}

TEST(StudySetup, ClosedLoopControllerIsThePapersPid) {
  const StudySetup setup = study_setup(StudyKind::closed_loop);
  ASSERT_TRUE(setup.controller.has_value());
  for (std::complex<double> z : {std::complex<double>(0.3, 0.8), std::complex<double>(-2.0, 0.1)}) {
    const std::complex<double> pid = 0.0115 + 0.00725 * z / (z - 1.0) + 0.00454 * (z - 1.0) / z;
    EXPECT_NEAR(std::abs((*setup.controller)(z)-pid), 0.0, 1e-15);
  }
  EXPECT_TRUE(setup.controller->is_biproper());
  EXPECT_DOUBLE_EQ(setup.sample_time, 0.05);
  EXPECT_THAT(setup.parameter_names,
              ::testing::ElementsAre("a11", "a12", "b10", "a21", "a22", "b20"));
}

TEST(StudySetup, OpenLoopSystemHasThePapersPolesAndGains) {
  const StudySetup setup = study_setup(StudyKind::open_loop);
  ASSERT_TRUE(setup.noise_filter.has_value());
  const std::complex<double> z(0.2, 0.7);
  EXPECT_NEAR(std::abs((*setup.noise_filter)(z) - (z + 0.5) / (z - 0.85)), 0.0, 1e-15);
  EXPECT_NEAR(setup.system.to_transfer_function().dc_gain(), 3.0 + 0.4 + 0.2 + 0.05, 1e-12);
  const Eigen::VectorXcd poles = setup.system[1].to_transfer_function().poles();
  EXPECT_NEAR(std::abs(poles[0] - std::conj(poles[1])), 0.0, 1e-12);
  EXPECT_NEAR(poles[0].real(), -0.15, 1e-12);
  EXPECT_NEAR(std::abs(poles[0].imag()), 3.16, 1e-12);
}

TEST(ComparedParameters, RecoversTheTruthFromTheUnfactoredModel) {
  for (StudyKind kind : {StudyKind::open_loop, StudyKind::closed_loop}) {
    const StudySetup setup = study_setup(kind);
    const Eigen::VectorXd direct = compared_parameters(kind, setup.system);
    EXPECT_TRUE(direct.isApprox(setup.true_parameters, 1e-14));
    // The unfactored model (one submodel) is split by partial fractions first.
    const TransferFunction g = setup.system.to_transfer_function();
    const Polynomial a = g.denominator().anti_monic();
    const Polynomial b = (1.0 / g.denominator()[0]) * g.numerator();
    const AdditiveModel unfactored({Submodel{a, b, 0}});
    const Eigen::VectorXd split = compared_parameters(kind, unfactored);
    ASSERT_EQ(split.size(), setup.true_parameters.size());
    EXPECT_LT((split - setup.true_parameters).cwiseAbs().maxCoeff(), 1e-9);
  }
}

TEST(ComparedParameters, AModelThatDoesNotSplitGivesNoneInsteadOfThrowing) {
  // (p^2 + 2 p + 1)^4: a repeated pole pair, no partial-fraction split into four modes.
  const Polynomial double_pole{1.0, 2.0, 1.0};
  const Polynomial a = double_pole * double_pole * double_pole * double_pole;
  const AdditiveModel repeated({Submodel{a, Polynomial{1.0, 0.5}, 0}});
  for (StudyKind kind : {StudyKind::open_loop, StudyKind::closed_loop}) {
    EXPECT_EQ(compared_parameters(kind, repeated).size(), 0);
  }
}

TEST(SimulateStudyRun, StartsWithinThePerturbationAndIsReplayable) {
  StudyOptions options = StudyOptions::paper(StudyKind::closed_loop);
  const StudySetup setup = study_setup(options.kind);
  const StudyRunInput a = simulate_study_run(options, 300, 42);
  const StudyRunInput b = simulate_study_run(options, 300, 42);
  EXPECT_TRUE(same_bits(a.data.output(), b.data.output()));
  EXPECT_TRUE(same_bits(a.initial_model.parameters(), b.initial_model.parameters()));
  ASSERT_TRUE(a.data.has_reference());
  const Eigen::VectorXd relative =
      a.initial_model.parameters().cwiseQuotient(setup.system.parameters()).array() - 1.0;
  EXPECT_LE(relative.cwiseAbs().maxCoeff(), 0.05);
  EXPECT_GT(relative.cwiseAbs().maxCoeff(), 0.0);
  options.initial_perturbation = 0.0;
  EXPECT_TRUE(same_bits(simulate_study_run(options, 300, 42).initial_model.parameters(),
                        setup.system.parameters()));
  EXPECT_FALSE(same_bits(simulate_study_run(options, 300, 43).data.output(), a.data.output()));
}

TEST(StudyOptions, ValidateNamesTheField) {
  StudyOptions options;
  options.runs = 0;
  EXPECT_THAT([&] { options.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(
                                               ::testing::HasSubstr("StudyOptions.runs is 0")));
  options = StudyOptions::paper(StudyKind::open_loop);
  options.estimators = {StudyEstimator::clsrivc};
  EXPECT_THAT([&] { options.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr(
                  "StudyOptions.estimators[0] is clsrivc; it must be srivc or additive_srivc")));
  options.estimators.clear();
  options.max_samples = options.min_samples - 1;
  EXPECT_THAT([&] { options.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr(
                  "StudyOptions.max_samples is 1999; it must be >= min_samples (2000)")));
  EXPECT_EQ(StudyOptions::paper(StudyKind::closed_loop).sizes, 50);
  EXPECT_EQ(StudyOptions::paper(StudyKind::closed_loop).max_samples, 123036);
  EXPECT_DOUBLE_EQ(StudyOptions::paper(StudyKind::closed_loop).tolerance, 1e-7);
}

TEST(RunStudy, ParallelEqualsSerialAndEachRunReplaysAlone) {
  for (StudyKind kind : {StudyKind::open_loop, StudyKind::closed_loop}) {
    StudyOptions options = tiny(kind);
    options.threads = 1;
    const StudyResult serial = run_study(options);
    options.threads = 3;
    const StudyResult parallel = run_study(options);
    const size_t estimators = options.active_estimators().size();
    ASSERT_EQ(serial.records.size(), 6u * estimators);
    ASSERT_EQ(parallel.records.size(), serial.records.size());
    for (size_t i = 0; i < serial.records.size(); ++i) {
      expect_same_record(serial.records[i], parallel.records[i]);
      EXPECT_TRUE(serial.records[i].error.empty()) << serial.records[i].error;
    }
    // Replay run 1 at size 1 alone.
    const std::vector<StudyRecord> replay = run_study_case(options, 1, 1);
    ASSERT_EQ(replay.size(), estimators);
    const size_t first = (1 * 3 + 1) * estimators;
    for (size_t e = 0; e < estimators; ++e) {
      expect_same_record(replay[e], serial.records[first + e]);
    }
    std::ostringstream a, b;
    write_mse_csv(serial, a);
    write_mse_csv(parallel, b);
    EXPECT_EQ(a.str(), b.str());
  }
}

TEST(SummarizeStudy, ComputesMsePerEstimatorSizeAndParameter) {
  const Eigen::Vector2d truth(1.0, 10.0);
  std::vector<StudyRecord> records;
  auto add = [&](StudyEstimator e, int j, double x0, double x1, double se, bool valid) {
    StudyRecord r;
    r.estimator = e;
    r.size_index = j;
    r.valid = valid;
    r.termination = Termination::converged;
    r.estimate = Eigen::Vector2d(x0, x1);
    r.standard_error = Eigen::Vector2d(se, 2.0 * se);
    records.push_back(r);
  };
  add(StudyEstimator::srivc, 0, 1.1, 9.0, 0.1, true);
  add(StudyEstimator::srivc, 0, 0.7, 10.0, 0.3, true);
  add(StudyEstimator::srivc, 0, 50.0, 50.0, 0.3, false);  // invalid: ignored
  add(StudyEstimator::additive_srivc, 0, 1.0, 10.5, 0.2, true);
  const auto rows = summarize_study(records, {100},
                                    {StudyEstimator::srivc, StudyEstimator::additive_srivc}, truth);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].samples, 100);
  EXPECT_EQ(rows[0].valid_runs, 2);
  EXPECT_EQ(rows[0].converged_runs, 3);
  EXPECT_DOUBLE_EQ(rows[0].mean_squared_error, (0.01 + 0.09) / 2.0);
  EXPECT_DOUBLE_EQ(rows[0].bias, (0.1 - 0.3) / 2.0);
  EXPECT_DOUBLE_EQ(rows[0].predicted_mean_squared_error, (0.01 + 0.09) / 2.0);
  EXPECT_DOUBLE_EQ(rows[1].mean_squared_error, 1.0 / 2.0);
  EXPECT_DOUBLE_EQ(rows[1].predicted_mean_squared_error, (0.04 + 0.36) / 2.0);
  EXPECT_EQ(rows[2].estimator, StudyEstimator::additive_srivc);
  EXPECT_DOUBLE_EQ(rows[3].mean_squared_error, 0.25);
}

// Statistical sanity: 40 runs at N = 2000 of the additive open-loop estimator. The MSE of
// 40 runs is within about +-sqrt(2/40) = 22 % of its expectation, and the asymptotic
// covariance predicts that expectation once the bias is negligible: the ratio must lie
// within a factor 2.2 either way (over 3.5 standard deviations on the log scale).
TEST(RunStudy, SmallOpenLoopMseAgreesWithThePredictedCovariance) {
  StudyOptions options = StudyOptions::paper(StudyKind::open_loop);
  options.estimators = {StudyEstimator::additive_srivc};
  options.runs = 40;
  options.sizes = 1;
  options.max_samples = options.min_samples;
  const StudyResult result = run_study(options);
  ASSERT_EQ(result.mse.size(), 4u);
  for (const MseRow& row : result.mse) {
    SCOPED_TRACE(result.parameter_names[static_cast<size_t>(row.parameter)]);
    EXPECT_EQ(row.valid_runs, 40);
    // Tolerance 1e-10 at N = 2000 leaves an occasional run at the iteration limit.
    EXPECT_GE(row.converged_runs, 36);
    const double ratio = row.mean_squared_error / row.predicted_mean_squared_error;
    EXPECT_GT(ratio, 1.0 / 2.2);
    EXPECT_LT(ratio, 2.2);
    // No significant bias: |mean error| below 3.5 standard errors of the mean.
    EXPECT_LT(std::abs(row.bias), 3.5 * std::sqrt(row.mean_squared_error / 40.0));
  }
}

}  // namespace
}  // namespace ctid::paper_study_test
