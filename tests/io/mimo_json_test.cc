// JSON of the shared-pole models and results (issue 13): a MIMO model and a whole
// MimoEstimationResult read back bit for bit, and malformed documents refused with the field.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/model_json.h"
#include "ctid/refined_iv/mimo_srivc.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::mimo_json_test {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

MimoAdditiveModel two_by_three(bool with_direct) {
  std::vector<MimoSubmodel> submodels;
  int c = 0;
  for (double w : {1.5, 4.0}) {
    MimoSubmodel s{Polynomial{1.0, 0.06 / w, 1.0 / (w * w)}, {}};
    for (int j = 0; j < 6; ++j, ++c) s.b.push_back(Polynomial{0.3 * c - 1.1, 0.01 * c + 0.2});
    submodels.push_back(std::move(s));
  }
  Eigen::MatrixXd d;
  if (with_direct) d = Eigen::MatrixXd::Constant(3, 2, 0.125);
  return MimoAdditiveModel(2, 3, submodels, d);
}

void expect_equal(const MimoAdditiveModel& a, const MimoAdditiveModel& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.inputs(), b.inputs());
  EXPECT_EQ(a.outputs(), b.outputs());
  for (int i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].a.coefficients(), b[i].a.coefficients());
    EXPECT_EQ(a[i].integrators, b[i].integrators);
    for (size_t c = 0; c < a[i].b.size(); ++c) {
      EXPECT_EQ(a[i].b[c].coefficients(), b[i].b[c].coefficients());
    }
  }
  EXPECT_EQ(a.has_direct_term(), b.has_direct_term());
  EXPECT_EQ(a.direct(), b.direct());
  EXPECT_EQ(a.input_delays(), b.input_delays());
}

TEST(MimoJson, ModelRoundTrip) {
  for (bool direct : {false, true}) {
    const MimoAdditiveModel g = two_by_three(direct);
    const nlohmann::json j = io::to_json(g);
    EXPECT_EQ(j.at("type"), "mimo_additive_model");
    EXPECT_EQ(j.at("submodels")[0].at("numerators_ascending").size(), 6u);
    expect_equal(io::mimo_additive_model_from_json(j, "m.json"), g);
    EXPECT_FALSE(j.contains("input_delays"));
    const MimoAdditiveModel delayed = g.with_input_delays(Eigen::Vector2d(0.0, 0.0125));
    const nlohmann::json jd = io::to_json(delayed);
    EXPECT_EQ(jd.at("input_delays")[1], 0.0125);
    expect_equal(io::mimo_additive_model_from_json(jd, "m.json"), delayed);
  }
  // A rigid-body submodel: R_0 / p^2, written with its integrators.
  std::vector<MimoSubmodel> submodels = two_by_three(false).submodels();
  submodels.push_back(
      MimoSubmodel{Polynomial{1.0}, std::vector<Polynomial>(6, Polynomial{0.3}), 2});
  const MimoAdditiveModel rigid(2, 3, submodels);
  const nlohmann::json j = io::to_json(rigid);
  EXPECT_EQ(j.at("submodels")[2].at("integrators"), 2);
  EXPECT_FALSE(j.at("submodels")[0].contains("integrators"));
  expect_equal(io::mimo_additive_model_from_json(j, "m.json"), rigid);
}

// Found by fuzz_model_json: a numerator read as [0.0] was written [] (the zero polynomial has
// no coefficients), which the reader refuses; ctid must read every model it writes.
TEST(MimoJson, ZeroNumeratorIsWrittenAsZeroAndReadBack) {
  const nlohmann::json document = nlohmann::json::parse(
      R"({"type": "mimo_additive_model", "inputs": 2, "outputs": 1, "submodels": [
          {"denominator_ascending": [1.0, 0.2, 1.0], "numerators_ascending": [[0.0], [0.5]]}]})");
  const MimoAdditiveModel model = io::mimo_additive_model_from_json(document, "zero.json");
  const nlohmann::json written = io::to_json(model);
  EXPECT_EQ(written["submodels"][0]["numerators_ascending"][0], nlohmann::json::array({0.0}));
  const MimoAdditiveModel back = io::mimo_additive_model_from_json(written, "again.json");
  EXPECT_EQ(back.submodels()[0].b[1].coefficients(), model.submodels()[0].b[1].coefficients());
}

TEST(MimoJson, MalformedModelsNameTheField) {
  nlohmann::json j = io::to_json(two_by_three(true));
  j["submodels"][1]["numerators_ascending"].erase(0);
  EXPECT_THAT([&] { io::mimo_additive_model_from_json(j, "m.json"); },
              ThrowsMessage<InvalidArgument>(
                  HasSubstr("m.json: submodels[1].numerators_ascending: has 5 numerators")));
  j = io::to_json(two_by_three(true));
  j["direct"][2] = nlohmann::json::array({1.0});
  EXPECT_THAT([&] { io::mimo_additive_model_from_json(j, "m.json"); },
              ThrowsMessage<InvalidArgument>(HasSubstr("direct: [2] has 1 entries")));
  j = io::to_json(two_by_three(false));
  j["submodels"][0]["denominator_ascending"] = nlohmann::json::array({2.0, 1.0});
  EXPECT_THAT([&] { io::mimo_additive_model_from_json(j, "m.json"); },
              ThrowsMessage<InvalidArgument>(HasSubstr("anti-monic")));
  j = io::to_json(two_by_three(false));
  j["input_delays"] = nlohmann::json::array({0.1});
  EXPECT_THAT([&] { io::mimo_additive_model_from_json(j, "m.json"); },
              ThrowsMessage<InvalidArgument>(
                  HasSubstr("input_delays: has 1 entries; it needs one per input (2)")));
  j["input_delays"] = nlohmann::json::array({0.1, -0.5});
  EXPECT_THAT([&] { io::mimo_additive_model_from_json(j, "m.json"); },
              ThrowsMessage<InvalidArgument>(HasSubstr("input 2: the delay is -0.5 s")));
  j = io::to_json(two_by_three(false));
  j["colour"] = "red";
  EXPECT_THAT([&] { io::mimo_additive_model_from_json(j, "m.json"); },
              ThrowsMessage<InvalidArgument>(HasSubstr("colour")));
}

TEST(MimoJson, EstimationResultRoundTrip) {
  const MimoAdditiveModel truth = two_by_three(false);
  Eigen::MatrixXd u(600, 2);
  for (int k = 0; k < 2; ++k) u.col(k) = white_noise(600, 1.0, 3 + k);
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(600, 3);
  for (int j = 0; j < 3; ++j) {
    for (int k = 0; k < 2; ++k) y.col(j) += simulate(truth.channel(j, k), u.col(k), 0.05);
    y.col(j) += white_noise(600, 0.05, 10 + j);
  }
  const MimoEstimationResult r =
      mimo_srivc(MimoData(0.05, u, y), std::vector<SubmodelOrder>(2, {2, 1, 0}), {}, truth);
  ASSERT_EQ(r.modes.size(), 2u);
  const nlohmann::json j = io::fields_to_json(r);
  MimoEstimationResult back;
  io::fields_from_json(j, back, "r.json");
  expect_equal(*back.model, *r.model);
  EXPECT_EQ(back.termination, r.termination);
  EXPECT_EQ(back.message, r.message);
  EXPECT_EQ(back.fit_percent, r.fit_percent);
  EXPECT_EQ(back.verdict.usable, r.verdict.usable);
  ASSERT_EQ(back.modes.size(), 2u);
  EXPECT_EQ(back.modes[1].shape, r.modes[1].shape);
  EXPECT_EQ(back.modes[1].shape_se_imag, r.modes[1].shape_se_imag);
  EXPECT_EQ(back.modes[0].natural_frequency_se, r.modes[0].natural_frequency_se);
}

}  // namespace
}  // namespace ctid::mimo_json_test
