// `ctid simulate`, `ctid fit` and `ctid structure` with an analog controller, a transfer_function
// C(p) given to
// --controller (decision 0067): the simulated loop is the library's, the fit gives the unstable
// plant from the noise-free record to 1e-8 through clsrivc_continuous, and what it does not take
// is refused in one line.
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/io/csv.h"
#include "ctid/io/json.h"
#include "ctid/simulation/closed_loop.h"

namespace ctid::cli::analog_loop_test {
namespace {

using testing::expect_bad_input;
using ::testing::HasSubstr;

// G = 2 / (1 - 0.5 p + 0.1 p^2), unstable; C = (1 + 0.6 p) / (1 + 0.05 p) holds it.
const char* kPlant = R"({"type": "transfer_function", "numerator_ascending": [2],
  "denominator_ascending": [1, -0.5, 0.1]})";
const char* kController = R"({"type": "transfer_function", "numerator_ascending": [1, 0.6],
  "denominator_ascending": [1, 0.05]})";

class AnalogLoop : public testing::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    plant_ = write("g.json", kPlant);
    controller_ = write("c.json", kController);
    const auto r = ctid({"simulate", "-m", plant_, "--controller", controller_, "-e", "white", "-n",
                         "3000", "-T", "0.02", "-o", "loop.csv"});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_THAT(r.out, HasSubstr("analog closed loop"));
  }
  std::string plant_;
  std::string controller_;
};

TEST_F(AnalogLoop, SimulateWritesTheLibrarysAnalogLoop) {
  const io::CsvTable written = io::read_csv(path("loop.csv"));
  const ClosedLoopSimulation expected = simulate_closed_loop(
      TransferFunction(Polynomial{2.0}, Polynomial{1.0, -0.5, 0.1}),
      TransferFunction(Polynomial{1.0, 0.6}, Polynomial{1.0, 0.05}), written.column("r"), 0.02);
  EXPECT_EQ(written.column("y"), expected.output);
  EXPECT_EQ(written.column("u"), expected.input);
}

TEST_F(AnalogLoop, FitGivesTheUnstablePlantFromTheNoiseFreeRecord) {
  const auto r = ctid({"fit", "loop.csv", "--poles", "2", "--zeros", "0", "--controller",
                       controller_, "-o", "fit.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("clsrivc_continuous"));
  const nlohmann::json result = io::read_json(path("fit.json"));
  EXPECT_EQ(result["estimator"], "clsrivc_continuous");
  EXPECT_EQ(result["loop"], "closed");
  EXPECT_EQ(result["controller"]["type"], "transfer_function");
  const std::vector<double> truth = {-0.5, 0.1, 2.0};
  for (std::size_t i = 0; i < truth.size(); ++i) {
    EXPECT_NEAR(result["parameters"][i].get<double>(), truth[i], 1e-8) << i;
  }
}

// Each candidate is judged by its output from r through the analog loop (its plant is
// unstable, so y - G u would diverge): the true two-pole structure is recommended.
TEST_F(AnalogLoop, StructureRecommendsTheTrueOrderJudgedThroughTheLoop) {
  const auto r = ctid({"structure", "loop.csv", "--poles", "1:3", "--zeros", "0", "--controller",
                       controller_, "-o", "scan.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("recommended: n=2 m=0 ("));
  const nlohmann::json scan = io::read_json(path("scan.json"));
  const nlohmann::json& chosen = scan["fits"][scan["recommended"].get<int>()];
  EXPECT_GT(chosen["validation_fit"].get<double>(), 100.0 - 1e-6);
}

TEST_F(AnalogLoop, WhatTheAnalogFitDoesNotTakeIsRefusedInOneLine) {
  expect_bad_input(ctid({"fit", "loop.csv", "--modes", "1", "--controller", controller_}), "fit",
                   "with a continuous-time controller one unfactored model is fitted");
  expect_bad_input(ctid({"fit", "loop.csv", "--poles", "2", "--zeros", "0", "--controller",
                         controller_, "--input-delay-samples", "2"}),
                   "fit", "a delay in an analog loop is not supported");
  const std::string model_file = write("not_a_controller.json", R"({"type": "additive_model",
      "submodels": [{"numerator_ascending": [1], "denominator_ascending": [1, 1]}]})");
  expect_bad_input(
      ctid({"fit", "loop.csv", "--poles", "2", "--zeros", "0", "--controller", model_file}), "fit",
      "a controller is a \"discrete_transfer_function\" (C_d(q), a digital loop) or a "
      "\"transfer_function\" (C(p), an analog loop)");
  const std::string weak = write("weak.json", R"({"type": "transfer_function",
      "numerator_ascending": [0.1], "denominator_ascending": [1]})");
  expect_bad_input(ctid({"simulate", "-m", plant_, "--controller", weak, "-e", "white", "-n", "100",
                         "-T", "0.02", "-o", "weak.csv"}),
                   "simulate", "the controller does not stabilise the plant");
}

}  // namespace
}  // namespace ctid::cli::analog_loop_test
