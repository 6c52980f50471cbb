// The front doors of the estimator modules (decision 0044): identify(MimoData, ...),
// identify(MimoFrf, ...), identify_output_only, identify(data, DelayedFeedbackStructure, ...),
// validate_model(DelayedFeedbackLoop, ...) and validate_identification(ProcessStructure, ...)
// give what the estimator they front gives on the same input, bit for bit (options, start and
// progress reach it), and refuse bad input with the estimator's own message.
#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/identification/feedback_loop.h"
#include "ctid/identification/frf_matrix.h"
#include "ctid/identification/identification.h"
#include "ctid/identification/mimo.h"
#include "ctid/identification/output_only.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"
#include "oma/chain_model.h"
#include "support/de_iuliis_systems.h"
#include "support/mimo_systems.h"
#include "support/paper_systems.h"
#include "support/sanitizers.h"

namespace ctid::front_doors_test {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

constexpr double kH = testing::kPaperSampleTime;

MimoData beam_record(const MimoAdditiveModel& g, int samples) {
  Eigen::MatrixXd u(samples, g.inputs());
  for (int k = 0; k < g.inputs(); ++k) {
    u.col(k) = white_noise(samples, 1.0, 5 + 17 * static_cast<unsigned>(k));
  }
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(samples, g.outputs());
  for (int j = 0; j < g.outputs(); ++j) {
    for (int k = 0; k < g.inputs(); ++k) y.col(j) += simulate(g.channel(j, k), u.col(k), kH);
  }
  return MimoData(kH, u, y);
}

// Every coefficient of two models, exactly.
bool same_model(const MimoAdditiveModel& a, const MimoAdditiveModel& b) {
  if (a.size() != b.size() || a.inputs() != b.inputs() || a.outputs() != b.outputs()) return false;
  for (int i = 0; i < a.size(); ++i) {
    if (a[i].a.coefficients() != b[i].a.coefficients() || a[i].b.size() != b[i].b.size()) {
      return false;
    }
    for (std::size_t c = 0; c < a[i].b.size(); ++c) {
      if (a[i].b[c].coefficients() != b[i].b[c].coefficients()) return false;
    }
  }
  return true;
}

// The same double, NaN included (FDD estimates no damping ratio).
bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

// (done, total) of every progress call.
struct Calls {
  std::vector<std::pair<int, int>> seen;
  std::function<void(int, int)> callback() {
    return [this](int done, int total) { seen.emplace_back(done, total); };
  }
};

TEST(FrontDoors, SeveralChannelsAreMimoSrivcBitForBit) {
  const MimoAdditiveModel truth = testing::four_mode_beam(2, 3, 11);
  const MimoData data = beam_record(truth, 1500);
  const std::vector<SubmodelOrder> orders(4, {2, 0, 0});
  const MimoEstimationResult automatic = identify(data, orders);
  const MimoEstimationResult direct = mimo_srivc(data, orders);
  ASSERT_TRUE(automatic.model && direct.model) << direct.message;
  EXPECT_TRUE(direct.converged()) << direct.message;
  EXPECT_TRUE(same_model(*automatic.model, *direct.model));
  EXPECT_TRUE(automatic.fit_percent == direct.fit_percent);
  EXPECT_TRUE(automatic.covariance == direct.covariance);
  EXPECT_EQ(automatic.message, direct.message);

  // Options, start and progress reach the estimator: three iterations from the truth, white
  // noise, no covariance.
  MimoIdentificationOptions options;
  options.refined_iv.max_iterations = 3;
  options.refined_iv.noise = NoiseAssumption::white;
  options.refined_iv.compute_covariance = false;
  options.initial_model = truth;
  Calls front;
  Calls estimator;
  const MimoEstimationResult started = identify(data, orders, options, front.callback());
  const MimoEstimationResult expected =
      mimo_srivc(data, orders, options.refined_iv, truth, estimator.callback());
  ASSERT_TRUE(started.model && expected.model) << expected.message;
  EXPECT_TRUE(same_model(*started.model, *expected.model));
  EXPECT_EQ(started.iterations, expected.iterations);
  EXPECT_EQ(started.covariance.size(), 0);
  EXPECT_FALSE(front.seen.empty());
  EXPECT_EQ(front.seen, estimator.seen);
  EXPECT_EQ(front.seen.front().second, 3);
}

TEST(FrontDoors, SeveralChannelsRefuseAsMimoSrivcDoes) {
  const MimoData data = beam_record(testing::four_mode_beam(2, 3, 11), 300);
  EXPECT_THAT(
      [&] { identify(data, std::vector<SubmodelOrder>{}); },
      ThrowsMessage<InvalidArgument>(HasSubstr("mimo_srivc: the structure has no submodels")));
  MimoIdentificationOptions options;
  options.refined_iv.input_delays_samples = {1.0};  // one delay for two inputs
  EXPECT_THAT(
      [&] {
        identify(data, std::vector<SubmodelOrder>(2, {2, 0, 0}), options);
      },
      ThrowsMessage<InvalidArgument>(HasSubstr("input_delays_samples has 1")));
}

MimoFrf frf_of(const MimoAdditiveModel& g, int lines) {
  MimoFrf frf;
  frf.frequencies = Eigen::VectorXd::LinSpaced(lines, 0.05, 20.0);
  frf.response = mimo_frequency_response(g, frf.frequencies);
  for (int k = 0; k < g.inputs(); ++k) frf.input_names.push_back("u" + std::to_string(k + 1));
  for (int j = 0; j < g.outputs(); ++j) frf.output_names.push_back("y" + std::to_string(j + 1));
  return frf;
}

TEST(FrontDoors, AnFrfMatrixIsFrfMatrixFitBitForBit) {
  const MimoAdditiveModel truth = testing::four_mode_beam(2, 3, 11);
  const MimoFrf frf = frf_of(truth, 300);
  const std::vector<SubmodelOrder> orders(4, {2, 0, 0});
  Calls front;
  Calls estimator;
  const FrfMatrixFitResult fitted = identify(frf, orders, {}, front.callback());
  const FrfMatrixFitResult direct = frf_matrix_fit(frf, orders, {}, {}, estimator.callback());
  ASSERT_TRUE(fitted.model && direct.model) << direct.message;
  EXPECT_TRUE(direct.converged()) << direct.message;
  EXPECT_TRUE(same_model(*fitted.model, *direct.model));
  EXPECT_TRUE(fitted.fit_percent == direct.fit_percent);
  EXPECT_FALSE(front.seen.empty());
  EXPECT_EQ(front.seen, estimator.seen);

  // The band and the start reach the fit.
  FrfIdentificationOptions options;
  options.frf_fit.max_frequency = 10.0;
  options.frf_fit.max_iterations = 2;
  options.initial_model = truth;
  const FrfMatrixFitResult banded = identify(frf, orders, options);
  const FrfMatrixFitResult expected = frf_matrix_fit(frf, orders, options.frf_fit, truth);
  ASSERT_TRUE(banded.model && expected.model) << expected.message;
  EXPECT_TRUE(same_model(*banded.model, *expected.model));
  EXPECT_EQ(banded.iterations, expected.iterations);
  EXPECT_FALSE(same_model(*banded.model, *fitted.model) && banded.iterations == fitted.iterations);

  EXPECT_THAT(
      [&] {
        identify(frf, std::vector<SubmodelOrder>{{3, 0, 0}});
      },
      ThrowsMessage<InvalidArgument>(HasSubstr("frf_matrix_fit")));
}

TEST(FrontDoors, OutputOnlyIsOmaBitForBit) {
  const oma_test::ChainModel chain;
  const Eigen::MatrixXd y = chain.simulate(12000, 0.05, 11);
  const std::vector<std::string> names{"a", "b", "c", "d"};
  for (const OmaMethod method : {OmaMethod::ssi_cov, OmaMethod::fdd}) {
    SCOPED_TRACE(enum_name(method));
    OmaOptions options;
    options.method = method;
    options.max_order = 24;
    options.block_rows = 20;
    const OmaResult front = identify_output_only(y, chain.h, options, names);
    const OmaResult direct = oma(y, chain.h, options, names);
    EXPECT_EQ(front.method, method);
    EXPECT_EQ(front.channels, names);
    ASSERT_FALSE(direct.modes.empty()) << direct.verdict.summary();
    ASSERT_EQ(front.modes.size(), direct.modes.size());
    for (std::size_t i = 0; i < direct.modes.size(); ++i) {
      EXPECT_EQ(front.modes[i].frequency_hz, direct.modes[i].frequency_hz);
      EXPECT_TRUE(same(front.modes[i].damping_ratio, direct.modes[i].damping_ratio));
      EXPECT_TRUE(front.modes[i].shape_real == direct.modes[i].shape_real);
    }
    EXPECT_EQ(front.stabilisation.size(), direct.stabilisation.size());
  }
  EXPECT_THAT([&] { identify_output_only(y.leftCols(1), chain.h); },
              ThrowsMessage<InvalidArgument>(HasSubstr("outputs has 1")));
}

// One candidate (the approximate gcd) to keep the runs short; the pipeline tests cover the
// others.
FeedbackIdentificationOptions foh_feedback() {
  FeedbackIdentificationOptions o;
  o.output_error.hold = Hold::first_order_hold;
  o.separation = SeparationMethod::gcd;
  o.structured_candidate = false;
  o.iv_filter_poles.clear();
  return o;
}

TEST(FrontDoors, ADelayedFeedbackLoopIsIdentifyDelayedFeedbackBitForBit) {
  CTID_SKIP_UNDER_SANITIZERS(
      "FeedbackPipeline.NoiseFreeInformativeRecordRecoversFAndH runs the same identification");
  const DelayedFeedbackLoop loop = test_support::paper_feedback_loop();
  const SampledData data = test_support::feedback_record(loop, 15.0);
  const FeedbackIdentificationResult front =
      identify(data, DelayedFeedbackStructure{3, 3}, 0.5, foh_feedback());
  const FeedbackIdentificationResult direct =
      identify_delayed_feedback(data, 3, 3, 0.5, foh_feedback());
  ASSERT_TRUE(direct.best_candidate.has_value()) << direct.message;
  EXPECT_TRUE(loop_parameters(front.loop) == loop_parameters(direct.loop));
  EXPECT_EQ(front.output_rms, direct.output_rms);
  EXPECT_EQ(front.candidates.size(), direct.candidates.size());
  for (const SeparationCandidateReport& c : front.candidates) EXPECT_EQ(c.source, "gcd");

  // validate_model of a loop is validate_loop: the true loop fits the noise-free record.
  const ValidationReport report = validate_model(loop, data, Hold::first_order_hold);
  const ValidationReport expected = validate_loop(loop, data, Hold::first_order_hold);
  EXPECT_EQ(report.fit_percent, expected.fit_percent);
  EXPECT_GT(report.fit_percent, 99.999);

  EXPECT_THAT(
      [&] {
        identify(data, DelayedFeedbackStructure{0, 3}, 0.5);
      },
      ThrowsMessage<InvalidArgument>(HasSubstr("order")));
}

TEST(FrontDoors, AnUnknownFeedbackDelayIsTheDelayScanBitForBit) {
  CTID_SKIP_UNDER_SANITIZERS(
      "FeedbackPipeline.DelayScanFindsTheDelayFromAGridThatMissesIt runs the same scan");
  // A short record and a two-point grid: the scan's accuracy is the pipeline test's; here the
  // front door must give the scan's result and progress, whatever they are.
  const DelayedFeedbackLoop loop = test_support::paper_feedback_loop();
  const SampledData data = test_support::feedback_record(loop, 12.0);
  DelayIdentificationOptions options;
  options.identification = foh_feedback();
  options.scan.min_delay = 0.44;
  options.scan.max_delay = 0.52;
  options.scan.points = 2;
  options.scan.hold = Hold::first_order_hold;
  options.scan.regressors = options.identification.regressors;
  options.scan.criterion = DelayCriterion::equation_error;  // the cheapest
  options.joint_delay = false;
  options.golden_iterations = 2;
  Calls front_calls;
  Calls direct_calls;
  const DelayIdentificationResult front =
      identify(data, DelayedFeedbackStructure{3, 3}, options, front_calls.callback());
  const DelayIdentificationResult direct =
      identify_delayed_feedback_with_delay_scan(data, 3, 3, options, direct_calls.callback());
  EXPECT_EQ(front.delay, direct.delay);
  EXPECT_EQ(front.evaluations, direct.evaluations);
  EXPECT_EQ(front.identification.output_rms, direct.identification.output_rms);
  EXPECT_TRUE(loop_parameters(front.identification.loop) ==
              loop_parameters(direct.identification.loop));
  EXPECT_EQ(front_calls.seen.size(), 2U);
  EXPECT_EQ(front_calls.seen, direct_calls.seen);
}

TEST(FrontDoors, ProcessModelOptionsAreCheckedAsTheModuleChecksThem) {
  const ProcessStructure p1d = ProcessStructure::parse("P1D");
  ProcessModelOptions options;
  options.parameters.push_back(ProcessParameterSetting{"Tp2", 1.0, false, {}, {}});
  std::string expected;
  try {
    validate_process_model(p1d, options);
  } catch (const InvalidArgument& e) {
    expected = e.what();
  }
  ASSERT_THAT(expected, HasSubstr("Tp2"));
  EXPECT_THAT([&] { validate_identification(p1d, options); },
              ThrowsMessage<InvalidArgument>(expected));
  options.parameters.front().name = "Tp1";
  EXPECT_NO_THROW(validate_identification(p1d, options));
}

}  // namespace
}  // namespace ctid::front_doors_test
