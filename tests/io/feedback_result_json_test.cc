// The delayed_feedback_result document: typed and versioned, models as the io model documents,
// and a write-read-write round trip that reproduces every number bit for bit.
#include "ctid/io/feedback_result_json.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/delayed_feedback/feedback_delay_scan.h"
#include "ctid/delayed_feedback/identification.h"
#include "ctid/io/json.h"
#include "io/test_directory.h"
#include "support/de_iuliis_systems.h"
#include "support/sanitizers.h"

namespace ctid::io::feedback_result_json_test {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// Computed once: every test reads the same identification.
const DelayedFeedbackResult& identified() {
  static const DelayedFeedbackResult result = [] {
    const SampledData data =
        test_support::feedback_record(test_support::paper_feedback_loop(), 20.0);
    FeedbackIdentificationOptions o;
    o.output_error.hold = Hold::first_order_hold;
    o.iv_filter_poles = {0.5};
    DelayedFeedbackResult r;
    r.identification = identify_delayed_feedback(data, 3, 3, 0.5, o);
    FeedbackDelayScanOptions scan;
    scan.min_delay = 0.3;
    scan.max_delay = 0.7;
    scan.points = 5;
    scan.refine = false;
    r.delay_scan = scan_feedback_delay(data, 3, 3, scan);
    return r;
  }();
  return result;
}

TEST(FeedbackResultJson, DocumentIsTypedVersionedAndUsesTheModelSchema) {
  CTID_SKIP_UNDER_SANITIZERS(
      "RoundTripThroughAFileIsBitIdentical writes and reads the same document");
  const DelayedFeedbackResult r = identified();
  ASSERT_TRUE(r.identification.converged()) << r.identification.brief_report();
  const nlohmann::json j = to_json(r);
  EXPECT_EQ(j["type"], "delayed_feedback_result");
  EXPECT_EQ(j["version"], 1);
  const nlohmann::json& loop = j["identification"]["loop"];
  EXPECT_EQ(loop["type"], "delayed_feedback_loop");
  EXPECT_EQ(loop["forward"]["type"], "transfer_function");
  EXPECT_EQ(loop["forward"]["numerator_ascending"].size(), 3u);
  EXPECT_EQ(j["identification"]["termination"], "converged");
  EXPECT_EQ(j["identification"]["best_candidate"].get<std::size_t>(),
            *r.identification.best_candidate);
  EXPECT_EQ(j["delay_scan"]["delays"].size(), 5u);
  EXPECT_TRUE(is_delayed_feedback_result(j));
}

TEST(FeedbackResultJson, RoundTripThroughAFileIsBitIdentical) {
  const testing::TestDirectory dir;
  const DelayedFeedbackResult r = identified();
  write_delayed_feedback_result(dir / "result.json", r);
  const DelayedFeedbackResult back = read_delayed_feedback_result(dir / "result.json");
  // Every number compares with == (nlohmann compares doubles exactly).
  EXPECT_EQ(to_json(back), to_json(r));
  EXPECT_EQ(back.identification.loop.forward.numerator().coefficients(),
            r.identification.loop.forward.numerator().coefficients());
  EXPECT_EQ(back.identification.loop.feedback.denominator().coefficients(),
            r.identification.loop.feedback.denominator().coefficients());
  EXPECT_EQ(back.identification.loop.delay, r.identification.loop.delay);
  EXPECT_EQ(back.identification.output_rms, r.identification.output_rms);
  EXPECT_EQ(back.identification.termination, r.identification.termination);
  EXPECT_EQ(back.identification.best_candidate, r.identification.best_candidate);
  EXPECT_EQ(back.identification.candidates.size(), r.identification.candidates.size());
  EXPECT_EQ(back.identification.cramer_rao.covariance, r.identification.cramer_rao.covariance);
  ASSERT_TRUE(back.delay_scan.has_value());
  // Finite numbers come back bit for bit; a non-finite one (an unusable delay, +inf) is
  // written as null and comes back as NaN.
  ASSERT_EQ(back.delay_scan->criterion.size(), r.delay_scan->criterion.size());
  for (Eigen::Index i = 0; i < r.delay_scan->criterion.size(); ++i) {
    if (std::isfinite(r.delay_scan->criterion(i))) {
      EXPECT_EQ(back.delay_scan->criterion(i), r.delay_scan->criterion(i)) << i;
    } else {
      EXPECT_TRUE(std::isnan(back.delay_scan->criterion(i))) << i;
    }
  }
  EXPECT_EQ(back.delay_scan->delays, r.delay_scan->delays);
}

TEST(FeedbackResultJson, BadDocumentsNameTheSourceAndField) {
  nlohmann::json j = to_json(identified());
  j["version"] = 2;
  EXPECT_THAT([&] { delayed_feedback_result_from_json(j, "r.json"); },
              ThrowsMessage<InvalidArgument>(HasSubstr("r.json: version must be 1")));
  j["version"] = 1;
  j["identification"]["output_rms"] = "small";
  EXPECT_THAT([&] { delayed_feedback_result_from_json(j, "r.json"); },
              ThrowsMessage<InvalidArgument>(HasSubstr("r.json.identification.output_rms")));
  j = to_json(identified());
  j["identification"]["colour"] = 1;
  EXPECT_THAT([&] { delayed_feedback_result_from_json(j, "r.json"); },
              ThrowsMessage<InvalidArgument>(HasSubstr("unknown field 'colour'")));
  EXPECT_THAT(
      [&] {
        delayed_feedback_result_from_json(nlohmann::json{{"type", "x"}}, "r.json");
      },
      ThrowsMessage<InvalidArgument>(HasSubstr("not a delayed_feedback_result")));
}

}  // namespace
}  // namespace ctid::io::feedback_result_json_test
