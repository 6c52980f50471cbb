// `ctid fit --noise-model` (decision 0056): RIVC's estimator name, its summary line and the
// result document's noise model; `none` writes exactly what no flag writes; a bad word, a
// record too short for the orders and several outputs are refused in one line.
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/core/additive_model.h"
#include "ctid/io/json.h"
#include "ctid/io/report_json.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"

namespace ctid::cli::noise_model_test {
namespace {

using testing::expect_bad_input;
using ::testing::HasSubstr;

// t,u,y of 2 / (1 + 0.5 p + p^2) with AR(1) noise, h = 0.05.
std::string record_csv(int n = 1500) {
  const AdditiveModel g({{Polynomial({1.0, 0.5, 1.0}), Polynomial({2.0}), 0}});
  const Eigen::VectorXd u = white_noise(n, 1.0, 3);
  const DiscreteTransferFunction h(Polynomial({0.0, 1.0}), Polynomial({-0.95, 1.0}), 0.05);
  return testing::tuy_csv(0.05, u, simulate(g, u, 0.05) + colored_noise(h, n, 0.0004, 4));
}

class NoiseModelFlag : public testing::CliTest {};

TEST_F(NoiseModelFlag, RivcWritesItsNoiseModelAndNoneIsSrivc) {
  const std::string data = write("bj.csv", record_csv());
  const auto r = ctid(
      {"fit", data, "--poles", "2", "--zeros", "0", "--noise-model", "1,0", "-o", "rivc.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("ctid fit: rivc on"));
  EXPECT_THAT(r.out, HasSubstr("noise model: ARMA(1, 0), D v = C e with d_1.. = [-0.9"));
  const nlohmann::json doc = io::read_json(path("rivc.json"));
  EXPECT_EQ(doc["estimator"], "rivc");
  ASSERT_TRUE(doc["noise_model"].is_object());
  EXPECT_EQ(doc["noise_model"]["ar"].size(), 2u);
  EXPECT_EQ(doc["noise_model"]["spectrum"].size(),
            doc["noise_model"]["spectrum_frequencies"].size());

  const auto plain = ctid({"fit", data, "--poles", "2", "--zeros", "0", "-o", "plain.json"});
  const auto none = ctid(
      {"fit", data, "--poles", "2", "--zeros", "0", "--noise-model", "none", "-o", "none.json"});
  ASSERT_EQ(plain.status, 0) << plain.err;
  ASSERT_EQ(none.status, 0) << none.err;
  EXPECT_EQ(plain.out, none.out);
  EXPECT_EQ(testing::slurp(path("plain.json")), testing::slurp(path("none.json")));
  EXPECT_TRUE(io::read_json(path("plain.json"))["noise_model"].is_null());
}

TEST_F(NoiseModelFlag, ValidateHorizonPredictsWithTheResultsNoiseModel) {
  const std::string data = write("bj.csv", record_csv());
  ASSERT_EQ(ctid({"fit", data, "--poles", "2", "--zeros", "0", "--noise-model", "1,0", "-o",
                  "rivc.json", "-q"})
                .status,
            0);
  const auto r = ctid({"validate", "rivc.json", data, "--horizon", "1", "-o", "v.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("1-step-ahead prediction (noise model ARMA(1, 0)): fit "));
  const nlohmann::json v = io::read_json(path("v.json"));
  EXPECT_EQ(v["prediction"]["horizon"], 1);
  EXPECT_GT(v["prediction"]["fit_percent"].get<double>(),
            v["prediction"]["simulation_fit_percent"].get<double>());
  EXPECT_FALSE(v["prediction"].contains("prediction"));
  // The report reads back with its prediction (ctid report, read_result).
  EXPECT_EQ(io::validation_report_from_json(v, "v.json").window_samples, 1500);
  ASSERT_EQ(ctid({"fit", data, "--poles", "2", "--zeros", "0", "-o", "plain.json", "-q"}).status,
            0);
  expect_bad_input(ctid({"validate", "plain.json", data, "--horizon", "2"}), "validate",
                   "--horizon predicts with a noise model; plain.json has none");
  expect_bad_input(ctid({"validate", "rivc.json", data, "--horizon", "5000"}), "validate",
                   "the horizon 5000 must be at least 1 and below the record's 1500 samples");
  expect_bad_input(ctid({"validate", "rivc.json", data, "plain.json", "--horizon", "2"}),
                   "validate", "--horizon predicts one model's output");
  expect_bad_input(ctid({"validate", "rivc.json", data, "--horizon", "2", "--window", "10:"}),
                   "validate", "--horizon scores the prediction on the whole record from rest");
}

TEST_F(NoiseModelFlag, BadWordsShortRecordsAndSeveralOutputsAreRefused) {
  const std::string data = write("bj.csv", record_csv());
  expect_bad_input(ctid({"fit", data, "--poles", "2", "--zeros", "0", "--noise-model", "2"}), "fit",
                   "--noise-model: the noise model '2' is not P,Q");
  const std::string short_data = write("short.csv", record_csv(60));
  expect_bad_input(
      ctid({"fit", short_data, "--poles", "2", "--zeros", "0", "--noise-model", "4,4"}), "fit",
      "cannot hold an ARMA(4, 4) noise model");
  expect_bad_input(
      ctid({"fit", data, "--output-columns", "y,y", "--modes", "1", "--noise-model", "1,0"}), "fit",
      "--noise-model is not available with --input-columns / --output-columns");
}

}  // namespace
}  // namespace ctid::cli::noise_model_test
