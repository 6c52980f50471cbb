#include "ctid/io/sampled_data_csv.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/io/fields_json.h"
#include "io/test_directory.h"

namespace ctid::io::sampled_data_csv_test {
namespace {

using ::testing::HasSubstr;

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(SampledDataCsv, ReadsUniformRecordWithReference) {
  const CsvTable table = parse_csv("time,r,u,y\n1.0,5,1,2\n1.5,6,3,4\n2.0,7,5,6\n", "d.csv");
  CsvColumns columns;
  columns.time = "time";
  columns.reference = "r";
  const SampledData data = sampled_data_from_table(table, columns);
  EXPECT_EQ(data.size(), 3);
  EXPECT_DOUBLE_EQ(data.sample_time(), 0.5);
  EXPECT_DOUBLE_EQ(data.start_time(), 1.0);
  EXPECT_EQ(data.input()(2), 5.0);
  EXPECT_EQ(data.output()(1), 4.0);
  ASSERT_TRUE(data.has_reference());
  EXPECT_EQ(data.reference()(0), 5.0);
}

TEST(SampledDataCsv, NonUniformTimeStampsNameFileAndColumn) {
  const CsvTable table = parse_csv("t,u,y\n0,1,2\n0.1,1,2\n0.25,1,2\n0.3,1,2\n", "d.csv");
  const std::string message = error_of([&] { sampled_data_from_table(table); });
  EXPECT_THAT(message, HasSubstr("d.csv: column 't': time stamps are not uniform"));
}

TEST(SampledDataCsv, DecreasingTimeIsAnError) {
  const CsvTable table = parse_csv("t,u,y\n1,1,2\n0,1,2\n", "d.csv");
  EXPECT_THAT(error_of([&] { sampled_data_from_table(table); }),
              HasSubstr("d.csv: column 't': time stamps must increase"));
}

TEST(SampledDataCsv, MissingColumnIsNamed) {
  const CsvTable table = parse_csv("t,u\n0,1\n1,2\n", "d.csv");
  EXPECT_EQ(error_of([&] { sampled_data_from_table(table); }),
            "d.csv: no column 'y' (columns: t, u)");
}

TEST(SampledDataCsv, TimedSignalGivesStartAndSampleTime) {
  const CsvTable table = parse_csv("t,u\n2,1\n2.25,2\n2.5,3\n", "d.csv");
  const TimedSignal s = timed_signal_from_table(table, "t", "u");
  EXPECT_DOUBLE_EQ(s.start_time, 2.0);
  EXPECT_DOUBLE_EQ(s.sample_time, 0.25);
  EXPECT_EQ(s.values, table.column("u"));
}

TEST(SampledDataCsv, ColumnsValidateNamesTheField) {
  CsvColumns columns;
  columns.input = "y";
  EXPECT_THAT(error_of([&] { columns.validate(); }), HasSubstr("must differ"));
  columns = CsvColumns{};
  columns.relative_tolerance = 0.0;
  EXPECT_THAT(error_of([&] { columns.validate(); }),
              HasSubstr("CsvColumns.relative_tolerance is 0"));
}

TEST(SampledDataCsv, ColumnsRoundTripThroughTheirFields) {
  CsvColumns columns;
  columns.reference = "r";
  columns.relative_tolerance = 1e-3;
  const CsvColumns back = options_from_json<CsvColumns>(fields_to_json(columns), "c.json");
  EXPECT_EQ(back.reference, "r");
  EXPECT_EQ(back.relative_tolerance, 1e-3);
  EXPECT_EQ(fields_to_json(back), fields_to_json(columns));
  EXPECT_THAT(error_of([] {
                options_from_json<CsvColumns>(nlohmann::json{{"input", "t"}}, "c.json");
              }),
              HasSubstr("c.json: CsvColumns names 't', 't', 'y', '' must differ"));
}

TEST(SampledDataCsv, WriteThenReadRoundTripsExactly) {
  const testing::TestDirectory dir;
  Eigen::VectorXd u(5), y(5), r(5);
  u << 1.0 / 3.0, -2.5, 1e-17, 4e99, 0.1;  // 1e100 is the largest magnitude taken
  y << 0.7, 0.1 + 0.2, -1.0 / 7.0, 3.0, 1e-300;
  r << 1, 2, 3, 4, 5;
  const SampledData data(0.05, u, y, r, 0.0);
  CsvColumns columns;
  columns.reference = "r";
  write_sampled_data(dir / "d.csv", data, columns);
  const SampledData back = read_sampled_data(dir / "d.csv", columns);
  EXPECT_EQ(back.input(), u);
  EXPECT_EQ(back.output(), y);
  EXPECT_EQ(back.reference(), r);
  EXPECT_NEAR(back.sample_time(), 0.05, 1e-15);
  EXPECT_EQ(read_csv(dir / "d.csv").names, (std::vector<std::string>{"t", "u", "y", "r"}));
}

}  // namespace
}  // namespace ctid::io::sampled_data_csv_test

namespace ctid::io::sampled_data_csv_test {
namespace {

TEST(SampledDataCsv, TheFileMayDeclareTheInputHold) {
  const std::string body = "t,u,y\n0,1,2\n0.5,3,4\n1,5,6\n";
  EXPECT_EQ(sampled_data_from_table(parse_csv(body, "d.csv")).input_hold(), Hold::zero_order_hold);
  const CsvTable declared = parse_csv("# measured on rig 2\n# input_hold: foh\n" + body, "d.csv");
  const SampledData data = sampled_data_from_table(declared);
  EXPECT_EQ(data.input_hold(), Hold::first_order_hold);
  EXPECT_EQ(data.size(), 3);
  // Written back with its declaration, and read again the same.
  const CsvTable written = parse_csv(format_csv(to_csv_table(data)), "w.csv");
  EXPECT_EQ(sampled_data_from_table(written).input_hold(), Hold::first_order_hold);
  EXPECT_THAT(format_csv(to_csv_table(data)), ::testing::StartsWith("# input_hold: foh\nt,u,y\n"));
  const CsvTable bad = parse_csv("#input_hold: spline\n" + body, "d.csv");
  EXPECT_THAT(error_of([&] { sampled_data_from_table(bad); }),
              HasSubstr("d.csv:1: input_hold is 'spline'; it must be zoh or foh"));
}

}  // namespace
}  // namespace ctid::io::sampled_data_csv_test
