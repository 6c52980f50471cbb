// `ctid simulate` with a delayed_feedback_loop model: the CSV equals simulate_delayed on the
// same input, `ctid feedback` recovers F and H from it, and misuse is one line with exit 2.
#include <cmath>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/io/excitation_spec.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"
#include "ctid/io/sampled_data_csv.h"
#include "ctid/simulation/delayed_feedback.h"
#include "support/sanitizers.h"

namespace ctid::cli::simulate_loop_test {
namespace {

using testing::CliTest;
using ::testing::HasSubstr;
using testing::line_count;
using ::testing::StartsWith;

// 30 s at h = 0.05 s: two periods of 15 s, every line from 1/15 Hz to 0.6 Hz (9 lines, up to
// 3.8 rad/s), the informative record of docs/algorithms/feedback-delay.md.
io::ExcitationSpec multisine_spec() {
  io::ExcitationSpec spec;
  spec.kind = io::ExcitationKind::multisine;
  spec.samples = 600;
  spec.sample_time = 0.05;
  spec.periods = 2;
  spec.max_frequency_hz = 0.6;
  return spec;
}

const std::vector<std::string> kMultisineFlags = {
    "-e", "multisine", "-n", "600", "-T", "0.05", "--periods", "2", "--max-frequency-hz", "0.6"};

std::vector<std::string> simulate_args(const std::string& model, const std::string& out,
                                       std::vector<std::string> extra = {}) {
  std::vector<std::string> args = {"simulate", "-m", model, "-o", out, "-q"};
  args.insert(args.end(), kMultisineFlags.begin(), kMultisineFlags.end());
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

DelayedFeedbackLoop shipped_loop() {
  return io::delayed_feedback_loop_from_json(
      io::read_json(std::string(CTID_SOURCE_DIR) + "/examples/models/de_iuliis_section4_loop.json"),
      "shipped");
}

Eigen::VectorXd reference_output(Hold hold) {
  return simulate_delayed(to_delayed_state_space(shipped_loop()),
                          io::generate_excitation(multisine_spec()), 0.05, hold,
                          DelayedSimulationOptions{4});
}

void expect_bad_input(const testing::RunResult& r, const std::string& what) {
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_THAT(r.err, StartsWith("ctid simulate: error: "));
  EXPECT_THAT(r.err, HasSubstr(what));
}

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST_F(CliTest, SimulateLoopEqualsSimulateDelayedAndFeedbackRecoversIt) {
  CTID_SKIP_UNDER_SANITIZERS(
      "CliTest.FeedbackRecoversTheLoopAndWritesJson runs ctid feedback; the other simulate-loop "
      "tests run the simulation");
  const std::string model = example("de_iuliis_section4_loop.json");
  const std::string data = path("d.csv").string();
  const auto sim = ctid(simulate_args(model, data, {"--hold", "foh"}));
  ASSERT_EQ(sim.status, 0) << sim.err;
  const SampledData d = io::read_sampled_data(data);
  const Eigen::VectorXd y = reference_output(Hold::first_order_hold);
  ASSERT_EQ(d.output().size(), 600);
  EXPECT_EQ(d.input(), io::generate_excitation(multisine_spec()));
  EXPECT_LT((d.output() - y).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(y.cwiseAbs().maxCoeff(), 0.1);

  const auto fb = ctid({"feedback", data, "--forward-order", "3", "--feedback-order", "3",
                        "--delay", "0.5", "--hold", "foh", "-o", path("r.json").string(), "-q"});
  ASSERT_EQ(fb.status, 0) << fb.err;
  const nlohmann::json result = io::read_json(path("r.json"));
  const DelayedFeedbackLoop truth = shipped_loop();  // monic denominators already
  const auto expect_close = [](const nlohmann::json& got, const Polynomial& want,
                               const std::string& what) {
    ASSERT_EQ(got.size(), static_cast<std::size_t>(want.coefficients().size())) << what;
    for (std::size_t k = 0; k < got.size(); ++k) {
      const double w = want.coefficients()(static_cast<Eigen::Index>(k));
      EXPECT_NEAR(got[k].get<double>(), w, 1e-5 * std::abs(w)) << what << "[" << k << "]";
    }
  };
  // The delayed_feedback_result document (io/feedback_result_json.h).
  const nlohmann::json& loop = result["identification"]["loop"];
  expect_close(loop["forward"]["numerator_ascending"], truth.forward.numerator(), "F numerator");
  expect_close(loop["forward"]["denominator_ascending"], truth.forward.denominator(),
               "F denominator");
  expect_close(loop["feedback"]["numerator_ascending"], truth.feedback.numerator(), "H numerator");
  expect_close(loop["feedback"]["denominator_ascending"], truth.feedback.denominator(),
               "H denominator");

  // ctid validate judges the loop of the result and the true loop on the same record: both
  // fit the noise-free data, the true loop exactly (the same simulation as ctid simulate).
  const auto truth_report = ctid({"validate", model, data, "-o", path("v1.json").string(), "-q"});
  ASSERT_EQ(truth_report.status, 0) << truth_report.err;
  EXPECT_DOUBLE_EQ(io::read_json(path("v1.json"))["fit_percent"].get<double>(), 100.0);
  const auto fitted_report =
      ctid({"validate", path("r.json").string(), data, "-o", path("v3.json").string()});
  ASSERT_EQ(fitted_report.status, 0) << fitted_report.err;
  EXPECT_THAT(fitted_report.out, ::testing::HasSubstr("whiteness"));
  EXPECT_GT(io::read_json(path("v3.json"))["fit_percent"].get<double>(), 99.99);
  const auto zoh =
      ctid({"validate", model, data, "--hold", "zoh", "-o", path("v2.json").string(), "-q"});
  ASSERT_EQ(zoh.status, 0) << zoh.err;
  EXPECT_LT(io::read_json(path("v2.json"))["fit_percent"].get<double>(), 99.9);
  const auto plot = ctid({"validate", model, data, "--plot", path("figures").string()});
  EXPECT_EQ(plot.status, 2);
  EXPECT_THAT(plot.err, ::testing::HasSubstr("holds a closed loop with delayed feedback"));
}

TEST_F(CliTest, SimulateLoopHoldAndNoiseToSignalRatio) {
  const std::string model = example("de_iuliis_section4_loop.json");
  const auto zoh = ctid(simulate_args(model, path("zoh.csv").string(), {"--hold", "zoh"}));
  ASSERT_EQ(zoh.status, 0) << zoh.err;
  const Eigen::VectorXd y0 = reference_output(Hold::zero_order_hold);
  const Eigen::VectorXd y_zoh = io::read_sampled_data(path("zoh.csv")).output();
  EXPECT_LT((y_zoh - y0).cwiseAbs().maxCoeff(), 1e-12);
  // The hold matters: foh and zoh differ by far more than the simulation error.
  EXPECT_GT((reference_output(Hold::first_order_hold) - y0).cwiseAbs().maxCoeff(), 1e-3);

  const auto noisy = ctid(simulate_args(model, path("nsr.csv").string(),
                                        {"--hold", "zoh", "--nsr", "0.05", "--noise-seed", "9"}));
  ASSERT_EQ(noisy.status, 0) << noisy.err;
  const Eigen::VectorXd y = io::read_sampled_data(path("nsr.csv")).output();
  EXPECT_NEAR((y - y0).cwiseAbs().mean() / y0.cwiseAbs().mean(), 0.05, 1e-9);
}

TEST_F(CliTest, SimulateLoopMisuseIsOneLineAndExitTwo) {
  const std::string model = example("de_iuliis_section4_loop.json");
  const std::string out = path("out.csv").string();
  expect_bad_input(ctid(simulate_args(model, out, {"-c", example("gonzalez_6_2_pid.json")})),
                   "--controller does not apply to");
  expect_bad_input(ctid(simulate_args(model, out,
                                      {"--noise-filter", example("gonzalez_6_1_noise_filter.json"),
                                       "--noise-std", "0.1"})),
                   "--noise-filter does not apply to");
  // Loop-only flags on an ordinary model; foh in closed loop (the DAC holds the input).
  expect_bad_input(ctid(simulate_args(example("gonzalez_6_2_plant.json"), out,
                                      {"--hold", "foh", "-c", example("gonzalez_6_2_pid.json")})),
                   "in closed loop the controller's output is held (zoh)");
  expect_bad_input(ctid(simulate_args(example("gonzalez_6_2_plant.json"), out, {"--nsr", "0.1"})),
                   "--nsr applies to a delayed_feedback_loop model only");

  const std::string tf_h = R"({"type": "transfer_function", "numerator_ascending": [1, 5, 1],
      "denominator_ascending": [2, 2, 3, 1]})";
  {
    std::ofstream(path("biproper.json"))
        << R"({"type": "delayed_feedback_loop", "delay": 0.5, "feedback": )" << tf_h
        << R"(, "forward": {"type": "transfer_function", "numerator_ascending": [2, 1, 2, 1],
            "denominator_ascending": [3, 2, 3, 1]}})";
    std::ofstream(path("malformed.json"))
        << R"({"type": "delayed_feedback_loop", "delay": 0.5, "forward": )" << tf_h << "}";
  }
  expect_bad_input(ctid(simulate_args(path("biproper.json").string(), out)),
                   path("biproper.json").string() +
                       ": delayed feedback loop: DelayedFeedbackLoop: forward F must be strictly "
                       "proper");
  expect_bad_input(ctid(simulate_args(path("malformed.json").string(), out)),
                   path("malformed.json").string() + ": feedback: required field is missing");
  EXPECT_FALSE(std::filesystem::exists(out));

  // An existing output is refused without --force and left as it was.
  std::ofstream(path("keep.csv")) << "mine\n";
  expect_bad_input(ctid(simulate_args(model, path("keep.csv").string())),
                   "file exists; pass --force");
  EXPECT_EQ(read_text(path("keep.csv")), "mine\n");
  EXPECT_EQ(ctid(simulate_args(model, path("keep.csv").string(), {"--force"})).status, 0);
  EXPECT_NE(read_text(path("keep.csv")), "mine\n");
}

}  // namespace
}  // namespace ctid::cli::simulate_loop_test
