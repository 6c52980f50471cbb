#include "ctid/core/preprocessing.h"

#include <cmath>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"

namespace ctid::preprocessing_test {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

SampledData ramp_record(int n, double h) {
  const Eigen::VectorXd k = Eigen::VectorXd::LinSpaced(n, 0.0, n - 1.0);
  Eigen::VectorXd u = (0.3 * k).array().sin() + 5.0;
  Eigen::VectorXd y = (0.2 * k).array().cos() + 2.0 + 0.5 * h * k.array();
  return SampledData(h, std::move(u), std::move(y), std::nullopt, 1.0);
}

TEST(Preprocessing, NothingAskedKeepsTheRecordAndWarnsAboutLargeMeans) {
  const SampledData data = ramp_record(200, 0.1);
  const PreprocessedData p = preprocess(data);
  EXPECT_EQ(p.data.input(), data.input());
  EXPECT_EQ(p.data.output(), data.output());
  EXPECT_EQ(p.record.first_row, 0);
  EXPECT_EQ(p.record.end_row, 200);
  ASSERT_EQ(p.record.warnings.size(), 2u);
  EXPECT_THAT(p.record.warnings[0], HasSubstr("input mean 5"));
  EXPECT_THAT(p.record.warnings[0], HasSubstr("consider removing it (detrend mean)"));
}

TEST(Preprocessing, AConstantSignalGetsNoAdviceToRemoveItsMean) {
  // Removing the mean of a constant input leaves zeros; whatever needs the input to vary
  // refuses it with its own error, so the warning would only come first and mislead.
  const SampledData ramp = ramp_record(200, 0.1);
  const SampledData data(0.1, Eigen::VectorXd::Constant(200, 3.0), ramp.output());
  const PreprocessedData p = preprocess(data);
  ASSERT_EQ(p.record.warnings.size(), 1u);
  EXPECT_THAT(p.record.warnings[0], HasSubstr("output mean"));
}

TEST(Preprocessing, MeanAndLinearTrendsAreRemovedAndRecorded) {
  const SampledData data = ramp_record(400, 0.1);
  PreprocessingOptions options;
  options.detrend = Detrend::mean;
  const PreprocessedData m = preprocess(data, options);
  EXPECT_NEAR(m.data.input().mean(), 0.0, 1e-14);
  EXPECT_NEAR(m.data.output().mean(), 0.0, 1e-14);
  EXPECT_DOUBLE_EQ(m.record.input_offset, data.input().mean());
  EXPECT_TRUE(m.record.warnings.empty());

  // A pure line is removed exactly, and its coefficients are recovered.
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(50, 0.0, 49.0) * 0.2;
  Eigen::VectorXd line = (3.0 - 0.7 * t.array()).matrix();
  const SampledData straight(0.2, line, line);
  options.detrend = Detrend::linear;
  const PreprocessedData l = preprocess(straight, options);
  EXPECT_LT(l.data.output().cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_NEAR(l.record.output_offset, 3.0, 1e-13);
  EXPECT_NEAR(l.record.output_slope, -0.7, 1e-13);
  EXPECT_THAT(l.record.summary(), HasSubstr("lines removed (u 3 + -0.7 t"));
}

TEST(Preprocessing, AFitsTrendTravelsToAnotherRecord) {
  // On the estimation record itself, removing the recorded trend is preprocess's detrending
  // bit for bit; on another record it removes the same line from that record's first sample,
  // not the record's own (MATLAB's detrend(zv, T)), and add_output_trend puts it back.
  const SampledData data = ramp_record(400, 0.1);
  for (const Detrend detrend : {Detrend::mean, Detrend::linear}) {
    PreprocessingOptions options;
    options.detrend = detrend;
    const PreprocessedData fitted = preprocess(data, options);
    const SampledData same = remove_trend(data, fitted.record);
    EXPECT_EQ(same.input(), fitted.data.input());
    EXPECT_EQ(same.output(), fitted.data.output());

    const SampledData other = ramp_record(250, 0.1);
    const SampledData moved(0.1, other.input().array() + 0.25, other.output().array() - 1.5,
                            std::nullopt, 7.0);
    const SampledData removed = remove_trend(moved, fitted.record);
    EXPECT_EQ(removed.size(), 250);
    EXPECT_EQ(removed.start_time(), 7.0);
    for (const int k : {0, 17, 249}) {
      const double t = 0.1 * k;
      EXPECT_NEAR(removed.input()(k),
                  moved.input()(k) - fitted.record.input_offset - fitted.record.input_slope * t,
                  1e-13);
      EXPECT_NEAR(removed.output()(k),
                  moved.output()(k) - fitted.record.output_offset - fitted.record.output_slope * t,
                  1e-13);
    }
    // The moved record's own mean is not what was removed: its offset of +0.25 stays.
    if (detrend == Detrend::mean) {
      EXPECT_NEAR(removed.input().mean() - (other.input().mean() - data.input().mean()), 0.25,
                  1e-12);
    }
    const Eigen::VectorXd back = add_output_trend(removed.output(), 0.1, fitted.record);
    EXPECT_LT((back - moved.output()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(Preprocessing, RowAndTimeRangesKeepTheRightSamples) {
  const SampledData data = ramp_record(100, 0.5);  // t = 1 + 0.5 k
  PreprocessingOptions rows;
  rows.first_row = 10;
  rows.end_row = 30;
  const PreprocessedData r = preprocess(data, rows);
  EXPECT_EQ(r.data.size(), 20);
  EXPECT_EQ(r.data.input()(0), data.input()(10));
  EXPECT_DOUBLE_EQ(r.data.start_time(), 6.0);
  PreprocessingOptions times;
  times.start_time = 6.0;
  times.end_time = 16.0;
  const PreprocessedData t = preprocess(data, times);
  EXPECT_EQ(t.record.first_row, 10);
  EXPECT_EQ(t.record.end_row, 30);
  EXPECT_EQ(t.data.output(), r.data.output());
}

TEST(Preprocessing, DecimationKeepsTheBandAndRemovesWhatWouldAlias) {
  const int n = 4000;
  const int factor = 5;
  const double h = 0.01;
  const Eigen::VectorXd k = Eigen::VectorXd::LinSpaced(n, 0.0, n - 1.0);
  // New Nyquist frequency: 0.5 / (5 h) = 10 Hz. 7.5 Hz must pass; 11 Hz and 30 Hz must not.
  const double pass = 7.5;
  Eigen::VectorXd low = (2.0 * std::numbers::pi * pass * h * k).array().sin();
  Eigen::VectorXd high = (2.0 * std::numbers::pi * 11.0 * h * k).array().sin() +
                         (2.0 * std::numbers::pi * 30.0 * h * k).array().sin();
  const SampledData data(h, low, high);
  PreprocessingOptions options;
  options.decimate = factor;
  const PreprocessedData d = preprocess(data, options);
  EXPECT_EQ(d.data.size(), n / factor);
  EXPECT_DOUBLE_EQ(d.data.sample_time(), factor * h);
  const Eigen::Index inner = 100;  // away from the reflected ends
  const Eigen::Index m = d.data.size() - 2 * inner;
  const Eigen::VectorXd kept = d.data.input().segment(inner, m);
  const Eigen::VectorXd expected = low(Eigen::seqN(inner * factor, m, factor));
  EXPECT_LT((kept - expected).cwiseAbs().maxCoeff(), 3e-3);
  EXPECT_LT(d.data.output().segment(inner, m).cwiseAbs().maxCoeff(), 3e-3);
  EXPECT_THAT(d.record.warnings.back(), HasSubstr("no longer held"));
}

TEST(Preprocessing, ScalingAppliesToInputAndOutput) {
  const SampledData data = ramp_record(20, 0.1);
  PreprocessingOptions options;
  options.input_scale = 2.0;
  options.output_scale = 0.5;
  const PreprocessedData s = preprocess(data, options);
  EXPECT_EQ(s.data.input(), Eigen::VectorXd(2.0 * data.input()));
  EXPECT_EQ(s.data.output(), Eigen::VectorXd(0.5 * data.output()));
}

TEST(Preprocessing, BadRangesAndFactorsAreOneClearError) {
  const SampledData data = ramp_record(100, 0.1);
  const auto error = [&](const PreprocessingOptions& o) {
    return [&data, o] { preprocess(data, o); };
  };
  PreprocessingOptions one;
  one.first_row = 5;
  one.end_row = 6;
  one.detrend = Detrend::mean;
  EXPECT_THAT(error(one), ThrowsMessage<InvalidArgument>(
                              HasSubstr("rows 5:6 keeps 1 sample; detrend mean needs at least 2")));
  PreprocessingOptions outside;
  outside.first_row = 90;
  outside.end_row = 120;
  EXPECT_THAT(error(outside), ThrowsMessage<InvalidArgument>(
                                  HasSubstr("rows 90:120 lie outside the record's 100 rows")));
  PreprocessingOptions empty;
  empty.first_row = 50;
  empty.end_row = 50;
  EXPECT_THAT(error(empty), ThrowsMessage<InvalidArgument>(HasSubstr("the row range is empty")));
  PreprocessingOptions late;
  late.start_time = 20.0;
  EXPECT_THAT(error(late),
              ThrowsMessage<InvalidArgument>(HasSubstr("time 20:11 s keeps no sample")));
  PreprocessingOptions zero;
  zero.decimate = 0;
  EXPECT_THAT(error(zero), ThrowsMessage<InvalidArgument>(
                               HasSubstr("PreprocessingOptions.decimate is 0; it must be >= 1")));
  PreprocessingOptions many;
  many.decimate = 100;
  EXPECT_THAT(error(many),
              ThrowsMessage<InvalidArgument>(HasSubstr("decimate 100 leaves 1 sample")));
}

}  // namespace
}  // namespace ctid::preprocessing_test
