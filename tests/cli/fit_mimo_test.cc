// `ctid fit` with several inputs and outputs (--input-columns / --output-columns): the modes of a
// noise-free two-input, three-output record recovered with their shapes in the JSON, the exit
// status of an unusable fit, and bad usage exiting 2 with one line naming the problem.
#include <cmath>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/core/mimo_data.h"
#include "ctid/core/mimo_model.h"
#include "ctid/io/documents.h"
#include "ctid/io/json.h"
#include "ctid/io/mimo_data_csv.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::cli {
namespace {

using ::testing::HasSubstr;

constexpr double kH = 0.05;

// Two modes (1.4 and 4 rad/s) with rank-one residues over three outputs and two inputs.
MimoAdditiveModel two_modes() {
  const double shapes[2][3] = {{1.0, 0.5, -0.3}, {-0.4, 1.0, 0.6}};
  const double participation[2][2] = {{1.0, 0.6}, {-0.5, 0.8}};
  std::vector<MimoSubmodel> submodels;
  const double w[2] = {1.4, 4.0};
  for (int i = 0; i < 2; ++i) {
    MimoSubmodel s{Polynomial{1.0, 0.1 / w[i], 1.0 / (w[i] * w[i])}, {}};
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 2; ++k) s.b.push_back(Polynomial{shapes[i][j] * participation[i][k]});
    }
    submodels.push_back(std::move(s));
  }
  return MimoAdditiveModel(2, 3, std::move(submodels));
}

class FitMimoCommand : public testing::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    const MimoAdditiveModel g = two_modes();
    Eigen::MatrixXd u(2000, 2);
    for (int k = 0; k < 2; ++k) u.col(k) = white_noise(2000, 1.0, 5 + k);
    Eigen::MatrixXd y = Eigen::MatrixXd::Zero(2000, 3);
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 2; ++k) y.col(j) += simulate(g.channel(j, k), u.col(k), kH);
    }
    io::write_mimo_data(path("d.csv"),
                        MimoData(kH, u, y).with_names({"f1", "f2"}, {"a1", "a2", "a3"}));
  }
};

TEST_F(FitMimoCommand, SharedModesFromNoiseFreeData) {
  const auto r = ctid({"fit", "d.csv", "--input-columns", "f1,f2", "--output-columns", "a1:a3",
                       "--modes", "2", "-o", "r.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("mimo_srivc: converged"));
  EXPECT_THAT(r.out, HasSubstr("2 inputs x 3 outputs"));
  EXPECT_THAT(r.out, HasSubstr("mode 1: f_n = 0.2228169"));  // 1.4 / (2 pi) Hz
  EXPECT_THAT(r.out, HasSubstr("fit a3: 100 %"));
  const nlohmann::json j = io::read_json(path("r.json"));
  EXPECT_EQ(j.at("type"), "mimo_estimation_result");
  EXPECT_EQ(j.at("data").at("outputs"), nlohmann::json({"a1", "a2", "a3"}));
  ASSERT_EQ(j.at("modes").size(), 2u);
  EXPECT_NEAR(j.at("modes")[1].at("natural_frequency").get<double>(), 4.0, 1e-8);
  // The second mode's shape: (-0.4, 1, 0.6) scaled to unit length, largest entry positive.
  const double norm = std::sqrt(0.16 + 1.0 + 0.36);
  EXPECT_NEAR(j.at("modes")[1].at("shape")[0][0].get<double>(), -0.4 / norm, 1e-8);
  EXPECT_NEAR(j.at("modes")[1].at("shape")[1][0].get<double>(), 1.0 / norm, 1e-8);
  EXPECT_TRUE(j.at("verdict").at("usable").get<bool>());
  // The document reads back as the result that wrote it.
  const auto back = std::get<MimoEstimationResult>(io::read_result(path("r.json")));
  EXPECT_EQ(back.modes.size(), 2u);
  EXPECT_EQ(back.model->outputs(), 3);
}

TEST_F(FitMimoCommand, BadUsageNamesTheProblem) {
  const std::vector<std::string> columns{"d.csv", "--input-columns", "f1,f2", "--output-columns",
                                         "a1:a3"};
  const auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args{"fit"};
    args.insert(args.end(), columns.begin(), columns.end());
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  testing::expect_bad_input(ctid(with({"--poles", "4", "--zeros", "1"})), "fit",
                            "an unfactored model has no shared modes");
  testing::expect_bad_input(ctid(with({"--modes", "2", "--delay", "2"})), "fit",
                            "--delay is not available with --input-columns");
  testing::expect_bad_input(ctid(with({"--modes", "2", "--start", "frf"})), "fit",
                            "--start must be auto");
  testing::expect_bad_input(ctid({"fit", "d.csv", "--input-columns", "f1,f9", "--output-columns",
                                  "a1:a3", "--modes", "2"}),
                            "fit", "'f9' not found");
  testing::expect_bad_input(ctid({"fit", "d.csv", "--input-column", "f1", "--output-column", "a1",
                                  "--modes", "2", "--direct"}),
                            "fit", "--direct goes with --input-columns");
}

}  // namespace
}  // namespace ctid::cli
