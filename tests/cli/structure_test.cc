// `ctid structure` run as a user would: on the noise-free Section 6.1 record (four modes) a
// scan over three to five modes recommends four, prints its table and writes the scan; bad
// ranges exit 2 with one line.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <variant>
#include <vector>

#include "cli/run_ctid.h"
#include "ctid/io/documents.h"
#include "ctid/io/json.h"
#include "support/sanitizers.h"

namespace ctid::cli::structure_test {
namespace {

using ::testing::HasSubstr;

class StructureCommand : public testing::Section61Test {};

void expect_bad_input(const testing::RunResult& r, const std::string& fragment) {
  testing::expect_bad_input(r, "structure", fragment);
}

TEST_F(StructureCommand, RecommendsTheTrueNumberOfModesAndWritesTheScan) {
  const auto r = ctid({"structure", "d.csv", "--modes", "3:5", "-o", "s.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("3 structures on d.csv (5735 samples fitted, 2457 held out)"));
  EXPECT_THAT(r.out, HasSubstr(" * 4 modes"));
  EXPECT_THAT(r.out, HasSubstr("recommended: 4 modes (fewest parameters"));
  const nlohmann::json j = io::read_json(path("s.json"));
  EXPECT_EQ(j.at("type"), "structure_scan_result");
  ASSERT_EQ(j.at("fits").size(), 3U);
  EXPECT_EQ(j.at("recommended"), 1);
  EXPECT_GT(j.at("fits")[1].at("validation_fit").get<double>(), 99.99);
  EXPECT_TRUE(j.at("fits")[1].at("usable").get<bool>());
  EXPECT_FALSE(j.at("stabilisation").empty());
  // The document reads back as the scan, with the context ("data") set aside.
  const io::ResultDocument read = io::read_result(path("s.json"));
  const auto* scan = std::get_if<StructureScanResult>(&read);
  ASSERT_NE(scan, nullptr);
  EXPECT_EQ(scan->recommended, 1);
  ASSERT_EQ(scan->fits.size(), 3U);
  EXPECT_EQ(scan->fits[1].structure.orders.size(), 4U);
  EXPECT_EQ(scan->fits[1].transfer_function.denominator().degree(), 8);
}

TEST_F(StructureCommand, ScansIntegratorsZerosAndTheDelay) {
  // 0.3696 e^{-3h s} / (s (s + 2.14)), h = 0.01 s, noise-free: over 0-2 poles with or without
  // an integrator (a pure integrator included), 0 or 1 zero and delays 0-5, the scan
  // recommends the true K/(p (1 + a p)) and each candidate found the 3-sample delay.
  write("g.json", R"({"type": "transfer_function", "numerator_ascending": [0.3696],
    "denominator_ascending": [0, 2.14, 1], "input_delay": 0.03})");
  const auto s = ctid({"simulate", "-m", "g.json", "--excitation", "prbs", "--samples", "2000",
                       "--samples-per-bit", "5", "-T", "0.01", "-o", "i.csv", "-q"});
  ASSERT_EQ(s.status, 0) << s.err;
  const auto r = ctid({"structure", "i.csv", "--poles", "0:2", "--integrators", "0:1", "--zeros",
                       "0:1", "--delay-scan-samples", "0:5", "--detrend", "none", "-o", "s.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("n=0 m=0 l=1"));
  EXPECT_THAT(r.out, HasSubstr("recommended: n=1 m=0 l=1"));
  const nlohmann::json j = io::read_json(path("s.json"));
  // (n, l) in {(0,1), (1,0), (1,1), (2,0), (2,1)}, each with m = 0 and m = 1: 10 structures.
  EXPECT_EQ(j.at("fits").size(), 10U);
  expect_bad_input(ctid({"structure", "i.csv", "--poles", "1:2", "--input-delay-samples", "1",
                         "--delay-scan-samples", "0:3"}),
                   "give --input-delay-samples or --delay-scan-samples, not both");
  expect_bad_input(ctid({"structure", "i.csv", "--poles", "0:2"}), "integers >= 1");
  expect_bad_input(ctid({"structure", "i.csv", "--poles", "1:2", "--initial-conditions", "x"}),
                   "--initial-conditions");
}

TEST_F(StructureCommand, BadRangesExitTwoWithOneLine) {
  expect_bad_input(ctid({"structure", "d.csv", "--modes", "3:1"}), "MAX is below MIN");
  expect_bad_input(ctid({"structure", "d.csv", "--modes", "x"}), "expected MIN:MAX");
  expect_bad_input(ctid({"structure", "d.csv", "--modes", "1:2", "--poles", "1:2"}),
                   "give one range");
  expect_bad_input(ctid({"structure", "d.csv", "--poles", "2:3", "--zeros", "5"}),
                   "an improper model");
  expect_bad_input(ctid({"structure", "d.csv", "--modes", "1:2", "--validation-fraction", "2"}),
                   "--validation-fraction is 2");
}

// Several inputs and outputs (decision 0064): mode counts of the shared-pole fit on the measured
// flexible structure, the table, the document and its diagram; SISO-only flags are refused.
TEST_F(StructureCommand, SeveralChannelsScanModeCounts) {
  const std::string data =
      std::string(CTID_SOURCE_DIR) + "/data/daisy_flexible_structure/flexible_structure.csv";
  const std::vector<std::string> channels = {"--time-column",    "t_s",
                                             "--input-columns",  "u1_force:u2_force",
                                             "--output-columns", "y1_acc:y28_acc"};
  std::vector<std::string> refused = {"structure", data, "--modes", "2:3", "--poles", "2:3"};
  refused.insert(refused.end(), channels.begin(), channels.end());
  expect_bad_input(ctid(refused), "--poles is for one input and output");
  std::vector<std::string> no_modes = {"structure", data};
  no_modes.insert(no_modes.end(), channels.begin(), channels.end());
  expect_bad_input(ctid(no_modes), "with --input-columns / --output-columns give --modes MIN:MAX");
  // A one-channel estimator flag is refused, not ignored; a shared one is taken.
  std::vector<std::string> history = {"structure", data, "--modes", "2:3", "--history"};
  history.insert(history.end(), channels.begin(), channels.end());
  expect_bad_input(ctid(history), "--history is for one input and output");
  std::vector<std::string> relocate = {"structure", data, "--modes", "2:3", "--relocate-modes"};
  relocate.insert(relocate.end(), channels.begin(), channels.end());
  expect_bad_input(ctid(relocate), "--relocate-modes is for one input and output");
  // And the other way: a several-channel flag on one channel.
  expect_bad_input(ctid({"structure", data, "--time-column", "t_s", "--input-column", "u1_force",
                         "--output-column", "y1_acc", "--modes", "1:2", "--rank-one"}),
                   "--rank-one goes with --input-columns / --output-columns");
  CTID_SKIP_UNDER_SANITIZERS(
      "MimoStructureScan.TwoModesAreRecommendedAndStableInTheDiagram runs the scan itself");
  std::vector<std::string> args = {"structure", data, "--modes", "6:7", "--direct", "--detrend",
                                   "mean", "--decimate", "2",
                                   // a flag the two estimators share: taken (its default value)
                                   "--max-iterations", "100", "-o", "mimo.json"};
  args.insert(args.end(), channels.begin(), channels.end());
  const auto r = ctid(args);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("ctid structure: 2 mode counts on"));
  EXPECT_THAT(r.out, HasSubstr("(2 inputs, 28 outputs; 2984 samples fitted, 1278 held out)"));
  EXPECT_THAT(r.out, HasSubstr("recommended: 7 modes"));
  const auto doc = io::read_result(path("mimo.json"));
  const auto* scan = std::get_if<MimoStructureScanResult>(&doc);
  ASSERT_NE(scan, nullptr);
  ASSERT_EQ(scan->fits.size(), 2u);
  EXPECT_EQ(scan->fits[1].modes, 7);
  EXPECT_EQ(scan->fits[1].validation_fit.size(), 28);
  EXPECT_FALSE(scan->stabilisation.empty());
}

// A digital loop, a discrete PI controller around 2 / ((p + 1)(p + 3)) written by `ctid
// simulate --controller`: with the controller, each candidate is judged through the loop from r
// (decision 0070) and the true order is recommended, its held-out end fitted exactly.
class DigitalLoopStructure : public testing::CliTest {
 protected:
  // Writes the loop's record, noise-free, to loop.csv; returns the controller file.
  std::string simulate_loop() {
    const std::string plant = write("g.json", R"({"type": "transfer_function",
        "numerator_ascending": [2], "denominator_ascending": [3, 4, 1]})");
    const std::string controller = write("c.json", R"({"type": "discrete_transfer_function",
        "numerator_ascending": [-1.6, 1.64], "denominator_ascending": [-1, 1],
        "sample_time": 0.02})");
    const auto sim = ctid({"simulate", "-m", plant, "--controller", controller, "-e", "white", "-n",
                           "3000", "-T", "0.02", "-o", "loop.csv"});
    EXPECT_EQ(sim.status, 0) << sim.err;
    return controller;
  }
};

TEST_F(DigitalLoopStructure, RecommendsTheTrueOrderJudgedThroughTheLoop) {
  const std::string controller = simulate_loop();
  const auto r = ctid({"structure", "loop.csv", "--poles", "1:3", "--zeros", "0", "--controller",
                       controller, "-o", "scan.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("recommended: n=2 m=0 ("));
  const nlohmann::json scan = io::read_json(path("scan.json"));
  const nlohmann::json& chosen = scan["fits"][scan["recommended"].get<int>()];
  EXPECT_GT(chosen["validation_fit"].get<double>(), 100.0 - 1e-6);
}

// The same loop with the controller unknown: --two-stage fits r -> u, then every structure's
// plant from the simulated input, and scores it from that input (decision 0071); noise-free,
// the true order is recommended and fits the held-out end exactly. --two-stage with a
// controller, or with several channels, is refused in one line.
TEST_F(DigitalLoopStructure, TwoStageRecommendsTheTrueOrderWithoutTheController) {
  const std::string controller = simulate_loop();
  const auto r = ctid({"structure", "loop.csv", "--poles", "1:3", "--zeros", "0", "--two-stage",
                       "--sensitivity-model", "rational", "-o", "scan.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("recommended: n=2 m=0 ("));
  const nlohmann::json scan = io::read_json(path("scan.json"));
  const nlohmann::json& chosen = scan["fits"][scan["recommended"].get<int>()];
  EXPECT_GT(chosen["validation_fit"].get<double>(), 100.0 - 1e-6);

  const auto both =
      ctid({"structure", "loop.csv", "--poles", "1:3", "--two-stage", "--controller", controller});
  EXPECT_EQ(both.status, 2);
  EXPECT_THAT(both.err, HasSubstr("--controller excludes --two-stage"));
  const auto mimo = ctid({"structure", "loop.csv", "--input-columns", "u", "--output-columns", "y",
                          "--modes", "1:2", "--two-stage"});
  EXPECT_EQ(mimo.status, 2);
  EXPECT_THAT(mimo.err, HasSubstr("--two-stage is for one input and output"));
}

}  // namespace
}  // namespace ctid::cli::structure_test
