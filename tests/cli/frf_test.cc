// `ctid frf` run as a user would: on noise-free periodic data the averaged FRF equals the
// exact ZOH-sampled response of the true model at every excited line, the peaks sit at the
// modes; Welch gives coherence; bad input exits 2 with one line.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <variant>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/LU>

#include "cli/run_ctid.h"
#include "ctid/io/csv.h"
#include "ctid/io/documents.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"
#include "ctid/simulation/discretization.h"

namespace ctid::cli::frf_test {
namespace {

using ::testing::HasSubstr;

// Section 6.1 under 4 periods of a 2048-sample multisine, 0.01-3 Hz, h = 0.05 s.
class FrfCommand : public testing::Section61Test {};

void expect_bad_input(const testing::RunResult& r, const std::string& fragment) {
  testing::expect_bad_input(r, "frf", fragment);
}

// G_d(e^{j w h}) of the ZOH equivalent: what a periodic steady state measures exactly.
std::complex<double> zoh_response(const StateSpace& d, double w, double h) {
  const std::complex<double> z = std::polar(1.0, w * h);
  const Eigen::Index n = d.a.rows();
  const Eigen::MatrixXcd m =
      z * Eigen::MatrixXcd::Identity(n, n) - d.a.cast<std::complex<double>>();
  const Eigen::VectorXcd x = m.partialPivLu().solve(d.b.cast<std::complex<double>>());
  return (d.c.cast<std::complex<double>>() * x)(0) + d.d;
}

TEST_F(FrfCommand, PeriodicFrfEqualsTheSampledResponseAndFindsTheModes) {
  const auto r = ctid({"frf", "d.csv", "--period", "2048", "-o", "f.csv"});
  ASSERT_EQ(r.status, 0) << r.err;
  const io::CsvTable t = io::read_csv(path("f.csv"));
  const AdditiveModel model = std::get<AdditiveModel>(io::read_continuous_model(
      std::string(CTID_SOURCE_DIR) + "/examples/models/gonzalez_6_1_open_loop.json"));
  const StateSpace d = discretize_zoh(model.to_transfer_function().to_state_space(), 0.05);
  // Lines k/(2048 x 0.05 s) in 0.01-3 Hz: k = 2..307.
  EXPECT_EQ(t.rows(), 306);
  // Noise-free, the output repeats with the input: coherence 1 at every excited line.
  ASSERT_TRUE(t.has_column("coherence"));
  EXPECT_GT(t.column("coherence").minCoeff(), 1.0 - 1e-9);
  ASSERT_TRUE(t.has_column("input_level"));
  EXPECT_DOUBLE_EQ(t.column("input_level").maxCoeff(), 1.0);
  for (int k = 0; k < t.rows(); ++k) {
    const double w = t.column("frequency")(k);
    const std::complex<double> g(t.column("real")(k), t.column("imag")(k));
    const std::complex<double> truth = zoh_response(d, w, 0.05);
    // What is left of the transient after the first period, e^{-0.15 x 102.4} ~ 2e-7,
    // relative to the peak |G| ~ 9.
    ASSERT_LT(std::abs(g - truth), 1e-5) << "line " << k;
    EXPECT_NEAR(t.column("magnitude_db")(k), 20.0 * std::log10(std::abs(g)), 1e-9);
    EXPECT_NEAR(t.column("phase_deg")(k), std::arg(g) * 180.0 / std::numbers::pi, 1e-9);
    EXPECT_NEAR(t.column("frequency_hz")(k), w / (2.0 * std::numbers::pi), 1e-12);
  }
  // Four peaks listed; the lightly damped modes 2 and 3 within 1 % of w_n.
  EXPECT_THAT(r.out, HasSubstr("excited band: 0.0195312 to 2.99805 Hz, 306 of 306 lines"));
  EXPECT_THAT(r.out, HasSubstr("4 resonance peaks"));
  EXPECT_THAT(r.out, HasSubstr("coherence 1\n"));
  EXPECT_THAT(r.out, HasSubstr("w = 3.1"));
  EXPECT_THAT(r.out, HasSubstr("w = 5.7"));
}

TEST_F(FrfCommand, WelchWritesCoherence) {
  const auto r = ctid({"frf", "d.csv", "--segment-length", "2048", "-o", "w.csv", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  const io::CsvTable t = io::read_csv(path("w.csv"));
  // Of lines 1..L/2, those where the input reaches 1 % of its largest line: the multisine's
  // band, 0.01-3 Hz, and the window's leakage just outside it.
  ASSERT_TRUE(t.has_column("input_level"));
  EXPECT_GT(t.column("input_level").minCoeff(), 0.01);
  EXPECT_LT(t.column("frequency_hz").minCoeff(), 0.05);
  EXPECT_GT(t.column("frequency_hz").maxCoeff(), 2.95);
  EXPECT_LT(t.column("frequency_hz").maxCoeff(), 3.2);
  EXPECT_GT(t.rows(), 290);
  EXPECT_LT(t.rows(), 340);
  ASSERT_TRUE(t.has_column("coherence"));
  EXPECT_GE(t.column("coherence").minCoeff(), 0.0);
  EXPECT_LE(t.column("coherence").maxCoeff(), 1.0 + 1e-12);
  // Noise-free, inside the excited band the output is linear in the input: coherence near 1
  // (below 1 only through window leakage of the lightly damped modes).
  std::vector<double> band;
  for (int k = 0; k < t.rows(); ++k) {
    const double hz = t.column("frequency_hz")(k);
    if (hz > 0.1 && hz < 2.5) band.push_back(t.column("coherence")(k));
  }
  ASSERT_GT(band.size(), 200u);
  std::sort(band.begin(), band.end());
  EXPECT_GT(band[band.size() / 2], 0.99);
  EXPECT_GT(band.front(), 0.8);
}

TEST_F(FrfCommand, JsonOutputIsAnFrfDocumentWithTheCsvValues) {
  ASSERT_EQ(ctid({"frf", "d.csv", "--segment-length", "2048", "-o", "w.csv", "-q"}).status, 0);
  const auto r = ctid({"frf", "d.csv", "--segment-length", "2048", "-o", "w.json", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  const io::ResultDocument read = io::read_result(path("w.json"));
  ASSERT_TRUE(std::holds_alternative<Frf>(read));
  const Frf& frf = std::get<Frf>(read);
  const io::CsvTable t = io::read_csv(path("w.csv"));
  ASSERT_EQ(frf.frequencies.size(), t.rows());
  EXPECT_EQ(frf.frequencies, t.column("frequency"));
  EXPECT_EQ(frf.response.real(), t.column("real"));
  EXPECT_EQ(frf.response.imag(), t.column("imag"));
  EXPECT_EQ(frf.coherence, t.column("coherence"));
  EXPECT_EQ(frf.block_length, 2048);
  const nlohmann::json j = io::read_json(path("w.json"));
  EXPECT_EQ(j.at("method"), "welch");
  EXPECT_TRUE(j.at("peaks").is_array());
}

TEST_F(FrfCommand, LineThresholdZeroKeepsEveryWelchLine) {
  const auto r = ctid({"frf", "d.csv", "--segment-length", "2048", "--line-threshold", "0",
                       "--min-coherence", "0", "-o", "w.csv"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(io::read_csv(path("w.csv")).rows(), 1024);  // lines 1..L/2
  EXPECT_THAT(r.out, HasSubstr("1024 of 1024 lines above --line-threshold 0"));
}

TEST_F(FrfCommand, BadInputExitsTwoWithOneLine) {
  expect_bad_input(ctid({"frf", "d.csv", "--line-threshold", "1.5"}), "--line-threshold is 1.5");
  expect_bad_input(ctid({"frf", "d.csv", "--period", "2048", "--min-coherence", "-1"}),
                   "--min-coherence is -1");
  expect_bad_input(ctid({"frf", "d.csv", "--period", "3000"}), "");
  expect_bad_input(ctid({"frf", "d.csv", "--period", "2048", "--segment-length", "256"}),
                   "no effect with --period");
  expect_bad_input(ctid({"frf", "d.csv", "--segment-length", "4"}), "--segment-length is 4");
  expect_bad_input(ctid({"frf", "d.csv", "--output-column", "q"}), "'q'");
  expect_bad_input(ctid({"frf", "d.csv", "--model", "d.csv"}), "--model needs --plot");
  write("f.csv", "keep");
  expect_bad_input(ctid({"frf", "d.csv", "-o", "f.csv"}), "file exists; pass --force");
  EXPECT_EQ(testing::slurp(path("f.csv")), "keep");
}

TEST_F(FrfCommand, PlotWritesTheFrfAndTheModelOverIt) {
  if (testing::python_package().empty()) {
    GTEST_SKIP() << "the ctid Python package is not built (CTID_BUILD_PYTHON=OFF); set "
                    "CTID_PYTHONPATH to test --plot";
  }
  const auto r = ctid(
      {"frf", "d.csv", "--plot", "fig", "--model", example("gonzalez_6_1_open_loop.json"), "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* name : {"frf.png", "bode.png"}) {
    const std::string bytes = testing::slurp(path("fig") / name);
    EXPECT_GT(bytes.size(), 10000u) << name;
    EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << name;
  }
  expect_bad_input(ctid({"frf", "d.csv", "--plot", "fig", "-q"}), "file exists");
}

}  // namespace
}  // namespace ctid::cli::frf_test
