#include "ctid/io/batch_summary.h"

#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"
#include "test_directory.h"

namespace ctid::io::batch_summary_test {
namespace {

using nlohmann::json;
using ::testing::HasSubstr;

void write(const std::filesystem::path& file, const std::string& text) {
  write_text_file(file.string(), text, Overwrite::yes);
}

BatchRecordFiles record_in(const testing::TestDirectory& out, const std::string& name) {
  return {name,
          {"data/" + name + ".csv"},
          (out / (name + ".json")).string(),
          (out / (name + ".error.json")).string()};
}

// Four records, one of each status: a usable SISO fit with one mode, an unusable MIMO fit
// whose modes are in rad/s, a failed record and one that has not run.
TEST(BatchSummary, GivesEachRecordItsStatusNumbersAndMessage) {
  const testing::TestDirectory out;
  write(out / "good.json",
        R"({"verdict": {"usable": true}, "fit_percent": 91.25, "estimator": "srivc",
            "modes": [{"natural_frequency_hz": 1.5, "natural_frequency_hz_standard_error": 0.01,
                       "damping_ratio": 0.02, "damping_ratio_standard_error": 0.001}]})");
  write(out / "mimo.json",
        R"({"type": "mimo_estimation_result", "verdict": {"usable": false,
            "reasons": ["fit below 50 %", "not converged"]}, "fit_percent": [40.0, 20.0],
            "modes": [{"natural_frequency": 6.283185307179586, "damping_ratio": 0.1}]})");
  write(out / "bad.error.json", R"({"message": "ctid fit: error: y is not finite"})");
  write(out / "timings.json", R"({"good": 0.5})");
  const std::vector<BatchRecordFiles> records{record_in(out, "good"), record_in(out, "mimo"),
                                              record_in(out, "bad"), record_in(out, "later")};
  const BatchCounts counts = write_batch_summary(out.path().string(), records);
  EXPECT_EQ(counts.ok, 1);
  EXPECT_EQ(counts.no_usable_model, 1);
  EXPECT_EQ(counts.failed, 1);
  EXPECT_EQ(counts.not_run, 1);
  const json rows = read_json((out / "summary.json").string())["records"];
  ASSERT_EQ(rows.size(), 4U);
  EXPECT_EQ(rows[0]["status"], "ok");
  EXPECT_EQ(rows[0]["seconds"], 0.5);
  EXPECT_EQ(rows[0]["modes"][0]["frequency_hz"], 1.5);
  EXPECT_EQ(rows[1]["status"], "no_usable_model");
  EXPECT_EQ(rows[1]["estimator"], "mimo_srivc");
  EXPECT_EQ(rows[1]["fit_percent"], 30.0);  // the mean over the outputs
  EXPECT_DOUBLE_EQ(rows[1]["modes"][0]["frequency_hz"].get<double>(), 1.0);
  EXPECT_EQ(rows[1]["message"], "fit below 50 %; not converged");
  EXPECT_EQ(rows[2]["status"], "failed");
  EXPECT_EQ(rows[2]["message"], "ctid fit: error: y is not finite");
  EXPECT_EQ(rows[3]["status"], "not_run");
  EXPECT_TRUE(rows[3]["seconds"].is_null());
  const std::string csv = read_text_file((out / "summary.csv").string());
  EXPECT_THAT(csv, HasSubstr("mode1_frequency_hz,mode1_frequency_se_hz,mode1_damping"));
  EXPECT_THAT(csv, HasSubstr("\nlater,data/later.csv,not_run,,,,,,,,,\n"));
  EXPECT_THAT(csv, HasSubstr("good,data/good.csv,ok,true,91.25,srivc,1.5,0.01,0.02,0.001,0.5,\n"));
}

TEST(BatchSummary, RefusesToReplaceAFileItDidNotWrite) {
  const testing::TestDirectory out;
  EXPECT_NO_THROW(check_batch_summary_files(out.path().string()));
  (void)write_batch_summary(out.path().string(), {});
  EXPECT_NO_THROW(check_batch_summary_files(out.path().string()));  // its own summary
  write(out / "summary.csv", "my notes\n");
  try {
    check_batch_summary_files(out.path().string());
    ADD_FAILURE() << "a foreign summary.csv was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("summary.csv: file exists and is not a ctid batch summary"));
  }
}

TEST(BatchSummary, TimingsKeepOtherRecordsAndSkipWhatIsNotANumber) {
  const testing::TestDirectory out;
  write(out / "timings.json", R"({"a": 1.25, "b": "soon"})");
  record_batch_timings(out.path().string(), {{"c", 2.5}});
  const auto times = read_batch_timings(out.path().string());
  ASSERT_EQ(times.size(), 2U);
  EXPECT_EQ(times.at("a"), 1.25);
  EXPECT_EQ(times.at("c"), 2.5);
}

}  // namespace
}  // namespace ctid::io::batch_summary_test
