#include "ctid/io/model_json.h"

#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/io/json.h"
#include "io/test_directory.h"

namespace ctid::io::model_json_test {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

std::string continuous_error(const std::string& text) {
  try {
    continuous_model_from_json(parse_json(text, "m.json"), "m.json");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

std::string discrete_error(const std::string& text) {
  try {
    discrete_transfer_function_from_json(parse_json(text, "c.json"), "c.json");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(ModelJson, TransferFunctionFieldsAreAscending) {
  const ContinuousModel m = continuous_model_from_json(
      nlohmann::json::parse(R"json({"type": "transfer_function", "description": "1/(2s+1)",
          "numerator_ascending": [1], "denominator_ascending": [1, 2], "input_delay": 0.1})json"),
      "m.json");
  const auto& g = std::get<TransferFunction>(m);
  EXPECT_EQ(g.denominator(), Polynomial({1.0, 2.0}));  // 1 + 2 s
  EXPECT_EQ(g.numerator(), Polynomial({1.0}));
  EXPECT_EQ(g.input_delay(), 0.1);
  EXPECT_DOUBLE_EQ(g.poles()(0).real(), -0.5);
}

TEST(ModelJson, TransferFunctionRoundTripIsExact) {
  const TransferFunction g(Polynomial{1.0 / 3.0, -2e-7}, Polynomial{1600.0, 416.0, 408.0, 5.0, 1.0},
                           0.04);
  const nlohmann::json text = nlohmann::json::parse(to_json(g).dump());
  const auto back = std::get<TransferFunction>(continuous_model_from_json(text, "m.json"));
  EXPECT_EQ(back.numerator(), g.numerator());
  EXPECT_EQ(back.denominator(), g.denominator());
  EXPECT_EQ(back.input_delay(), g.input_delay());
}

TEST(ModelJson, AdditiveModelRoundTripThroughAFile) {
  const testing::TestDirectory dir;
  const AdditiveModel g({Submodel{Polynomial{1.0, 0.25, 0.25}, Polynomial{3.0}, 0},
                         Submodel{Polynomial{1.0, 0.01, 0.025}, Polynomial{1.0, 1.0 / 7.0}, 0},
                         Submodel{Polynomial{1.0, 0.5}, Polynomial{2.0}, 1}},
                        0.15);
  write_model(dir / "g.json", ContinuousModel{g});
  const auto back = std::get<AdditiveModel>(read_continuous_model(dir / "g.json"));
  ASSERT_EQ(back.size(), 3);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(back[i].a, g[i].a);
    EXPECT_EQ(back[i].b, g[i].b);
    EXPECT_EQ(back[i].integrators, g[i].integrators);
  }
  EXPECT_EQ(back.input_delay(), 0.15);
  EXPECT_THROW(write_model(dir / "g.json", ContinuousModel{g}), InvalidArgument);
}

TEST(ModelJson, DiscreteTransferFunctionRoundTripIsExact) {
  const DiscreteTransferFunction c(Polynomial{0.00454, -0.02058, 0.02329},
                                   Polynomial{0.0, -1.0, 1.0}, 0.05);
  const auto back = discrete_transfer_function_from_json(to_json(c), "c.json");
  EXPECT_EQ(back.numerator(), c.numerator());
  EXPECT_EQ(back.denominator(), c.denominator());
  EXPECT_EQ(back.sample_time(), c.sample_time());
}

TEST(ModelJson, ZeroLeadingCoefficientNamesFileAndField) {
  const std::string m = continuous_error(
      R"({"type": "transfer_function", "numerator_ascending": [1], "denominator_ascending": [1, 2, 0]})");
  EXPECT_THAT(m, StartsWith("m.json: denominator_ascending: "));
  EXPECT_THAT(m, HasSubstr("leading coefficient"));
}

TEST(ModelJson, NonFiniteCoefficientIsRejected) {
  EXPECT_THAT(continuous_error(R"({"type": "transfer_function", "numerator_ascending": [1e999],
                                 "denominator_ascending": [1, 2]})"),
              StartsWith("m.json:1:"));
  EXPECT_THAT(continuous_error(R"({"type": "transfer_function", "numerator_ascending": [NaN],
                                   "denominator_ascending": [1, 2]})"),
              StartsWith("m.json:1:"));
  nlohmann::json doc = to_json(TransferFunction(Polynomial{1.0}, Polynomial{1.0, 2.0}));
  doc["denominator_ascending"][1] = std::numeric_limits<double>::quiet_NaN();
  try {
    transfer_function_from_json(doc, "m.json");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "m.json: denominator_ascending[1]: value is not finite");
  }
}

TEST(ModelJson, AdditiveSubmodelErrorsNameTheSubmodel) {
  const std::string not_anti_monic = continuous_error(R"({"type": "additive_model", "submodels": [
      {"denominator_ascending": [1, 0.5, 0.25], "numerator_ascending": [3]},
      {"denominator_ascending": [2, 0.5, 0.25], "numerator_ascending": [3]}]})");
  EXPECT_THAT(not_anti_monic, StartsWith("m.json: additive model: "));
  EXPECT_THAT(not_anti_monic, HasSubstr("1"));
  EXPECT_EQ(continuous_error(R"({"type": "additive_model", "submodels": [
      {"denominator_ascending": [1, 0.5], "numerator_ascending": [3], "integrators": -1}]})"),
            "m.json: submodels[0].integrators: is -1; it must be between 0 and 16");
  EXPECT_THAT(continuous_error(R"({"type": "additive_model", "submodels": [
      {"denominator_ascending": [1, 0.5], "numerator": [3]}]})"),
              StartsWith("m.json: submodels[0].numerator_ascending: required field is missing"));
  EXPECT_THAT(continuous_error(R"({"type": "additive_model", "submodels": []})"),
              HasSubstr("m.json: submodels: the array is empty"));
}

TEST(ModelJson, UnknownFieldsAndTypesAreRejected) {
  EXPECT_THAT(continuous_error(R"({"type": "transfer_function", "numerator_ascending": [1],
      "denominator_ascending": [1, 2], "delay": 3})"),
              StartsWith("m.json: delay: unknown field"));
  EXPECT_THAT(continuous_error(R"({"type": "state_space"})"),
              StartsWith("m.json: type: is 'state_space'; a continuous-time model file needs"));
  EXPECT_THAT(continuous_error(R"({"numerator_ascending": [1]})"),
              StartsWith("m.json: type: required field is missing"));
  EXPECT_THAT(continuous_error("[1, 2]"), StartsWith("m.json: document: expected a JSON object"));
}

TEST(ModelJson, NegativeDelayIsRejected) {
  EXPECT_THAT(continuous_error(R"({"type": "transfer_function", "numerator_ascending": [1],
      "denominator_ascending": [1, 2], "input_delay": -0.5})"),
              StartsWith("m.json: transfer function: "));
}

TEST(ModelJson, DiscreteSampleTimeMustBePositive) {
  for (const std::string h : {"0", "-0.05"}) {
    EXPECT_THAT(discrete_error(R"({"type": "discrete_transfer_function", "numerator_ascending": [1],
        "denominator_ascending": [-0.85, 1], "sample_time": )" +
                               h + "}"),
                StartsWith("c.json: discrete transfer function: "))
        << h;
  }
  EXPECT_THAT(discrete_error(R"({"type": "discrete_transfer_function", "numerator_ascending": [1],
      "denominator_ascending": [-0.85, 1]})"),
              StartsWith("c.json: sample_time: required field is missing"));
  EXPECT_THAT(discrete_error(R"({"type": "transfer_function", "numerator_ascending": [1],
      "denominator_ascending": [-0.85, 1], "sample_time": 1})"),
              StartsWith("c.json: type: is 'transfer_function' but a discrete_transfer_function"));
}

std::string loop_error(const std::string& text) {
  try {
    delayed_feedback_loop_from_json(parse_json(text, "loop.json"), "loop.json");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

// The loop of De Iuliis et al. (2017), Section 4, in a JSON text with `forward_numerator`
// in place of F's numerator so that tests can break one field at a time.
std::string loop_text(const std::string& forward_numerator, const std::string& delay = "0.5") {
  return R"({"type": "delayed_feedback_loop", "description": "paper",
      "forward": {"type": "transfer_function", "numerator_ascending": )" +
         forward_numerator + R"(, "denominator_ascending": [3, 2, 3, 1]},
      "feedback": {"type": "transfer_function", "numerator_ascending": [1, 5, 1],
                   "denominator_ascending": [2, 2, 3, 1]},
      "delay": )" +
         delay + "}";
}

TEST(ModelJson, DelayedFeedbackLoopIsReadAscendingAndRoundTrips) {
  const nlohmann::json text = parse_json(loop_text("[2, 1, 2]"), "loop.json");
  EXPECT_TRUE(is_delayed_feedback_loop(text));
  EXPECT_FALSE(
      is_delayed_feedback_loop(to_json(TransferFunction(Polynomial{1.0}, Polynomial{1.0, 1.0}))));
  EXPECT_FALSE(is_delayed_feedback_loop(nlohmann::json::array()));
  const DelayedFeedbackLoop loop = delayed_feedback_loop_from_json(text, "loop.json");
  EXPECT_EQ(loop.forward.numerator(), Polynomial({2.0, 1.0, 2.0}));
  EXPECT_EQ(loop.forward.denominator(), Polynomial({3.0, 2.0, 3.0, 1.0}));
  EXPECT_EQ(loop.feedback.numerator(), Polynomial({1.0, 5.0, 1.0}));
  EXPECT_EQ(loop.feedback.denominator(), Polynomial({2.0, 2.0, 3.0, 1.0}));
  EXPECT_EQ(loop.delay, 0.5);

  const DelayedFeedbackLoop back =
      delayed_feedback_loop_from_json(nlohmann::json::parse(to_json(loop).dump()), "again.json");
  EXPECT_EQ(back.forward.numerator(), loop.forward.numerator());
  EXPECT_EQ(back.feedback.denominator(), loop.feedback.denominator());
  EXPECT_EQ(back.delay, loop.delay);
}

TEST(ModelJson, DelayedFeedbackLoopErrorsNameTheFileAndField) {
  // Biproper F: the loop's own rule, prefixed with the file.
  EXPECT_THAT(loop_error(loop_text("[2, 1, 2, 1]")),
              StartsWith("loop.json: delayed feedback loop: DelayedFeedbackLoop: forward F must "
                         "be strictly proper"));
  EXPECT_THAT(loop_error(loop_text("[2, 1, 2]", "-0.1")),
              HasSubstr("loop.json: delayed feedback loop: DelayedFeedbackLoop: delay must be"));
  EXPECT_THAT(loop_error(loop_text("\"x\"")), StartsWith("loop.json: forward.numerator_ascending"));
  EXPECT_THAT(loop_error(R"({"type": "delayed_feedback_loop", "delay": 0.5,
      "feedback": {"type": "transfer_function", "numerator_ascending": [1],
                   "denominator_ascending": [1, 1]}})"),
              StartsWith("loop.json: forward: required field is missing"));
  EXPECT_THAT(loop_error(R"({"type": "transfer_function", "numerator_ascending": [1],
      "denominator_ascending": [1, 1]})"),
              StartsWith("loop.json: type: is 'transfer_function' but a delayed_feedback_loop"));
  // Fit and validate read ContinuousModel, which a loop is not.
  EXPECT_THAT(continuous_error(loop_text("[2, 1, 2]")),
              StartsWith("m.json: type: is 'delayed_feedback_loop'"));
}

}  // namespace
}  // namespace ctid::io::model_json_test
