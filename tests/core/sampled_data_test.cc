#include "ctid/core/sampled_data.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"

namespace ctid::sampled_data_test {
namespace {

using ::testing::HasSubstr;

TEST(SampledData, TimeAxisAndSegments) {
  const SampledData d(0.5, Eigen::VectorXd::LinSpaced(6, 0, 5), Eigen::VectorXd::Ones(6),
                      std::nullopt, 1.0);
  EXPECT_EQ(d.size(), 6);
  EXPECT_DOUBLE_EQ(d.time()(5), 3.5);
  const SampledData s = d.segment(2, 3);
  EXPECT_DOUBLE_EQ(s.start_time(), 2.0);
  EXPECT_DOUBLE_EQ(s.input()(0), 2.0);
  EXPECT_THAT([&] { d.reference(); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("no reference")));
  EXPECT_THROW(d.segment(5, 3), InvalidArgument);
}

TEST(SampledData, RejectsBadRecords) {
  const Eigen::VectorXd four = Eigen::VectorXd::Ones(4);
  EXPECT_THAT([&] { SampledData(0.0, four, four); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("sample time")));
  EXPECT_THAT([&] { SampledData(1.0, four, Eigen::VectorXd::Ones(3)); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("equal lengths")));
  Eigen::VectorXd bad = four;
  bad(2) = NAN;
  EXPECT_THAT([&] { SampledData(1.0, four, bad); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("output sample 2")));
  EXPECT_THAT([&] { SampledData(1.0, Eigen::VectorXd::Ones(1), Eigen::VectorXd::Ones(1)); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("at least 2")));
  EXPECT_THAT([&] { SampledData(1.0, four, four, Eigen::VectorXd::Ones(2)); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("reference has 2")));
}

// Issue 33: sums of squares of a record must stay finite and normal, so a record's largest
// magnitude lies within 1e-100..1e100 (an all-zero signal is judged elsewhere). At the edges
// the record is taken; beyond them the message names the signal, the magnitude and the sample.
TEST(SampledData, MagnitudesOutsideTheRepresentableRangeAreRefused) {
  const Eigen::VectorXd four = Eigen::VectorXd::LinSpaced(4, -1.0, 2.0);
  EXPECT_NO_THROW(SampledData(1.0, 1e100 * four / 2.0, 1e-100 * four / 2.0));
  EXPECT_NO_THROW(SampledData(1.0, four, Eigen::VectorXd::Zero(4)));
  for (const double scale : {1e101, 1e300, 1e-101, 1e-300, 4.9e-324}) {
    const Eigen::VectorXd scaled = scale * four / 2.0;
    EXPECT_THAT([&] { SampledData(1.0, scaled, four); },
                ::testing::ThrowsMessage<InvalidArgument>(
                    ::testing::AllOf(HasSubstr("the input reaches a magnitude of"),
                                     HasSubstr("(sample 3)"), HasSubstr("1e-100..1e+100"))));
    EXPECT_THAT([&] { SampledData(1.0, four, scaled); },
                ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("the output reaches")));
    EXPECT_THAT([&] { SampledData(1.0, four, four, scaled); },
                ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("the reference reaches")));
  }
}

TEST(SampledData, TimeStampsMustBeUniform) {
  Eigen::VectorXd t(5);
  t << 0.0, 0.1, 0.2, 0.3, 0.4;
  const SampledData d =
      SampledData::from_time_stamps(t, Eigen::VectorXd::Zero(5), Eigen::VectorXd::Zero(5));
  EXPECT_NEAR(d.sample_time(), 0.1, 1e-15);
  t(3) = 0.33;
  EXPECT_THAT(
      [&] { SampledData::from_time_stamps(t, Eigen::VectorXd::Zero(5), Eigen::VectorXd::Zero(5)); },
      ::testing::ThrowsMessage<InvalidArgument>(
          HasSubstr("sample 3 (t = 0.33 s) is 0.03 s off the grid t_0 + k h, with h = 0.1 s")));
  t << 0.4, 0.3, 0.2, 0.1, 0.0;
  EXPECT_THAT(
      [&] { SampledData::from_time_stamps(t, Eigen::VectorXd::Zero(5), Eigen::VectorXd::Zero(5)); },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("increase")));
}

// Stamps k h printed with `digits` significant digits, as a CSV writer would.
Eigen::VectorXd printed_stamps(int n, double h, int digits) {
  Eigen::VectorXd t(n);
  char buffer[40];
  for (int k = 0; k < n; ++k) {
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, k * h);
    t(k) = std::strtod(buffer, nullptr);
  }
  return t;
}

TEST(SampledData, StampsPrintedToFewDigitsAreUniform) {
  const double h = 1.0 / 1024.0;
  for (const int digits : {5, 6, 8}) {
    const Eigen::VectorXd t = printed_stamps(9000, h, digits);
    const TimeStampCheck check = check_time_stamps(t);
    EXPECT_FALSE(check.worst_sample)
        << digits << " digits: sample " << check.worst_sample.value_or(-1);
    EXPECT_EQ(check.digits, digits);
    EXPECT_NEAR(check.step, h, 1e-3 * h);
  }
  // The shipped flexible-structure stamps: 0.9755859375 printed as 0.97558594.
  const Eigen::VectorXd t = printed_stamps(8192, h, 8);
  EXPECT_EQ(t(999), 0.97558594);
  const SampledData d =
      SampledData::from_time_stamps(t, Eigen::VectorXd::Zero(8192), Eigen::VectorXd::Zero(8192));
  EXPECT_NEAR(d.sample_time(), h, 1e-8 * h);
}

TEST(SampledData, GapsAndJitterBeyondThePrintedDigitsAreRefused) {
  const double h = 0.08;
  Eigen::VectorXd t = printed_stamps(1000, h, 5);
  // A missing sample: every stamp after row 400 moves one step later.
  Eigen::VectorXd gap = t;
  gap.tail(600).array() += h;
  const TimeStampCheck missing = check_time_stamps(gap);
  ASSERT_TRUE(missing.worst_sample);
  EXPECT_EQ(*missing.worst_sample, 400);
  EXPECT_GT(missing.deviation, 0.4 * h);
  // Jitter of 1 % of h on stamps printed with all 17 digits.
  Eigen::VectorXd jitter = Eigen::VectorXd::LinSpaced(1000, 0.0, 999.0) * h;
  jitter(500) += 0.01 * h;
  EXPECT_THAT(
      [&] {
        SampledData::from_time_stamps(jitter, Eigen::VectorXd::Zero(1000),
                                      Eigen::VectorXd::Zero(1000));
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("not uniform: sample 500")));
  // Stamps too coarse to resolve a quarter step: 2 digits for h = 0.08 up to 80 s.
  const TimeStampCheck coarse = check_time_stamps(printed_stamps(1000, h, 2));
  EXPECT_TRUE(coarse.worst_sample);
}

}  // namespace
}  // namespace ctid::sampled_data_test

TEST(SampledData, InputHoldIsZeroOrderByDefaultAndKeptBySegments) {
  const ctid::SampledData data(0.1, Eigen::VectorXd::LinSpaced(10, 0.0, 1.0),
                               Eigen::VectorXd::LinSpaced(10, 1.0, 2.0));
  EXPECT_EQ(data.input_hold(), ctid::Hold::zero_order_hold);
  const ctid::SampledData foh = data.with_input_hold(ctid::Hold::first_order_hold);
  EXPECT_EQ(foh.input_hold(), ctid::Hold::first_order_hold);
  EXPECT_EQ(data.input_hold(), ctid::Hold::zero_order_hold);
  EXPECT_EQ(foh.segment(2, 5).input_hold(), ctid::Hold::first_order_hold);
  EXPECT_EQ(foh.segment(2, 5).input()(0), data.input()(2));
}
