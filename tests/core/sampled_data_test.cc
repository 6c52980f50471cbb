#include "ctid/core/sampled_data.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"

namespace ctid {
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

TEST(SampledData, TimeStampsMustBeUniform) {
  Eigen::VectorXd t(5);
  t << 0.0, 0.1, 0.2, 0.3, 0.4;
  const SampledData d =
      SampledData::from_time_stamps(t, Eigen::VectorXd::Zero(5), Eigen::VectorXd::Zero(5));
  EXPECT_NEAR(d.sample_time(), 0.1, 1e-15);
  t(3) = 0.31;
  EXPECT_THAT(
      [&] { SampledData::from_time_stamps(t, Eigen::VectorXd::Zero(5), Eigen::VectorXd::Zero(5)); },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("step 3")));
  t << 0.4, 0.3, 0.2, 0.1, 0.0;
  EXPECT_THAT(
      [&] { SampledData::from_time_stamps(t, Eigen::VectorXd::Zero(5), Eigen::VectorXd::Zero(5)); },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("increase")));
}

}  // namespace
}  // namespace ctid

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
