// `ctid frf` with several inputs and outputs (--input-columns / --output-columns): the FRF
// matrix of a noise-free two-input, three-output record against the sampled models, the 1 x 1
// case against the SISO command, Hadamard experiments with --period, and bad input exiting 2
// with one line that names the problem.
#include <cmath>
#include <complex>
#include <filesystem>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/LU>

#include "cli/run_ctid.h"
#include "ctid/core/mimo_data.h"
#include "ctid/core/mimo_model.h"
#include "ctid/core/transfer_function.h"
#include "ctid/io/csv.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"
#include "ctid/io/mimo_data_csv.h"
#include "ctid/io/mimo_frf_file.h"
#include "ctid/io/model_json.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::cli::frf_mimo_test {
namespace {

using ::testing::HasSubstr;
using Complex = std::complex<double>;

constexpr double kH = 0.05;

void expect_bad_input(const testing::RunResult& r, const std::string& fragment) {
  testing::expect_bad_input(r, "frf", fragment);
}

void expect_bad_input_of(const std::string& command, const testing::RunResult& r,
                         const std::string& fragment) {
  testing::expect_bad_input(r, command, fragment);
}

TransferFunction mode(double gain, double wn, double zeta) {
  return TransferFunction(Polynomial{gain * wn * wn}, Polynomial{wn * wn, 2 * zeta * wn, 1.0});
}

// G[j][i]: output j from input i.
std::vector<std::vector<TransferFunction>> system_2x3() {
  const TransferFunction lag(Polynomial{2.0}, Polynomial{1.0, 1.0});
  return {{mode(1.0, 2.0, 0.5), mode(-0.5, 4.0, 0.4)},
          {lag, mode(0.8, 3.0, 0.6)},
          {mode(0.3, 5.0, 0.5), lag}};
}

Complex zoh_response(const TransferFunction& g, double omega) {
  const StateSpace d = zoh_equivalent(g, kH);
  const Complex z = std::exp(Complex(0.0, omega * kH));
  const Eigen::MatrixXcd lhs =
      z * Eigen::MatrixXcd::Identity(d.order(), d.order()) - d.a.cast<Complex>();
  const Eigen::VectorXcd x = lhs.partialPivLu().solve(d.b.cast<Complex>());
  return (d.c.cast<Complex>() * x)(0) + d.d;
}

MimoData record(const Eigen::MatrixXd& u) {
  const auto g = system_2x3();
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(u.rows(), 3);
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 2; ++i) {
      y.col(j) += simulate(g[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)],
                           u.col(i).eval(), kH);
    }
  }
  return MimoData(kH, u, y).with_names({"u1", "u2"}, {"y1", "y2", "y3"});
}

class FrfMimoCommand : public testing::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    Eigen::MatrixXd u(65536, 2);
    u.col(0) = white_noise(65536, 1.0, 1);
    u.col(1) = white_noise(65536, 1.0, 2);
    io::write_mimo_data(path("d.csv"), record(u));
  }
};

TEST_F(FrfMimoCommand, WelchMatrixMatchesTheSampledModels) {
  const auto r = ctid({"frf", "d.csv", "--input-columns", "u1,u2", "--output-columns", "y1:y3",
                       "--segment-length", "2048", "-o", "m.csv"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("Welch H1 on d.csv: 2 inputs (u1, u2) x 3 outputs, 1024 lines, "
                               "63 segments of 2048 samples"));
  EXPECT_THAT(r.out, HasSubstr("inputs correlated (condition of the normalised S_uu > 100) at 0 "
                               "of 1024 lines"));
  EXPECT_THAT(r.out, HasSubstr("multiple coherence with all inputs, median over the excited "
                               "band:\n  y1 1\n"));
  EXPECT_THAT(r.out, HasSubstr("of sqrt(sum |H_ji|^2) over the 6 channels"));
  const io::CsvTable t = io::read_csv(path("m.csv"));
  EXPECT_EQ(t.rows(), 1024);
  const auto g = system_2x3();
  double worst = 0.0;
  for (int l = 0; l < 300; ++l) {  // up to 9.2 rad/s, where every channel has gain
    const double w = t.column("frequency")(l);
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 2; ++i) {
        const std::string pair = "y" + std::to_string(j + 1) + "/u" + std::to_string(i + 1);
        const Complex h(t.column(pair + "_real")(l), t.column(pair + "_imag")(l));
        const Complex truth =
            zoh_response(g[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)], w);
        worst = std::max(worst, std::abs(h - truth) / std::abs(truth));
      }
    }
    EXPECT_GT(t.column("coherence_y3")(l), 0.99);
  }
  // The leakage of a random input into 102-s segments acts as noise: 5.8 % at worst.
  EXPECT_LT(worst, 0.1);
  ASSERT_TRUE(t.has_column("y2/u1_variance"));
  ASSERT_TRUE(t.has_column("input_level_u2"));
  EXPECT_LT(t.column("input_condition").maxCoeff(), 2.0);
}

TEST_F(FrfMimoCommand, JsonDocumentHoldsTheMatrixAndThePeaks) {
  const auto r = ctid({"frf", "d.csv", "--input-columns", "u1:u2", "--output-columns", "y1,y3",
                       "-o", "m.json", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out, "");
  const nlohmann::json doc = io::read_json(path("m.json"));
  EXPECT_EQ(doc["type"], "mimo_frf");
  EXPECT_EQ(doc["method"], "welch");
  EXPECT_EQ(doc["outputs"], (std::vector<std::string>{"y1", "y3"}));
  const auto lines = doc["lines"].size();
  ASSERT_EQ(doc["response"].size(), lines);
  EXPECT_EQ(doc["response"][5].size(), 2u);     // outputs
  EXPECT_EQ(doc["response"][5][1].size(), 2u);  // inputs
  EXPECT_EQ(doc["coherence"][5].size(), 2u);
  EXPECT_TRUE(doc["peaks"].is_array());
}

// What `ctid frf` writes with several channels, `ctid fit-frf` reads: the CSV table, the
// "mimo_frf" document (.json) and the universal file (.uff, dataset 58) give the same matrix.
TEST_F(FrfMimoCommand, EveryMatrixFileItWritesFitFrfReads) {
  for (const char* name : {"m.csv", "m.json", "m.uff"}) {
    const auto r = ctid({"frf", "d.csv", "--input-columns", "u1:u2", "--output-columns", "y1:y3",
                         "-o", name, "-q"});
    ASSERT_EQ(r.status, 0) << name << ": " << r.err;
  }
  const MimoFrf csv = io::read_mimo_frf(path("m.csv"));
  const MimoFrf json = io::read_mimo_frf(path("m.json"));
  const MimoFrf uff = io::read_mimo_frf(path("m.uff"));
  EXPECT_EQ(io::read_text_file(path("m.uff")).substr(0, 12), "    -1\n    5");
  ASSERT_EQ(json.frequencies.size(), csv.frequencies.size());
  ASSERT_EQ(uff.frequencies.size(), csv.frequencies.size());
  EXPECT_EQ(json.output_names, csv.output_names);
  for (Eigen::Index l = 0; l < csv.frequencies.size(); ++l) {
    EXPECT_EQ(json.response[l], csv.response[l]) << "line " << l;
    // The universal file holds 6-7 significant digits.
    EXPECT_LT((uff.response[l] - csv.response[l]).norm(), 1e-5 * csv.response[l].norm())
        << "line " << l;
  }
  const auto fitted = ctid({"fit-frf", "m.json", "--modes", "2", "-q"});
  EXPECT_NE(fitted.status, 2) << fitted.err;
  testing::expect_bad_input(
      ctid({"frf", "d.csv", "--input-column", "u1", "--output-column", "y1", "-o", "s.uff"}), "frf",
      "-o s.uff: a universal file (dataset 58) holds an FRF matrix");
  EXPECT_FALSE(std::filesystem::exists(path("s.uff")));
}

TEST_F(FrfMimoCommand, OneByOneEqualsTheSisoCommand) {
  ASSERT_EQ(
      ctid({"frf", "d.csv", "--input-column", "u2", "--output-column", "y3", "-o", "s.csv", "-q"})
          .status,
      0);
  ASSERT_EQ(
      ctid({"frf", "d.csv", "--input-columns", "u2", "--output-columns", "y3", "-o", "m.csv", "-q"})
          .status,
      0);
  const io::CsvTable s = io::read_csv(path("s.csv"));
  const io::CsvTable m = io::read_csv(path("m.csv"));
  ASSERT_EQ(s.rows(), m.rows());
  for (int l = 0; l < s.rows(); ++l) {
    const Complex a(s.column("real")(l), s.column("imag")(l));
    const Complex b(m.column("y3/u2_real")(l), m.column("y3/u2_imag")(l));
    ASSERT_LT(std::abs(a - b), 1e-12 * std::abs(a)) << l;
    ASSERT_NEAR(s.column("coherence")(l), m.column("coherence_y3")(l), 1e-12);
  }
}

TEST_F(FrfMimoCommand, HadamardExperimentsWithPeriodAreExact) {
  MultisineOptions ms;
  ms.period_length = 512;
  ms.sample_time = kH;
  ms.max_frequency = 3.0;
  ms.periods = 4;
  ms.seed = 5;
  const Multisine s1 = multisine(ms);
  ms.seed = 6;
  const Eigen::VectorXd s2 = multisine(ms).signal;
  const auto n = s2.size();
  Eigen::MatrixXd u(2 * n, 2);
  u.col(0) << s1.signal, s1.signal;
  u.col(1) << s2, -s2;
  // Each experiment starts at rest: simulate the two halves apart and join them.
  const MimoData first = record(u.topRows(n));
  const MimoData second = record(u.bottomRows(n));
  Eigen::MatrixXd y(2 * n, 3);
  y << first.outputs(), second.outputs();
  io::write_mimo_data(path("p.csv"),
                      MimoData(kH, u, y).with_names({"u1", "u2"}, {"y1", "y2", "y3"}));
  const auto r = ctid({"frf", "p.csv", "--input-columns", "u1,u2", "--output-columns", "y1:y3",
                       "--period", "512", "--transient-periods", "2", "-o", "p_frf.csv"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("periodic on p.csv: 2 inputs (u1, u2) x 3 outputs"));
  const io::CsvTable t = io::read_csv(path("p_frf.csv"));
  EXPECT_EQ(t.rows(), static_cast<int>(s1.lines.size()));
  const auto g = system_2x3();
  for (int l = 0; l < t.rows(); ++l) {
    const Complex h(t.column("y3/u1_real")(l), t.column("y3/u1_imag")(l));
    ASSERT_LT(std::abs(h - zoh_response(g[2][0], t.column("frequency")(l))), 1e-9) << l;
  }
}

TEST_F(FrfMimoCommand, SimulatedOrthogonalMultisinesGiveTheModelsFrfMatrix) {
  // Two shared modes, two inputs, three outputs: ctid simulate writes the Hadamard
  // experiments, ctid frf --period reads them back as the model's sampled FRF matrix.
  const auto anti_monic = [](double wn, double zeta) {
    return Polynomial{1.0, 2.0 * zeta / wn, 1.0 / (wn * wn)};
  };
  std::vector<Polynomial> r1, r2;
  for (double c : {1.0, -0.4, 0.7, 0.2, -1.1, 0.5}) r1.push_back(Polynomial{c});
  for (double c : {0.3, 0.9, -0.6, 1.2, 0.4, -0.8}) r2.push_back(Polynomial{c});
  const MimoAdditiveModel model(2, 3, {{anti_monic(2.0, 0.3), r1}, {anti_monic(5.0, 0.2), r2}});
  io::write_json(path("m.json"), io::to_json(model));
  const auto s =
      ctid({"simulate", "-m", "m.json", "--excitation", "multisine", "--samples", "4096",
            "--periods", "4", "--sample-time", "0.05", "--max-frequency-hz", "3", "-o", "s.csv"});
  ASSERT_EQ(s.status, 0) << s.err;
  EXPECT_THAT(s.out, HasSubstr("2 experiments of Hadamard-phased multisines, 4 periods of 1024"));
  const auto r = ctid({"frf", "s.csv", "--input-columns", "u1:u2", "--output-columns", "y1:y3",
                       "--period", "1024", "-o", "f.csv", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  const io::CsvTable t = io::read_csv(path("f.csv"));
  EXPECT_EQ(t.rows(), 153);  // lines k / (1024 x 0.05 s) up to 3 Hz
  double worst = 0.0;
  for (int l = 0; l < t.rows(); ++l) {
    const double w = t.column("frequency")(l);
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 2; ++k) {
        const StateSpace d =
            discretize_zoh(model.channel(j, k).to_transfer_function().to_state_space(), kH);
        const Complex z = std::exp(Complex(0.0, w * kH));
        const Eigen::MatrixXcd lhs =
            z * Eigen::MatrixXcd::Identity(d.a.rows(), d.a.rows()) - d.a.cast<Complex>();
        const Complex truth =
            (d.c.cast<Complex>() * lhs.partialPivLu().solve(d.b.cast<Complex>()))(0) + d.d;
        const std::string pair = "y" + std::to_string(j + 1) + "/u" + std::to_string(k + 1);
        const Complex h(t.column(pair + "_real")(l), t.column(pair + "_imag")(l));
        worst = std::max(worst, std::abs(h - truth));
      }
    }
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_LT(t.column("input_condition").maxCoeff(), 1.0 + 1e-9);
  expect_bad_input_of("simulate",
                      ctid({"simulate", "-m", "m.json", "--excitation", "white", "--samples", "100",
                            "--sample-time", "0.05", "-o", "w.csv"}),
                      "a mimo_additive_model is driven by orthogonal multisines");
}

TEST_F(FrfMimoCommand, BadColumnsAndFlagsExitTwoWithOneLine) {
  expect_bad_input(
      ctid({"frf", "d.csv", "--input-columns", "u1,u2", "--output-columns", "y1:y29"}),
      "d.csv: output column 'y29' not found (in range 'y1:y29'); columns are t, u1, u2, y1, y2, "
      "y3");
  expect_bad_input(ctid({"frf", "d.csv", "--input-columns", "u1,y1", "--output-columns", "y1:y3"}),
                   "d.csv: column 'y1' is named twice (as input and as output)");
  expect_bad_input(ctid({"frf", "d.csv", "--input-columns", "u1", "--input-column", "u2",
                         "--output-columns", "y1"}),
                   "give --input-column or --input-columns, not both");
  expect_bad_input(ctid({"frf", "d.csv", "--input-columns", "u1,u2", "--output-columns", "y1",
                         "--resample", "0.1"}),
                   "--resample is not available with --input-columns / --output-columns yet");
  expect_bad_input(ctid({"frf", "d.csv", "--input-columns", "u1,u2", "--output-columns", "y1",
                         "--decimate", "0"}),
                   "--decimate is 0; it must be >= 1");
  expect_bad_input(ctid({"frf", "d.csv", "--input-columns", "u1,u2", "--output-columns", "y1",
                         "--experiments", "2"}),
                   "--experiments needs --period");
  expect_bad_input(ctid({"frf", "d.csv", "--experiments", "2"}),
                   "--experiments needs several inputs (--input-columns)");
  expect_bad_input(ctid({"frf", "d.csv", "--input-columns", "u1,u2", "--output-columns", "y1",
                         "--period", "512", "--experiments", "3"}),
                   "do not split into 3 experiments");
}

TEST_F(FrfMimoCommand, PlotDrawsTheFrfMatrix) {
  if (testing::python_package().empty()) {
    GTEST_SKIP() << "the ctid Python package is not built (CTID_BUILD_PYTHON=OFF); set "
                    "CTID_PYTHONPATH to test --plot";
  }
  const auto r = ctid({"frf", "d.csv", "--input-columns", "u1,u2", "--output-columns", "y1:y3",
                       "--plot", "fig", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_GT(std::filesystem::file_size(path("fig/frf_matrix.png")), 1000u);
  expect_bad_input(ctid({"frf", "d.csv", "--input-columns", "u1,u2", "--output-columns", "y1",
                         "--plot", "fig2", "--model", example("gonzalez_6_1_open_loop.json")}),
                   "--model is not available with --input-columns / --output-columns yet");
}

TEST_F(FrfMimoCommand, PreprocessingAppliesToEveryChannel) {
  const auto r = ctid({"frf", "d.csv", "--input-columns", "u1,u2", "--output-columns", "y1",
                       "--rows", "0:16384", "--segment-length", "1024", "-q", "-o", "r.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(io::read_json(path("r.json"))["averages"], 31);
  // Detrending and decimation apply to every channel: half the samples, twice the step.
  const auto d =
      ctid({"frf", "d.csv", "--input-columns", "u1,u2", "--output-columns", "y1:y3", "--detrend",
            "mean", "--decimate", "2", "--segment-length", "1024", "-o", "d.json"});
  ASSERT_EQ(d.status, 0) << d.err;
  EXPECT_THAT(d.out, HasSubstr("preprocessing: "));
  const nlohmann::json doc = io::read_json(path("d.json"));
  EXPECT_EQ(doc["data"]["samples"], 32768);
  EXPECT_DOUBLE_EQ(doc["data"]["sample_time"].get<double>(), 0.1);
  EXPECT_EQ(doc["data"]["preprocessing"]["decimate"], 2);
}

}  // namespace
}  // namespace ctid::cli::frf_mimo_test
