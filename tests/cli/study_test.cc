// `ctid study` run as a user would, on a tiny closed-loop study: the files it promises, a
// replayed run equal to its row in runs.csv, thread count not changing the result, results
// never replaced without --force, bad flags exiting 2 with one line. (--scheduler on a real
// LocalCluster: python/tests/test_distributed_study.py.)
#include <string>
#include <variant>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/io/documents.h"

namespace ctid::cli::study_test {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

class StudyCommand : public testing::CliTest {
 protected:
  // 2 sizes (500, 700) x 3 runs of Section 6.2, SRIVC and CLSRIVC only.
  testing::RunResult tiny(const std::string& dir, std::vector<std::string> extra = {}) {
    std::vector<std::string> args{"study",
                                  "closed-loop",
                                  "-o",
                                  dir,
                                  "--runs",
                                  "3",
                                  "--sizes",
                                  "2",
                                  "--max-samples",
                                  "700",
                                  "--estimators",
                                  "srivc",
                                  "clsrivc",
                                  "--no-plot",
                                  "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    return ctid(args);
  }
};

void expect_bad_input(const testing::RunResult& r, const std::string& fragment) {
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(testing::line_count(r.err), 1) << r.err;
  EXPECT_THAT(r.err, StartsWith("ctid study: error: "));
  EXPECT_THAT(r.err, HasSubstr(fragment));
}

TEST_F(StudyCommand, WritesItsFilesAndReplaysOneRunExactly) {
  ASSERT_EQ(tiny("s", {"--threads", "2"}).status, 0);
  // Header + one line per row.
  auto rows = [&](const char* file) {
    return testing::line_count(testing::slurp(path("s") / file)) - 1;
  };
  EXPECT_EQ(rows("runs.csv"), 2 * 3 * 2);  // sizes x runs x estimators
  EXPECT_EQ(rows("mse.csv"), 2 * 6 * 2);   // sizes x parameters x estimators
  EXPECT_EQ(rows("trends.csv"), 6 * 2);
  // The summary document holds the MSE table and the trends.
  const io::ResultDocument summary = io::read_result(path("s") / "summary.json");
  ASSERT_TRUE(std::holds_alternative<StudySummary>(summary));
  EXPECT_EQ(std::get<StudySummary>(summary).mse.size(), 2u * 6u * 2u);
  EXPECT_EQ(std::get<StudySummary>(summary).trends.size(), 6u * 2u);
  EXPECT_EQ(std::get<StudySummary>(summary).kind, StudyKind::closed_loop);
  // One thread gives the same bytes.
  ASSERT_EQ(tiny("serial", {"--threads", "1"}).status, 0);
  EXPECT_EQ(testing::slurp(path("serial") / "runs.csv"), testing::slurp(path("s") / "runs.csv"));
  // Replaying size 1, run 2 writes exactly its rows of the full runs.csv.
  ASSERT_EQ(tiny("one", {"--size-index", "1", "--run-index", "2"}).status, 0);
  const std::string all = testing::slurp(path("s") / "runs.csv");
  const std::string one = testing::slurp(path("one") / "runs.csv");
  const std::string body = one.substr(one.find('\n') + 1);
  ASSERT_FALSE(body.empty());
  EXPECT_NE(all.find(body), std::string::npos) << one;
}

TEST_F(StudyCommand, ResultsAreNotReplacedWithoutForce) {
  ASSERT_EQ(tiny("s").status, 0);
  write("s/mse.csv", "keep");
  expect_bad_input(tiny("s"), "file exists; pass --force");
  EXPECT_EQ(testing::slurp(path("s") / "mse.csv"), "keep");
  ASSERT_EQ(tiny("s", {"--force"}).status, 0);
  EXPECT_NE(testing::slurp(path("s") / "mse.csv"), "keep");
  write("file", "x");
  expect_bad_input(tiny("file"), "--output");
}

TEST_F(StudyCommand, BadFlagsExitTwo) {
  expect_bad_input(tiny("s", {"--size-index", "1"}), "give both");
  expect_bad_input(ctid({"study", "closed-loop", "-o", "s", "--estimators", "lsq"}),
                   "unknown estimator 'lsq'");
  expect_bad_input(ctid({"study", "closed-loop", "-o", "s", "--min-samples", "900", "--max-samples",
                         "800", "--no-plot"}),
                   "");
}

TEST_F(StudyCommand, SchedulerFlagIsCheckedBeforeAnyNetwork) {
  // No scheduler listens at port 1: both are refused before anything connects.
  expect_bad_input(
      tiny("s", {"--scheduler", "tcp://127.0.0.1:1", "--size-index", "0", "--run-index", "0"}),
      "replay one run here");
  expect_bad_input(tiny("s", {"--scheduler", ""}), "an address is needed");
}

TEST_F(StudyCommand, PlotDrawsMseAgainstN) {
  if (testing::python_package().empty()) {
    GTEST_SKIP() << "the ctid Python package is not built (CTID_BUILD_PYTHON=OFF); set "
                    "CTID_PYTHONPATH to test the figure";
  }
  std::vector<std::string> args{
      "study",         "closed-loop", "-o",           "s",     "--runs", "2", "--sizes", "2",
      "--max-samples", "600",         "--estimators", "srivc", "-q"};
  ASSERT_EQ(ctid(args).status, 0);
  const std::string bytes = testing::slurp(path("s") / "mse.png");
  EXPECT_GT(bytes.size(), 10000u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
}

}  // namespace
}  // namespace ctid::cli::study_test
