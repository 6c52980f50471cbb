// `ctid simulate --irregular` and `ctid validate --irregular` (decision 0053): the model at the
// stamps of the input file as given (jitter, equal stamps, a gap), nothing resampled; a model
// fitted by `ctid fit --irregular` on that noise-free record validates at 100 %; stamps that
// go back, a hold that contradicts the file and what needs a grid are refused in one line.
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/core/additive_model.h"
#include "ctid/io/csv.h"
#include "ctid/io/json.h"
#include "ctid/simulation/stamps.h"

namespace ctid::cli::irregular_stamps_test {
namespace {

using testing::expect_bad_input;
using ::testing::HasSubstr;

// (2 + 0.3 s) / (1 + 0.4 s + 0.25 s^2)
const char* kModel = R"({
  "type": "transfer_function",
  "numerator_ascending": [2, 0.3],
  "denominator_ascending": [1, 0.4, 0.25]
})";

// t,u at stamps 0.05 k ±30 % (seeded), every 40th stamp repeated, stamps 300-329 missing.
std::string input_csv(int n = 900, std::uint64_t seed = 6) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::normal_distribution<double> normal;
  std::string text = "t,u\n";
  char line[100];
  for (int k = 0, written = 0; written < n; ++k) {
    if (k >= 300 && k < 330) continue;
    const double t = 0.05 * (k + (k == 0 ? 0.0 : jitter(rng)));
    for (int copy = 0; copy < (k % 40 == 20 ? 2 : 1) && written < n; ++copy, ++written) {
      std::snprintf(line, sizeof line, "%.17g,%.17g\n", t, normal(rng));
      text += line;
    }
  }
  return text;
}

class IrregularStamps : public testing::CliTest {};

TEST_F(IrregularStamps, SimulateWritesTheModelAtTheStampsAsGiven) {
  const std::string model = write("g.json", kModel);
  const std::string in = write("in.csv", input_csv());
  for (const char* hold : {"zoh", "foh"}) {
    const std::string out = std::string(hold) + ".csv";
    const auto r =
        ctid({"simulate", "-m", model, "-i", in, "--irregular", "--hold", hold, "-o", out});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_THAT(r.out, HasSubstr("wrote 900 samples (t,u,y at the time stamps of"));
    EXPECT_THAT(r.out, HasSubstr("22 duplicates"));
    const io::CsvTable given = io::read_csv(in);
    const io::CsvTable written = io::read_csv(path(out));
    ASSERT_EQ(written.rows(), 900);
    EXPECT_EQ(written.column("t"), given.column("t"));  // the stamps, bit for bit
    EXPECT_EQ(written.column("u"), given.column("u"));
    const Hold h = std::string(hold) == "foh" ? Hold::first_order_hold : Hold::zero_order_hold;
    EXPECT_EQ(written.declaration("input_hold") != nullptr, h == Hold::first_order_hold);
    const TransferFunction g(Polynomial{2.0, 0.3}, Polynomial{1.0, 0.4, 0.25});
    const Eigen::VectorXd y = simulate_on_stamps(g, given.column("t"), given.column("u"), h);
    EXPECT_EQ(written.column("y"), y) << hold;
  }
}

TEST_F(IrregularStamps, AModelWithAnInputDelayIsSimulatedAndValidatedOnTheStamps) {
  const std::string model = write("g.json", R"({"type": "transfer_function",
      "numerator_ascending": [2, 0.3], "denominator_ascending": [1, 0.4, 0.25],
      "input_delay": 0.137})");
  const std::string in = write("in.csv", input_csv(400));
  ASSERT_EQ(ctid({"simulate", "-m", model, "-i", in, "--irregular", "-o", "d.csv"}).status, 0);
  const io::CsvTable given = io::read_csv(in);
  const TransferFunction g(Polynomial{2.0, 0.3}, Polynomial{1.0, 0.4, 0.25}, 0.137);
  EXPECT_EQ(io::read_csv(path("d.csv")).column("y"),
            simulate_on_stamps(g, given.column("t"), given.column("u"), Hold::zero_order_hold));
  const auto v = ctid({"validate", model, "d.csv", "--irregular", "-o", "r.json"});
  ASSERT_EQ(v.status, 0) << v.err;
  EXPECT_NEAR(io::read_json(path("r.json")).at("fit_percent").get<double>(), 100.0, 1e-9);
}

TEST_F(IrregularStamps, AModelFittedOnTheStampsValidatesAtAHundredPercent) {
  const std::string model = write("g.json", kModel);
  const std::string in = write("in.csv", input_csv());
  for (const char* hold : {"zoh", "foh"}) {
    const std::string data = std::string(hold) + ".csv";
    ASSERT_EQ(
        ctid({"simulate", "-m", model, "-i", in, "--irregular", "--hold", hold, "-o", data}).status,
        0);
    const std::string fit = std::string(hold) + "_fit.json";
    const auto f = ctid({"fit", data, "--irregular", "--poles", "2", "--zeros", "1", "-o", fit});
    ASSERT_EQ(f.status, 0) << f.err << f.out;
    const std::string report = std::string(hold) + "_report.json";
    const auto v = ctid({"validate", fit, data, "--irregular", "-o", report});
    ASSERT_EQ(v.status, 0) << v.err;
    EXPECT_THAT(v.out, HasSubstr("irregular time stamps, 22 duplicates"));
    EXPECT_THAT(v.out,
                HasSubstr(std::string("input ") +
                          (std::string(hold) == "foh" ? "first_order_hold" : "zero_order_hold")));
    const nlohmann::json j = io::read_json(path(report));
    EXPECT_NEAR(j.at("fit_percent").get<double>(), 100.0, 1e-6) << hold;
    EXPECT_EQ(j.at("window_samples").get<int>(), 900);
    EXPECT_EQ(j.at("data").at("time_stamps"), "irregular");
    EXPECT_EQ(j.at("data").at("duplicate_stamps").get<int>(), 22);
    EXPECT_TRUE(j.at("fit_estimated_state").is_null());
  }
}

TEST_F(IrregularStamps, StampsThatGoBackAreOneLineNamingTheStamp) {
  const std::string model = write("g.json", kModel);
  std::string text = input_csv(60);
  text += "0.5,1\n";  // stamp 60 goes back to 0.5 s
  const std::string in = write("back.csv", text);
  expect_bad_input(ctid({"simulate", "-m", model, "-i", in, "--irregular", "-o", "y.csv"}),
                   "simulate", "time stamp 60 (0.5 s) goes back before stamp 59");
  const std::string data = write("back_y.csv", "t,u,y\n0,1,0\n0.1,1,0.2\n0.05,1,0.3\n0.2,1,0.4\n");
  expect_bad_input(ctid({"validate", model, data, "--irregular"}), "validate",
                   "time stamp 2 (0.05 s) goes back before stamp 1 (0.1 s)");
}

TEST_F(IrregularStamps, AHoldThatContradictsTheFileIsRefused) {
  const std::string model = write("g.json", kModel);
  const std::string in = write("in.csv", input_csv(200));
  ASSERT_EQ(ctid({"simulate", "-m", model, "-i", in, "--irregular", "--hold", "foh", "-o", "d.csv"})
                .status,
            0);
  expect_bad_input(ctid({"validate", model, "d.csv", "--irregular", "--input-hold", "zoh"}),
                   "validate", "--input-hold zoh contradicts");
}

TEST_F(IrregularStamps, WhatNeedsAGridIsRefusedNamingTheFlag) {
  const std::string model = write("g.json", kModel);
  const std::string in = write("in.csv", input_csv(200));
  const std::vector<std::string> sim = {"simulate", "-m", model, "--irregular", "-o", "y.csv"};
  auto with = [&](std::vector<std::string> base, std::vector<std::string> extra) {
    base.insert(base.end(), extra.begin(), extra.end());
    return ctid(base);
  };
  expect_bad_input(with(sim, {"-e", "white", "-T", "0.1"}), "simulate",
                   "--excitation does not go with --irregular");
  expect_bad_input(with(sim, {"-i", in, "-T", "0.1"}), "simulate",
                   "--sample-time does not go with --irregular");
  const std::string controller = write("c.json", R"({"type": "discrete_transfer_function",
      "sample_time": 0.05, "numerator_ascending": [1], "denominator_ascending": [1]})");
  expect_bad_input(with(sim, {"-i", in, "-c", controller}), "simulate",
                   "--controller does not go with --irregular");
  expect_bad_input(
      ctid({"simulate", "-m", example("gonzalez_6_2_plant.json"), "-i", in, "-o", "u.csv"}),
      "simulate", "not uniform");
  ASSERT_EQ(ctid({"simulate", "-m", model, "-i", in, "--irregular", "-o", "d.csv"}).status, 0);
  const std::vector<std::string> val = {"validate", model, "d.csv", "--irregular"};
  expect_bad_input(with(val, {"--initial-state", "estimate"}), "validate",
                   "--initial-state estimate does not go with --irregular");
  expect_bad_input(with(val, {"--resample", "0.05"}), "validate",
                   "--resample does not go with --irregular");
  expect_bad_input(with(val, {model}), "validate", "several models does not go with --irregular");
}

}  // namespace
}  // namespace ctid::cli::irregular_stamps_test
