// `ctid fit-frf`: the modes of a noise-free two-input, three-output FRF matrix recovered from the
// CSV table `ctid frf -o` writes and from a universal file (dataset 58), the result document,
// exit status 3 for an unusable fit, and bad usage exiting 2 with one line naming the problem.
#include <complex>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/core/mimo_model.h"
#include "ctid/frf_fit/frf_matrix_fit.h"
#include "ctid/io/csv.h"
#include "ctid/io/documents.h"
#include "ctid/io/json.h"
#include "ctid/io/mimo_frf_file.h"
#include "ctid/io/uff58.h"
#include "support/mimo_systems.h"

namespace ctid::cli::fit_frf_test {
namespace {

using ::testing::HasSubstr;

using ctid::testing::two_mode_structure;

class FitFrfCommand : public testing::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    MimoFrf frf;
    frf.frequencies = Eigen::VectorXd::LinSpaced(200, 0.05, 10.0);
    frf.response = mimo_frequency_response(two_mode_structure(), frf.frequencies);
    frf.input_names = {"101+X", "102+X"};
    frf.output_names = {"1+Z", "2+Z", "3+Z"};
    io::write_csv(path("h.csv"), io::mimo_frf_table(frf));
    // The UFF abscissa holds six digits: a grid exact in them (0.01 .. 1.6 Hz).
    frf.frequencies = 2.0 * M_PI * Eigen::VectorXd::LinSpaced(160, 0.01, 1.6);
    frf.response = mimo_frequency_response(two_mode_structure(), frf.frequencies);
    io::write_uff58(path("h.uff"), frf);
    // Noise only: nothing to fit.
    std::mt19937_64 rng(3);
    std::normal_distribution<double> normal;
    for (Eigen::MatrixXcd& h : frf.response) {
      for (Eigen::Index c = 0; c < h.size(); ++c) h(c) = {normal(rng), normal(rng)};
    }
    io::write_csv(path("noise.csv"), io::mimo_frf_table(frf));
  }
};

TEST_F(FitFrfCommand, SharedModesFromTheCsvTable) {
  const auto r = ctid({"fit-frf", "h.csv", "--modes", "2", "-o", "r.json"});
  ASSERT_EQ(r.status, 0) << r.err << r.out;
  EXPECT_THAT(r.out, HasSubstr("ctid fit-frf: converged"));
  EXPECT_THAT(r.out, HasSubstr("200 lines fitted, 2 inputs x 3 outputs"));
  EXPECT_THAT(r.out, HasSubstr("mode 1: f_n = 0.222817"));  // 1.4 / (2 pi) Hz
  EXPECT_THAT(r.out, HasSubstr("fit 3+Z: 100 % (101+X) 100 % (102+X)"));
  const nlohmann::json j = io::read_json(path("r.json"));
  EXPECT_EQ(j.at("type"), "frf_matrix_fit_result");
  EXPECT_EQ(j.at("data").at("outputs"), nlohmann::json({"1+Z", "2+Z", "3+Z"}));
  const auto back = std::get<FrfMatrixFitResult>(io::read_result(path("r.json")));
  ASSERT_EQ(back.modes.size(), 2u);
  EXPECT_NEAR(back.modes[1].natural_frequency, 4.0, 1e-8);
  EXPECT_NEAR(back.modes[1].damping_ratio, 0.05, 1e-8);
}

TEST_F(FitFrfCommand, PlotDrawsTheModelOverTheFittedFrfAndTheModes) {
  if (testing::python_package().empty()) {
    GTEST_SKIP() << "the ctid Python package is not built (CTID_BUILD_PYTHON=OFF); set "
                    "CTID_PYTHONPATH to test --plot";
  }
  const auto r = ctid({"fit-frf", "h.csv", "--modes", "2", "--plot", "figures"});
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* name : {"frf_matrix_overlay.png", "mode_shapes.png", "mac.png"}) {
    testing::expect_png(path("figures") / name);
    EXPECT_THAT(r.out, HasSubstr(std::string("wrote figures/") + name));
  }
  const auto again = ctid({"fit-frf", "h.csv", "--modes", "2", "--plot", "figures"});
  testing::expect_bad_input(again, "fit-frf", "frf_matrix_overlay.png: file exists");
}

TEST_F(FitFrfCommand, StartsFromAnEarlierResult) {
  ASSERT_EQ(ctid({"fit-frf", "h.csv", "--modes", "2", "-o", "r.json"}).status, 0);
  const auto r = ctid({"fit-frf", "h.csv", "--modes", "2", "--initial", "r.json"});
  ASSERT_EQ(r.status, 0) << r.err << r.out;
  EXPECT_THAT(r.out, HasSubstr("converged after 1 iterations"));
  EXPECT_THAT(r.out, ::testing::Not(HasSubstr("vector-fitting start")));
  testing::expect_bad_input(ctid({"fit-frf", "h.csv", "--modes", "3", "--initial", "r.json"}),
                            "fit-frf", "the initial model has 2 submodels; the structure has 3");
}

TEST_F(FitFrfCommand, SharedModesFromAUniversalFileInABand) {
  const auto r = ctid({"fit-frf", "h.uff", "--modes", "2", "--band", "0.1:1.5"});
  ASSERT_EQ(r.status, 0) << r.err << r.out;
  EXPECT_THAT(r.out, HasSubstr("(band 0.1:1.5 Hz), 2 inputs x 3 outputs"));
  EXPECT_THAT(r.out, HasSubstr("mode 2: f_n = 0.63662"));  // 4 / (2 pi) Hz
}

TEST_F(FitFrfCommand, UnusableFitExitsThree) {
  const auto r = ctid({"fit-frf", "noise.csv", "--modes", "2"});
  EXPECT_EQ(r.status, 3) << r.err << r.out;
  EXPECT_THAT(r.out, HasSubstr("WARNING: no usable model"));
}

TEST_F(FitFrfCommand, BadUsageNamesTheProblem) {
  testing::expect_bad_input(ctid({"fit-frf", "h.csv"}), "fit-frf", "give the structure");
  testing::expect_bad_input(ctid({"fit-frf", "h.csv", "--modes", "0"}), "fit-frf",
                            "--modes must be at least 1");
  testing::expect_bad_input(ctid({"fit-frf", "h.csv", "--modes", "2", "--band", "3:1"}), "fit-frf",
                            "--band '3:1': expected LO:HI");
  testing::expect_bad_input(ctid({"fit-frf", "h.csv", "--submodel", "3,1"}), "fit-frf",
                            "n = 1 or 2");
  testing::expect_bad_input(ctid({"fit-frf", "h.csv", "--modes", "2", "--band", "1.58:1.6"}),
                            "fit-frf", "in the band are too few");
  testing::expect_bad_input(ctid({"fit-frf", "h.csv", "--modes", "2", "--weighting", "variance"}),
                            "fit-frf", "weighting 'variance' needs the FRF's variance");
}

}  // namespace
}  // namespace ctid::cli::fit_frf_test
