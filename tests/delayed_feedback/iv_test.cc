// The bias-corrected instrumental-variable iterations of the structured step 1
// (estimate_structured_step1_iv) on the noise-free informative record of
// feedback_pipeline_test.cc: the structured equation error alone is biased by the linear
// interpolation of y inside the regressors; the correction removes that bias.
#include <cmath>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/delayed_feedback/identification.h"
#include "support/de_iuliis_systems.h"

namespace ctid::iv_test {
namespace {

DelayedFeedbackLoop paper_loop() { return test_support::paper_feedback_loop(); }

SampledData clean_record() { return test_support::feedback_record(paper_loop()); }

FeedbackRegressorOptions regressors() {
  return {RegressorFilter::linear_integral_filter, 1.0, true, -1};
}

TEST(FeedbackIv, BiasCorrectionConvergesToTheTruthNoiseFree) {
  const SampledData data = clean_record();
  const StructuredStep1Result st =
      estimate_structured_step1(build_feedback_regression(data, 3, 3, 0.5, regressors()));
  const double start_rms = loop_output_rms(data, st.loop, Hold::first_order_hold, 4);
  EXPECT_GT(start_rms, 1e-3);  // the interpolation bias of the plain structured fit
  const StructuredIvResult iv = estimate_structured_step1_iv(data, st.loop, regressors());
  EXPECT_LT(iv.output_rms, 1e-6) << iv.message;
  EXPECT_LT((loop_parameters(iv.loop) - loop_parameters(paper_loop())).cwiseAbs().maxCoeff(), 1e-4);
  ASSERT_GE(iv.output_rms_history.size(), 2u);
  EXPECT_DOUBLE_EQ(iv.output_rms_history.front(), start_rms);
  EXPECT_DOUBLE_EQ(iv.loop.delay, 0.5);
  // Without the correction the instruments alone keep the bias: noise-free data carry none
  // for them to remove.
  StructuredIvOptions plain;
  plain.bias_correction = false;
  const StructuredIvResult uncorrected =
      estimate_structured_step1_iv(data, st.loop, regressors(), plain);
  EXPECT_GT(uncorrected.output_rms, 1e-3);
}

TEST(FeedbackIv, BadInputIsNamed) {
  StructuredIvOptions o;
  o.iterations = 0;
  EXPECT_THAT([&] { o.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("iterations")));
  FeedbackIdentificationOptions f;
  f.iv_filter_poles = {-1.0};
  EXPECT_THAT([&] { f.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("iv_filter_poles")));
  f.iv_filter_poles = {1.0};
  f.continuation_fractions = {1.5};
  EXPECT_THAT([&] { f.validate(); }, ::testing::ThrowsMessage<InvalidArgument>(
                                         ::testing::HasSubstr("continuation_fractions")));
  f.continuation_fractions = {};
  f.extra_finalists = -1;
  EXPECT_THAT([&] { f.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("extra_finalists")));
  f.extra_finalists = 2;
  f.finalist_ratio = 0.5;
  EXPECT_THAT([&] { f.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("finalist_ratio")));
  const SampledData tiny(0.05, Eigen::VectorXd::Ones(12), Eigen::VectorXd::Ones(12));
  EXPECT_THROW(estimate_structured_step1_iv(tiny, paper_loop(), regressors()), InvalidArgument);
}

}  // namespace
}  // namespace ctid::iv_test
