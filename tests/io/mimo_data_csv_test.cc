#include "ctid/io/mimo_data_csv.h"

#include <functional>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "io/test_directory.h"

namespace ctid::io::mimo_data_csv_test {
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

// Two forces and four accelerations, in the flexible structure's column naming.
CsvTable structure_table() {
  return parse_csv(
      "t_s,u1_force,u2_force,y1_acc,y2_acc,y3_acc,y4_acc,r1,r2\n"
      "0,1,2,3,4,5,6,7,8\n"
      "0.5,11,12,13,14,15,16,17,18\n"
      "1,21,22,23,24,25,26,27,28\n",
      "d.csv");
}

MimoCsvColumns columns(std::vector<std::string> inputs, std::vector<std::string> outputs) {
  MimoCsvColumns c;
  c.time = "t_s";
  c.inputs = std::move(inputs);
  c.outputs = std::move(outputs);
  return c;
}

TEST(MimoDataCsv, ReadsNamedColumnsAndRanges) {
  MimoCsvColumns c = columns({"u1_force:u2_force"}, {"y2_acc:y4_acc", "y1_acc"});
  c.references = {"r1", "r2"};
  const MimoData data = mimo_data_from_table(structure_table(), c);
  EXPECT_EQ(data.size(), 3);
  EXPECT_DOUBLE_EQ(data.sample_time(), 0.5);
  EXPECT_EQ(data.input_names(), (std::vector<std::string>{"u1_force", "u2_force"}));
  EXPECT_EQ(data.output_names(),
            (std::vector<std::string>{"y2_acc", "y3_acc", "y4_acc", "y1_acc"}));
  EXPECT_EQ(data.inputs()(1, 1), 12.0);
  EXPECT_EQ(data.outputs()(2, 0), 24.0);
  EXPECT_EQ(data.outputs()(0, 3), 3.0);
  ASSERT_TRUE(data.has_references());
  EXPECT_EQ(data.references()(2, 1), 28.0);
}

TEST(MimoDataCsv, SingleColumnRangeAndDeclaredHold) {
  const CsvTable table = parse_csv("# input_hold: foh\nt,a,b\n0,1,2\n1,3,4\n", "h.csv");
  MimoCsvColumns c;
  c.inputs = {"a:a"};
  c.outputs = {"b"};
  const MimoData data = mimo_data_from_table(table, c);
  EXPECT_EQ(data.input_count(), 1);
  EXPECT_EQ(data.input_hold(), Hold::first_order_hold);
}

TEST(MimoDataCsv, MissingColumnNamesFileColumnAndTheColumnsPresent) {
  const std::string message = error_of(
      [] { mimo_data_from_table(structure_table(), columns({"u1_force"}, {"y1_acc:y29"})); });
  EXPECT_THAT(message, HasSubstr("d.csv: output column 'y29' not found (in range 'y1_acc:y29'); "
                                 "columns are t_s, u1_force, u2_force, y1_acc"));
  EXPECT_THAT(
      error_of([] { mimo_data_from_table(structure_table(), columns({"u3_force"}, {"y1_acc"})); }),
      HasSubstr("d.csv: input column 'u3_force' not found; columns are t_s,"));
  EXPECT_THAT(error_of([] {
                MimoCsvColumns c = columns({"u1_force"}, {"y1_acc"});
                c.time = "t";
                mimo_data_from_table(structure_table(), c);
              }),
              HasSubstr("d.csv: time column 't' not found"));
}

TEST(MimoDataCsv, ColumnNamedTwiceIsAnError) {
  EXPECT_THAT(
      error_of([] {
        mimo_data_from_table(structure_table(), columns({"u1_force"}, {"y1_acc:y3_acc", "y2_acc"}));
      }),
      HasSubstr("d.csv: column 'y2_acc' is named twice (as output and as output)"));
  EXPECT_THAT(error_of([] {
                mimo_data_from_table(structure_table(), columns({"u1_force:y1_acc"}, {"y1_acc"}));
              }),
              HasSubstr("column 'y1_acc' is named twice (as input and as output)"));
  EXPECT_THAT(
      error_of([] { mimo_data_from_table(structure_table(), columns({"u1_force"}, {"t_s"})); }),
      HasSubstr("column 't_s' is named twice (as time and as output)"));
}

TEST(MimoDataCsv, EmptyListsBackwardRangesAndReferenceCount) {
  EXPECT_THAT(error_of([] { mimo_data_from_table(structure_table(), columns({}, {"y1_acc"})); }),
              HasSubstr("MimoCsvColumns.inputs is empty; name at least one input column"));
  EXPECT_THAT(error_of([] { mimo_data_from_table(structure_table(), columns({"u1_force"}, {})); }),
              HasSubstr("MimoCsvColumns.outputs is empty"));
  EXPECT_THAT(error_of([] {
                mimo_data_from_table(structure_table(), columns({"u1_force"}, {"y3_acc:y1_acc"}));
              }),
              HasSubstr("d.csv: output range 'y3_acc:y1_acc': column 'y3_acc' comes after "
                        "'y1_acc' in the file"));
  EXPECT_THAT(
      error_of([] { mimo_data_from_table(structure_table(), columns({"u1_force"}, {"y1_acc:"})); }),
      HasSubstr("output range 'y1_acc:' must be A:B"));
  EXPECT_THAT(error_of([] {
                MimoCsvColumns c = columns({"u1_force:u2_force"}, {"y1_acc"});
                c.references = {"r1"};
                mimo_data_from_table(structure_table(), c);
              }),
              HasSubstr("d.csv: 1 reference column for 2 inputs; give one reference per input"));
}

TEST(MimoDataCsv, NonUniformStampsUseTheSisoRule) {
  const CsvTable table = parse_csv("t,u,y\n0,1,2\n0.1,1,2\n0.25,1,2\n0.3,1,2\n", "d.csv");
  MimoCsvColumns c;
  c.inputs = {"u"};
  c.outputs = {"y"};
  EXPECT_THAT(error_of([&] { mimo_data_from_table(table, c); }),
              HasSubstr("d.csv: column 't': time stamps are not uniform"));
}

TEST(MimoDataCsv, WrittenRecordReadsBackBitIdentical) {
  testing::TestDirectory dir;
  Eigen::MatrixXd u(4, 2);
  u << 0.1, -2.0, 1.0 / 3.0, 4.0, 5.5, 6.25, -7.0, 1e-9;
  Eigen::MatrixXd y = Eigen::MatrixXd::Random(4, 3);
  Eigen::MatrixXd r = Eigen::MatrixXd::Random(4, 2);
  const MimoData data = MimoData(0.1, u, y, r, 2.0)
                            .with_names({"f1", "f2"}, {"a1", "a2", "a3"})
                            .with_input_hold(Hold::first_order_hold);
  write_mimo_data(dir / "m.csv", data, "time");
  EXPECT_THROW(write_mimo_data(dir / "m.csv", data), InvalidArgument);  // exists
  MimoCsvColumns c;
  c.time = "time";
  c.inputs = {"f1:f2"};
  c.outputs = {"a1:a3"};
  c.references = {"r_f1", "r_f2"};
  const MimoData back = read_mimo_data(dir / "m.csv", c);
  EXPECT_EQ(back.inputs(), data.inputs());
  EXPECT_EQ(back.outputs(), data.outputs());
  EXPECT_EQ(back.references(), data.references());
  EXPECT_EQ(back.output_names(), data.output_names());
  EXPECT_EQ(back.input_hold(), Hold::first_order_hold);
  EXPECT_NEAR(back.sample_time(), 0.1, 1e-15);
  EXPECT_DOUBLE_EQ(back.start_time(), 2.0);
}

}  // namespace
}  // namespace ctid::io::mimo_data_csv_test
