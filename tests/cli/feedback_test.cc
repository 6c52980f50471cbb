// `ctid feedback`: bad input gives exit 2 and one line; a run on a simulated informative
// record (smooth multisine, continued linearly between samples) recovers F and H.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/io/feedback_result_json.h"
#include "ctid/io/json.h"
#include "ctid/io/sampled_data_csv.h"
#include "ctid/simulation/delayed_feedback.h"
#include "support/de_iuliis_systems.h"
#include "support/sanitizers.h"

namespace ctid::cli::feedback_test {
namespace {

using testing::CliTest;
using ::testing::HasSubstr;
using testing::line_count;
using ::testing::StartsWith;

DelayedFeedbackLoop paper_loop() { return test_support::paper_feedback_loop(); }

// `samples` samples (601: 30 s) of the delayed-feedback tests' record, δ = 50 ms, 8 harmonics
// of a 15 s period.
SampledData informative_record(int samples = 601) {
  return test_support::feedback_record(paper_loop(),
                                       (samples - 1) * test_support::kFeedbackSampleTime);
}

void expect_bad_input(const testing::RunResult& r, const std::string& what) {
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_THAT(r.err, StartsWith("ctid feedback: error: "));
  EXPECT_THAT(r.err, HasSubstr(what));
}

TEST_F(CliTest, FeedbackBadInputIsOneLineAndExitTwo) {
  io::write_sampled_data(path("short.csv"), informative_record(20));
  const std::string data = path("short.csv").string();
  expect_bad_input(
      ctid({"feedback", data, "--forward-order", "3", "--feedback-order", "3", "--delay", "-0.5"}),
      "--delay");
  expect_bad_input(
      ctid({"feedback", data, "--forward-order", "0", "--feedback-order", "3", "--delay", "0.5"}),
      "order");
  // 20 samples: 10 equations after Δ, fewer than the 17 unknowns of step 1.
  expect_bad_input(
      ctid({"feedback", data, "--forward-order", "3", "--feedback-order", "3", "--delay", "0.5"}),
      "");
  // A record (0.95 s) shorter than the delay.
  expect_bad_input(
      ctid({"feedback", data, "--forward-order", "1", "--feedback-order", "1", "--delay", "5"}),
      "");
  expect_bad_input(ctid({"feedback", data, "--forward-order", "1", "--feedback-order", "1"}),
                   "--delay");
  expect_bad_input(ctid({"feedback", data, "--forward-order", "1", "--feedback-order", "1",
                         "--delay-scan", "0.6:0.2"}),
                   "--delay-scan");
}

TEST_F(CliTest, FeedbackRecoversTheLoopAndWritesJson) {
  CTID_SKIP_UNDER_SANITIZERS(
      "FeedbackPipeline runs the estimation and FeedbackResultJson the document under them");
  io::write_sampled_data(path("loop.csv"), informative_record());
  const auto r = ctid({"feedback", path("loop.csv").string(), "--forward-order", "3",
                       "--feedback-order", "3", "--delay", "0.5", "--output", "result.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("termination: converged after "));
  EXPECT_THAT(r.out, HasSubstr("F(s) ="));
  const nlohmann::json j = io::read_json(path("result.json"));
  const DelayedFeedbackLoop truth = paper_loop();
  const auto expect_poly = [](const nlohmann::json& a, const Polynomial& p) {
    ASSERT_EQ(a.size(), static_cast<std::size_t>(p.degree() + 1));
    for (int i = 0; i <= p.degree(); ++i)
      EXPECT_NEAR(a[static_cast<std::size_t>(i)].get<double>(), p.coefficient(i), 1e-6) << i;
  };
  EXPECT_EQ(j["type"], "delayed_feedback_result");
  EXPECT_EQ(j["version"], 1);
  const nlohmann::json& loop = j["identification"]["loop"];
  expect_poly(loop["forward"]["numerator_ascending"], truth.forward.numerator());
  expect_poly(loop["forward"]["denominator_ascending"], truth.forward.denominator());
  expect_poly(loop["feedback"]["numerator_ascending"], truth.feedback.numerator());
  expect_poly(loop["feedback"]["denominator_ascending"], truth.feedback.denominator());
  EXPECT_DOUBLE_EQ(loop["delay"].get<double>(), 0.5);
  EXPECT_FALSE(j["identification"]["candidates"].empty());
  EXPECT_EQ(j["identification"]["termination"], "converged");
  // The library reads the document back, every number bit for bit.
  const io::DelayedFeedbackResult back = io::read_delayed_feedback_result(path("result.json"));
  EXPECT_EQ(io::to_json(back), j);
  // No clobbering without --force.
  const auto again = ctid({"feedback", path("loop.csv").string(), "--forward-order", "3",
                           "--feedback-order", "3", "--delay", "0.5", "--output", "result.json"});
  EXPECT_EQ(again.status, 2);
  EXPECT_THAT(again.err, HasSubstr("--force"));
}

TEST_F(CliTest, FeedbackResultIsAModelForSimulate) {
  CTID_SKIP_UNDER_SANITIZERS(
      "CliTest.FeedbackRecoversTheLoopAndWritesJson runs ctid feedback; the simulate tests read "
      "model files");
  io::write_sampled_data(path("loop.csv"), informative_record());
  ASSERT_EQ(ctid({"feedback", path("loop.csv").string(), "--forward-order", "3", "--feedback-order",
                  "3", "--delay", "0.5", "--output", "result.json", "-q"})
                .status,
            0);
  // ctid simulate accepts the result and simulates its loop: the same record comes back.
  const auto r = ctid({"simulate", "--model", "result.json", "--input", path("loop.csv").string(),
                       "--output", "again.csv", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  const SampledData original = informative_record();
  const SampledData again = io::read_sampled_data(path("again.csv"));
  ASSERT_EQ(again.size(), original.size());
  EXPECT_LT((again.output() - original.output()).cwiseAbs().maxCoeff(), 1e-6);
}

}  // namespace
}  // namespace ctid::cli::feedback_test
