#include "ctid/core/mimo_data.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"

namespace ctid::mimo_data_test {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

Eigen::MatrixXd ramp(int rows, int cols, double offset) {
  Eigen::MatrixXd m(rows, cols);
  for (int j = 0; j < cols; ++j) {
    for (int k = 0; k < rows; ++k) m(k, j) = offset + 10 * j + k;
  }
  return m;
}

TEST(MimoData, ChannelsSegmentsAndNames) {
  const MimoData d = MimoData(0.5, ramp(6, 2, 0), ramp(6, 3, 100), ramp(6, 2, 200), 1.0)
                         .with_input_hold(Hold::first_order_hold);
  EXPECT_EQ(d.size(), 6);
  EXPECT_EQ(d.input_count(), 2);
  EXPECT_EQ(d.output_count(), 3);
  EXPECT_EQ(d.input_names(), (std::vector<std::string>{"u1", "u2"}));
  EXPECT_EQ(d.output_names(), (std::vector<std::string>{"y1", "y2", "y3"}));
  EXPECT_DOUBLE_EQ(d.time()(5), 3.5);

  const SampledData c = d.channel(1, 2);
  EXPECT_EQ(c.input(), d.inputs().col(1));
  EXPECT_EQ(c.output(), d.outputs().col(2));
  EXPECT_EQ(c.reference(), d.references().col(1));
  EXPECT_EQ(c.input_hold(), Hold::first_order_hold);
  EXPECT_DOUBLE_EQ(c.start_time(), 1.0);

  const MimoData s = d.segment(2, 3);
  EXPECT_DOUBLE_EQ(s.start_time(), 2.0);
  EXPECT_DOUBLE_EQ(s.outputs()(0, 1), 112.0);
  EXPECT_DOUBLE_EQ(s.references()(2, 0), 204.0);
  EXPECT_EQ(s.input_hold(), Hold::first_order_hold);

  const MimoData named = d.with_names({"f1", "f2"}, {"a", "b", "c"});
  EXPECT_EQ(named.output_names()[2], "c");
  EXPECT_EQ(named.segment(0, 2).input_names()[1], "f2");
}

TEST(MimoData, FromSisoRecord) {
  const SampledData siso = SampledData(0.1, Eigen::VectorXd::LinSpaced(5, 0, 4),
                                       Eigen::VectorXd::Ones(5), Eigen::VectorXd::Zero(5), 2.0)
                               .with_input_hold(Hold::first_order_hold);
  const MimoData d(siso);
  EXPECT_EQ(d.input_count(), 1);
  EXPECT_EQ(d.output_count(), 1);
  EXPECT_TRUE(d.has_references());
  const SampledData back = d.channel(0, 0);
  EXPECT_EQ(back.input(), siso.input());
  EXPECT_EQ(back.output(), siso.output());
  EXPECT_EQ(back.input_hold(), siso.input_hold());
  EXPECT_DOUBLE_EQ(back.start_time(), 2.0);
}

TEST(MimoData, RejectsBadRecordsWithOneMessage) {
  const Eigen::MatrixXd four = Eigen::MatrixXd::Ones(4, 2);
  EXPECT_THAT([&] { MimoData(0.0, four, four); },
              ThrowsMessage<InvalidArgument>(HasSubstr("sample time")));
  EXPECT_THAT([&] { MimoData(1.0, four, Eigen::MatrixXd::Ones(3, 2)); },
              ThrowsMessage<InvalidArgument>(HasSubstr("equal lengths")));
  EXPECT_THAT([&] { MimoData(1.0, Eigen::MatrixXd(4, 0), four); },
              ThrowsMessage<InvalidArgument>(HasSubstr("at least one input column")));
  EXPECT_THAT([&] { MimoData(1.0, four, four, Eigen::MatrixXd::Ones(4, 3)); },
              ThrowsMessage<InvalidArgument>(HasSubstr("3 reference columns for 2 inputs")));
  Eigen::MatrixXd bad = four;
  bad(2, 1) = NAN;
  EXPECT_THAT([&] { MimoData(1.0, four, bad); },
              ThrowsMessage<InvalidArgument>(HasSubstr("output 2 sample 2 is nan")));
  const MimoData d(1.0, four, four);
  EXPECT_THAT(
      [&] {
        d.with_names({"a", "b"}, {"c", "a"});
      },
      ThrowsMessage<InvalidArgument>(HasSubstr("'a' is named twice")));
  EXPECT_THAT(
      [&] {
        d.with_names({"a"}, {"c", "d"});
      },
      ThrowsMessage<InvalidArgument>(HasSubstr("1 input names for 2 inputs")));
  EXPECT_THAT([&] { d.channel(2, 0); },
              ThrowsMessage<InvalidArgument>(HasSubstr("input index 2 is out of range")));
  EXPECT_THAT([&] { d.segment(3, 2); }, ThrowsMessage<InvalidArgument>(HasSubstr("does not fit")));
}

}  // namespace
}  // namespace ctid::mimo_data_test
