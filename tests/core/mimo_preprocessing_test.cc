#include "ctid/core/mimo_preprocessing.h"

#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"

namespace ctid::mimo_preprocessing_test {
namespace {

using ::testing::HasSubstr;

// Two inputs, three outputs, each channel its own offset and slope.
MimoData record() {
  const int n = 400;
  Eigen::MatrixXd u(n, 2);
  Eigen::MatrixXd y(n, 3);
  for (int k = 0; k < n; ++k) {
    const double t = 0.1 * k;
    u.row(k) << std::sin(0.7 * t) + 3.0, std::cos(1.3 * t) - 0.02 * t;
    y.row(k) << std::sin(0.5 * t) + 10.0, 0.3 * t + std::sin(2.0 * t), std::cos(0.2 * t);
  }
  return MimoData(0.1, u, y, std::nullopt, 2.0).with_names({"f1", "f2"}, {"a", "b", "c"});
}

TEST(MimoPreprocessing, EveryChannelIsTheSisoPreprocessingOfIt) {
  const MimoData data = record();
  PreprocessingOptions options;
  options.first_row = 10;
  options.end_row = 390;
  options.detrend = Detrend::linear;
  options.decimate = 2;
  options.input_scale = 2.0;
  options.output_scale = 0.5;
  const PreprocessedMimoData p = preprocess(data, options);
  EXPECT_EQ(p.data.input_names(), data.input_names());
  EXPECT_EQ(p.data.output_names(), data.output_names());
  EXPECT_DOUBLE_EQ(p.data.sample_time(), 0.2);
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 3; ++j) {
      const PreprocessedData q = preprocess(data.channel(i, j), options);
      EXPECT_EQ(p.data.inputs().col(i), q.data.input());
      EXPECT_EQ(p.data.outputs().col(j), q.data.output());
      EXPECT_EQ(p.input_offsets(i), q.record.input_offset);
      EXPECT_EQ(p.output_slopes(j), q.record.output_slope);
      EXPECT_EQ(p.data.start_time(), q.data.start_time());
    }
  }
  EXPECT_EQ(p.record.samples, p.data.size());
  EXPECT_NEAR(p.output_slopes(1), 0.3, 0.01);
}

// An output-only record: every channel as the MIMO preprocessing gives it, bit for bit, and
// no warnings (oma removes the means itself).
TEST(MimoPreprocessing, OutputsOnlyAreTheMimoOutputsBitForBit) {
  const MimoData data = record();
  PreprocessingOptions options;
  options.start_time = 4.0;
  options.end_time = 40.0;
  options.detrend = Detrend::linear;
  options.decimate = 3;
  options.output_scale = 0.5;
  const PreprocessedMimoData p = preprocess(data, options);
  const PreprocessedOutputs q = preprocess_outputs(data.outputs(), 0.1, 2.0, options);
  EXPECT_EQ(q.outputs, p.data.outputs());
  EXPECT_EQ(q.start_time, p.data.start_time());
  EXPECT_EQ(q.record.samples, p.record.samples);
  EXPECT_EQ(q.record.first_row, p.record.first_row);
  EXPECT_DOUBLE_EQ(q.record.sample_time, 0.3);
  EXPECT_TRUE(q.record.warnings.empty());
  Eigen::MatrixXd bad = data.outputs();
  bad(7, 2) = std::numeric_limits<double>::quiet_NaN();
  try {
    preprocess_outputs(bad, 0.1, 2.0, options);
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("output channel 3 is nan at sample 7"));
  }
}

TEST(MimoPreprocessing, WarningsNameTheChannel) {
  const PreprocessedMimoData p = preprocess(record(), PreprocessingOptions{});
  EXPECT_THAT(
      p.record.warnings,
      ::testing::Contains(HasSubstr("input f1 mean 3.06973 is 4.3 x its standard deviation")));
  EXPECT_THAT(p.record.warnings, ::testing::Contains(HasSubstr("output a mean 10.0284 is 14 x")));
  for (const std::string& w : p.record.warnings) {
    EXPECT_THAT(w, ::testing::Not(HasSubstr("output c")));
  }
}

}  // namespace
}  // namespace ctid::mimo_preprocessing_test
