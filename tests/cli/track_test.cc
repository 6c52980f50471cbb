// `ctid track` run as a user would: on a noise-free one-mode record it follows the mode through
// five windows, prints one line per track, writes the document and the table with the documented
// columns, refuses to replace them without --force, says when no window gave a usable model
// (exit 3) and refuses bad windows with one line.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cli/run_ctid.h"
#include "ctid/core/mimo_data.h"
#include "ctid/core/mimo_model.h"
#include "ctid/io/json.h"
#include "ctid/io/mimo_data_csv.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"
#include "support/mimo_systems.h"

namespace ctid::cli::track_test {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

// 1 / (1 + 0.1 p + p^2): w_n = 1 rad/s (0.159155 Hz), zeta = 0.05, under a PRBS, h = 0.05 s,
// 3000 samples (150 s), noise-free.
class TrackCommand : public testing::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    write("g.json", R"({"type": "transfer_function", "numerator_ascending": [1.0],
      "denominator_ascending": [1.0, 0.1, 1.0]})");
    const auto r = ctid({"simulate", "-m", "g.json", "--excitation", "prbs", "--samples", "3000",
                         "--samples-per-bit", "2", "-T", "0.05", "-o", "d.csv", "-q"});
    ASSERT_EQ(r.status, 0) << r.err;
  }
};

void expect_bad_input(const testing::RunResult& r, const std::string& fragment) {
  testing::expect_bad_input(r, "track", fragment);
}

TEST_F(TrackCommand, FollowsTheModeAndWritesTheDocumentAndTheTable) {
  const auto r = ctid(
      {"track", "d.csv", "--window", "30", "--modes", "1", "-o", "t.json", "--table", "t.csv"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("ctid track: 5 windows of 30 s (600 samples, step 600) on d.csv"));
  EXPECT_THAT(r.out, HasSubstr("usable windows: 5 of 5; warm starts: 4"));
  EXPECT_THAT(r.out, HasSubstr("track 1: mean f_n = 0.159155 Hz"));
  EXPECT_THAT(r.out, HasSubstr("matched in 5 of 5 windows"));
  EXPECT_THAT(r.out, ::testing::Not(HasSubstr("WARNING")));

  const nlohmann::json j = io::read_json(path("t.json"));
  EXPECT_EQ(j.at("type"), "mode_tracking_result");
  EXPECT_EQ(j.at("version"), 1);
  ASSERT_EQ(j.at("windows").size(), 5U);
  EXPECT_EQ(j.at("windows")[4].at("first_sample"), 2400);
  EXPECT_EQ(j.at("windows")[4].at("start"), "previous_window");
  ASSERT_EQ(j.at("tracks").size(), 1U);
  for (const auto& w : j.at("tracks")[0].at("natural_frequency")) {
    EXPECT_NEAR(w.get<double>(), 1.0, 1e-8);
  }
  EXPECT_EQ(j.at("data").at("file"), "d.csv");

  const std::string table = testing::slurp(path("t.csv"));
  EXPECT_THAT(table, StartsWith("window,t_start,t_centre,t_end,track,frequency_hz,frequency_se_hz,"
                                "damping,damping_se,usable\n"
                                "1,0,14.975000000000001,29.950000000000003,1,0.159154943"));
  EXPECT_EQ(testing::line_count(table), 6);  // header + 5 windows x 1 track

  // Nothing is replaced without --force, each refusal one line naming the file.
  expect_bad_input(ctid({"track", "d.csv", "--window", "30", "--modes", "1", "-o", "t.json"}),
                   "t.json");
  expect_bad_input(ctid({"track", "d.csv", "--window", "30", "--modes", "1", "--table", "t.csv"}),
                   "--table t.csv exists; pass --force to replace it");
  expect_bad_input(
      ctid({"track", "d.csv", "--window", "30", "--modes", "1", "--table", "d.csv", "--force"}),
      "--table 'd.csv' is the input file 'd.csv' (data)");
  EXPECT_EQ(ctid({"track", "d.csv", "--window", "30", "--modes", "1", "-o", "t.json", "--table",
                  "t.csv", "--force", "-q"})
                .status,
            0);
}

TEST_F(TrackCommand, DrawsTheTrackingFigure) {
  if (testing::python_package().empty()) GTEST_SKIP() << "no ctid Python package in this build";
  const auto r = ctid({"track", "d.csv", "--window", "30", "--modes", "1", "--plot", "figures"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("wrote figures/tracking.png"));
  testing::expect_png(path("figures") / "tracking.png");
  expect_bad_input(ctid({"track", "d.csv", "--window", "30", "--modes", "1", "--plot", "figures"}),
                   "tracking.png");
}

TEST_F(TrackCommand, SaysWhenNoWindowGaveAUsableModel) {
  // Three modes in a one-mode record: every window's fit is refused by the verdict.
  const auto r = ctid({"track", "d.csv", "--window", "50", "--modes", "3", "--table", "t.csv"});
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_THAT(r.out, HasSubstr("WARNING: 3 of 3 windows gave no usable model (windows 1, 2 and "
                               "3); their modes are not tracked"));
  EXPECT_THAT(r.out, HasSubstr("usable windows: 0 of 3"));
  // The table still has a row per window, marked unusable.
  const std::string table = testing::slurp(path("t.csv"));
  EXPECT_EQ(testing::line_count(table), 4);
  EXPECT_THAT(table, HasSubstr("\n3,100,124.975,149.95,,,,,,0\n"));
}

TEST_F(TrackCommand, RefusesBadWindowsWithOneLine) {
  expect_bad_input(ctid({"track", "d.csv", "--window", "200", "--modes", "1"}),
                   "--window is 200 s (4000 samples); the record has 3000 samples "
                   "(150 s), so the window must not be longer");
  expect_bad_input(ctid({"track", "d.csv", "--window", "100", "--modes", "1"}),
                   "tracking needs at least 2 windows");
  expect_bad_input(ctid({"track", "d.csv", "--window", "30", "--step", "0", "--modes", "1"}),
                   "--step is 0 s; it must be > 0");
  expect_bad_input(ctid({"track", "d.csv", "--window", "0", "--modes", "1"}),
                   "--window is 0 s; it must be > 0");
  expect_bad_input(ctid({"track", "d.csv", "--window", "30"}), "give one model structure");
  expect_bad_input(
      ctid({"track", "d.csv", "--window", "30", "--modes", "1", "--max-frequency-jump", "0"}),
      "--max-frequency-jump is 0; it must be finite and > 0");
}

// Several outputs (--input-columns / --output-columns, docs/decisions/0026): two modes of
// three sensors under two forces, noise-free, 3000 samples of h = 0.05 s.
class TrackMimoCommand : public testing::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    const MimoAdditiveModel g = ctid::testing::two_mode_structure();
    Eigen::MatrixXd u(3000, 2);
    for (int k = 0; k < 2; ++k) u.col(k) = white_noise(3000, 1.0, 7 + k);
    Eigen::MatrixXd y = Eigen::MatrixXd::Zero(3000, 3);
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 2; ++k) y.col(j) += simulate(g.channel(j, k), u.col(k), 0.05);
    }
    io::write_mimo_data(path("m.csv"),
                        MimoData(0.05, u, y).with_names({"f1", "f2"}, {"a1", "a2", "a3"}));
  }
};

TEST_F(TrackMimoCommand, FollowsTheSharedModesWithTheirMac) {
  const auto r =
      ctid({"track", "m.csv", "--input-columns", "f1,f2", "--output-columns", "a1:a3", "--window",
            "50", "--submodel", "2,0", "--submodel", "2,0", "-o", "t.json", "--table", "t.csv"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("ctid track: 3 windows of 50 s (1000 samples, step 1000) on m.csv "
                               "(N = 3000, h = 0.05 s, 3 outputs, 2 inputs)"));
  EXPECT_THAT(r.out, HasSubstr("usable windows: 3 of 3; warm starts: 2"));
  EXPECT_THAT(r.out, HasSubstr("matched in 3 of 3 windows, smallest MAC "));
  const nlohmann::json j = io::read_json(path("t.json"));
  EXPECT_EQ(j.at("type"), "mimo_mode_tracking_result");
  ASSERT_EQ(j.at("tracks").size(), 2U);
  // Noise-free and mid-motion after window 1: exact with the initial state estimated.
  const double w[2] = {1.4, 4.0};
  for (int t = 0; t < 2; ++t) {
    const auto& track = j.at("tracks")[static_cast<std::size_t>(t)];
    for (const auto& value : track.at("natural_frequency")) {
      EXPECT_NEAR(value.get<double>(), w[t], 1e-7 * w[t]);
    }
    EXPECT_NEAR(track.at("mac")[2].get<double>(), 1.0, 1e-9);
  }
  EXPECT_EQ(j.at("options").at("refined_iv").at("initial_conditions"), "estimate");
  const std::string table = testing::slurp(path("t.csv"));
  EXPECT_THAT(table, StartsWith("window,t_start,t_centre,t_end,track,frequency_hz,frequency_se_hz,"
                                "damping,damping_se,mac,usable\n"));
  EXPECT_EQ(testing::line_count(table), 7);  // header + 3 windows x 2 tracks
}

TEST_F(TrackMimoCommand, RefusesWhatSeveralOutputsCannotDoWithOneLine) {
  const std::vector<std::string> base{
      "track", "m.csv", "--input-columns", "f1,f2", "--output-columns", "a1:a3", "--window", "50"};
  const auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return ctid(args);
  };
  expect_bad_input(with({"--poles", "4", "--zeros", "1"}),
                   "an unfactored model has no shared modes");
  expect_bad_input(
      with({"--modes", "2", "--input-delay-samples", "1"}),
      "--input-delay-samples is not available with --input-columns / --output-columns");
  expect_bad_input(with({"--modes", "2", "--start", "lssvf"}),
                   "--start lssvf is for one input and output");
  // Derived from the field tables: every one-channel fit flag the windows do not read.
  expect_bad_input(with({"--modes", "2", "--no-step-control"}),
                   "--step-control is not available with --input-columns / --output-columns");
  expect_bad_input(with({"--modes", "2", "--method", "fdd"}), "--method goes with --output-only");
  expect_bad_input(ctid({"track", "m.csv", "--input-column", "f1", "--output-column", "a1",
                         "--window", "50", "--modes", "2", "--mac-weight", "1"}),
                   "--mac-weight goes with --input-columns / --output-columns");
  expect_bad_input(with({"--modes", "2", "--min-mac", "1.5"}), "--min-mac is 1.5");
  expect_bad_input(ctid({"track", "m.csv", "--input-columns", "f1,f2", "--output-columns", "a1:a3",
                         "--window", "500", "--modes", "2"}),
                   "the window must not be longer");
}

}  // namespace
}  // namespace ctid::cli::track_test
