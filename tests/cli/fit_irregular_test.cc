// `ctid fit --irregular` (docs/decisions/0034): a CSV whose time column has ±30 % jitter,
// duplicate stamps and missing samples is fitted on its stamps as logged, exactly when it is
// noise-free and the input hold is declared right (--input-hold zoh / foh); what the estimator
// does not take is refused with one line naming the flag.
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/core/additive_model.h"
#include "ctid/io/json.h"
#include "ctid/simulation/discretization.h"

namespace ctid::cli::fit_irregular_test {
namespace {

using testing::expect_bad_input;
using ::testing::HasSubstr;

// theta = [a1 a2 b0 b1] of (2 + 0.3 p) / (1 + 0.4 p + 0.25 p^2).
Eigen::VectorXd true_parameters() {
  Eigen::VectorXd theta(4);
  theta << 0.4, 0.25, 2.0, 0.3;
  return theta;
}

// t,u,y of the system at stamps k 0.05 s ±30 % (1 % missing, 1 % repeated), u random and
// continued by `hold`, y exact on each interval, printed to 17 digits.
std::string jittered_csv(Hold hold, int n = 1200, std::uint64_t seed = 3) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> chance(0.0, 1.0);
  std::normal_distribution<double> normal;
  std::vector<double> t;
  for (int k = 0; static_cast<int>(t.size()) < n; ++k) {
    if (k > 0 && chance(rng) < 0.01) continue;
    t.push_back(0.05 * k + 0.015 * unit(rng));
  }
  for (int k = 1; k + 1 < n; ++k) {
    if (chance(rng) < 0.01) t[static_cast<size_t>(k)] = t[static_cast<size_t>(k - 1)];
  }
  const StateSpace ss = AdditiveModel::from_parameters({SubmodelOrder{2, 1, 0}}, true_parameters())
                            .to_transfer_function()
                            .to_state_space();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(ss.a.rows());
  std::string text = "t,u,y\n";
  double previous = 0.0;
  char line[160];
  for (int k = 0; k < n; ++k) {
    const double u = normal(rng);
    const auto at = static_cast<size_t>(k);
    if (k > 0 && t[at] > t[at - 1]) {
      const double h = t[at] - t[at - 1];
      if (hold == Hold::zero_order_hold) {
        const ZohDiscretization d = discretize_zoh(ss.a, ss.b, h);
        x = d.phi * x + d.gamma.col(0) * previous;
      } else {
        const FohDiscretization d = discretize_foh(ss.a, ss.b, h);
        x = d.phi * x + d.gamma0.col(0) * previous + d.gamma1.col(0) * u;
      }
    }
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g\n", t[at], u, ss.c.dot(x) + ss.d * u);
    text += line;
    previous = u;
  }
  return text;
}

double relative_error(const nlohmann::json& parameters) {
  double worst = 0.0;
  const Eigen::VectorXd theta = true_parameters();
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    const double value = parameters[static_cast<size_t>(i)];
    worst = std::max(worst, std::abs(value - theta(i)) / std::abs(theta(i)));
  }
  return worst;
}

class FitIrregular : public testing::CliTest {};

TEST_F(FitIrregular, NoiseFreeJitteredRecordIsFittedExactlyWithTheDeclaredHold) {
  for (const char* hold : {"zoh", "foh"}) {
    const std::string csv = write(
        std::string(hold) + ".csv",
        jittered_csv(std::string(hold) == "zoh" ? Hold::zero_order_hold : Hold::first_order_hold));
    const std::string out = std::string(hold) + ".json";
    const auto r = ctid({"fit", csv, "--irregular", "--input-hold", hold, "--poles", "2", "--zeros",
                         "1", "-o", out});
    ASSERT_EQ(r.status, 0) << r.err << r.out;
    EXPECT_THAT(r.out, HasSubstr("ctid fit: srivc_irregular on"));
    EXPECT_THAT(r.out, HasSubstr("time stamps: irregular"));
    const nlohmann::json j = io::read_json(path(out));
    EXPECT_EQ(j.at("estimator"), "srivc_irregular");
    EXPECT_EQ(j.at("data").at("time_stamps"), "irregular");
    EXPECT_GE(j.at("data").at("duplicate_stamps").get<int>(), 3);
    EXPECT_LT(relative_error(j.at("parameters")), 1e-8) << hold << ": " << j.at("parameters");
    EXPECT_TRUE(j.at("verdict").at("usable").get<bool>());
  }
}

TEST_F(FitIrregular, WithoutTheFlagTheStampsAreRefusedAsBefore) {
  const std::string csv = write("d.csv", jittered_csv(Hold::zero_order_hold));
  const auto r = ctid({"fit", csv, "--poles", "2", "--zeros", "1"});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("not uniform"));
}

TEST_F(FitIrregular, WhatItDoesNotTakeIsRefusedNamingTheFlag) {
  const std::string csv = write("d.csv", jittered_csv(Hold::zero_order_hold, 300));
  const std::vector<std::string> base = {"fit", csv, "--irregular", "--poles", "2", "--zeros", "1"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return ctid(args);
  };
  const std::string controller = write("c.json", R"({"type": "discrete_transfer_function",
    "numerator": [1.0], "denominator": [1.0], "sample_time": 0.05})");
  expect_bad_input(with({"--controller", controller}), "fit", "--controller does not go with");
  expect_bad_input(with({"--input-columns", "u,u", "--output-columns", "y"}), "fit",
                   "--input-columns / --output-columns does not go with --irregular");
  expect_bad_input(with({"--decimate", "2"}), "fit", "--decimate does not go with --irregular");
  expect_bad_input(with({"--resample", "0.05"}), "fit", "--resample does not go with");
  expect_bad_input(with({"--delay-scan-samples", "0:3"}), "fit",
                   "--delay-scan-samples does not go with");
  expect_bad_input(ctid({"fit", csv, "--irregular", "--modes", "1"}), "fit",
                   "--modes does not go with --irregular");
}

TEST_F(FitIrregular, BadStampsAreOneClearMessage) {
  std::string backwards = "t,u,y\n";
  for (int k = 0; k < 100; ++k) {
    const double t = k == 40 ? 0.05 * 38 : 0.05 * k;
    backwards += std::to_string(t) + "," + std::to_string(std::sin(0.3 * k) + (k % 3)) + "," +
                 std::to_string(std::cos(0.2 * k)) + "\n";
  }
  expect_bad_input(
      ctid({"fit", write("b.csv", backwards), "--irregular", "--poles", "2", "--zeros", "1"}),
      "fit", "time stamp 40 (1.9 s) goes back before stamp 39");
  expect_bad_input(ctid({"fit", write("n.csv", "t,u,y\n0,1,2\nnan,2,3\n0.05,1,1\n"), "--irregular",
                         "--poles", "1", "--zeros", "0"}),
                   "fit", "column 't' (field 1): value 'nan' is not finite");
  std::string few = "t,u,y\n";
  for (int k = 0; k < 15; ++k) {
    few += std::to_string(0.05 * k) + "," + std::to_string(std::sin(1.3 * k)) + "," +
           std::to_string(std::cos(0.7 * k)) + "\n";
  }
  expect_bad_input(
      ctid({"fit", write("f.csv", few), "--irregular", "--poles", "2", "--zeros", "1"}), "fit",
      "too few for 4 parameters");
}

}  // namespace
}  // namespace ctid::cli::fit_irregular_test
