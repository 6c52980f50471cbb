// The modal model fitted to an FRF matrix (frf_matrix_fit.h): exact recovery of the Section 6.1
// modes with random shapes (3 inputs x 5 outputs) and of eight lightly damped modes over
// 2 inputs x 28 outputs from noise-free FRFs, the direct term, standard errors against the
// spread of a seeded Monte Carlo, and one clear message for each kind of bad input.
#include "ctid/frf_fit/frf_matrix_fit.h"

#include <cmath>
#include <complex>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/estimation/mimo_modes.h"
#include "support/mimo_systems.h"
#include "support/paper_systems.h"
#include "support/sanitizers.h"

namespace ctid::frf_matrix_fit_test {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

using testing::four_mode_beam;

using testing::eight_mode_structure;

MimoFrf frf_of(const MimoAdditiveModel& g, const Eigen::VectorXd& w) {
  MimoFrf frf;
  frf.frequencies = w;
  frf.response = mimo_frequency_response(g, w);
  for (int k = 0; k < g.inputs(); ++k) frf.input_names.push_back("u" + std::to_string(k + 1));
  for (int j = 0; j < g.outputs(); ++j) frf.output_names.push_back("y" + std::to_string(j + 1));
  for (Eigen::Index l = 0; l < w.size(); ++l) {
    frf.variance.push_back(Eigen::MatrixXd::Ones(g.outputs(), g.inputs()));
  }
  return frf;
}

// Every w_n, zeta and residue entry of `estimate` against `truth` (same mode order), the largest
// relative error (residues relative to the largest of their mode's).
double largest_modal_error(const FrfMatrixFitResult& estimate, const MimoAdditiveModel& truth,
                           const std::vector<SubmodelOrder>& orders) {
  const std::vector<MimoMode> expected = mimo_modes(truth, orders);
  EXPECT_EQ(estimate.modes.size(), expected.size());
  double worst = 0.0;
  for (size_t i = 0; i < std::min(expected.size(), estimate.modes.size()); ++i) {
    const MimoMode& x = estimate.modes[i];
    const MimoMode& y = expected[i];
    worst = std::max(worst, std::abs(x.natural_frequency / y.natural_frequency - 1.0));
    worst = std::max(worst, std::abs(x.damping_ratio / y.damping_ratio - 1.0));
    // Residue matrix = shape * participation^T.
    const Eigen::MatrixXcd rx = x.shape * x.participation.transpose();
    const Eigen::MatrixXcd ry = y.shape * y.participation.transpose();
    worst = std::max(worst, (rx - ry).cwiseAbs().maxCoeff() / ry.cwiseAbs().maxCoeff());
  }
  return worst;
}

Eigen::VectorXd grid(double lo, double hi, int lines) {
  return Eigen::VectorXd::LinSpaced(lines, lo, hi);
}

TEST(FrfMatrixFit, ResponseOfADelayedModelIsThatOfItsChannels) {
  const MimoAdditiveModel g =
      four_mode_beam(3, 2, 5).with_input_delays(Eigen::Vector3d(0.0, 0.02, 0.135));
  const Eigen::VectorXd w = grid(0.1, 20.0, 7);
  const std::vector<Eigen::MatrixXcd> h = mimo_frequency_response(g, w);
  for (Eigen::Index l = 0; l < w.size(); ++l) {
    for (int j = 0; j < 2; ++j) {
      for (int k = 0; k < 3; ++k) {
        const std::complex<double> expected =
            g.channel(j, k).to_transfer_function().frequency_response(w(l));
        EXPECT_LT(std::abs(h[static_cast<size_t>(l)](j, k) - expected), 1e-12 * std::abs(expected));
      }
    }
  }
}

TEST(FrfMatrixFit, NoiseFreeThreeInputFiveOutputBeamIsRecoveredExactly) {
  const MimoAdditiveModel truth = four_mode_beam(3, 5, 11);
  const std::vector<SubmodelOrder> orders(4, {2, 0, 0});
  const FrfMatrixFitResult r = frf_matrix_fit(frf_of(truth, grid(0.05, 20.0, 400)), orders);
  ASSERT_TRUE(r.model.has_value()) << r.message;
  EXPECT_TRUE(r.converged()) << r.message;
  EXPECT_TRUE(r.verdict.usable) << r.verdict.summary();
  EXPECT_LT(largest_modal_error(r, truth, orders), 1e-9);
  EXPECT_GT(r.fit_percent.minCoeff(), 99.9999);
}

TEST(FrfMatrixFit, NoiseFreeTwoInputTwentyEightOutputEightModesAreRecoveredExactly) {
  CTID_SKIP_UNDER_SANITIZERS("the smaller FrfMatrixFit cases run the same fit");
  for (bool general : {false, true}) {
    const MimoAdditiveModel truth = eight_mode_structure(28, 3, general);
    const std::vector<SubmodelOrder> orders(8, {2, general ? 1 : 0, 0});
    const FrfMatrixFitResult r = frf_matrix_fit(frf_of(truth, grid(0.2, 20.0, 500)), orders);
    ASSERT_TRUE(r.model.has_value()) << r.message;
    EXPECT_TRUE(r.converged()) << r.message;
    EXPECT_LT(largest_modal_error(r, truth, orders), 1e-9) << (general ? "b0 + b1 p" : "b0");
  }
}

TEST(FrfMatrixFit, DirectTermAndGeneralNumeratorsAreRecoveredExactly) {
  // Accelerance-like: b_0 + b_1 p over each mode plus a direct term D.
  const MimoAdditiveModel base = eight_mode_structure(4, 9, true);
  std::vector<MimoSubmodel> three(base.submodels().begin(), base.submodels().begin() + 3);
  Eigen::MatrixXd d(4, 2);
  d << 0.5, -0.2, 0.1, 0.7, -0.3, 0.25, 0.05, -0.6;
  const MimoAdditiveModel truth(2, 4, three, d);
  const std::vector<SubmodelOrder> orders(3, {2, 1, 0});
  FrfMatrixFitOptions options;
  options.direct_term = true;
  const FrfMatrixFitResult r = frf_matrix_fit(frf_of(truth, grid(0.2, 8.0, 300)), orders, options);
  ASSERT_TRUE(r.model.has_value()) << r.message;
  EXPECT_TRUE(r.converged()) << r.message;
  EXPECT_LT(largest_modal_error(r, truth, orders), 1e-9);
  EXPECT_LT((r.model->direct() - d).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(FrfMatrixFit, RealPolesAndModesTogetherAreRecoveredExactly) {
  // A real pole (n = 1) between two modes: grouped by the start, kept out of the mode table.
  const MimoAdditiveModel modes = eight_mode_structure(3, 2, true);
  MimoSubmodel real{Polynomial{1.0, 1.0 / 2.5}, {}};
  for (int c = 0; c < 6; ++c) real.b.push_back(Polynomial{0.3 * (c + 1) - 1.0});
  const MimoAdditiveModel truth(2, 3, {modes[0], real, modes[3]});
  const std::vector<SubmodelOrder> orders{{2, 1, 0}, {1, 0, 0}, {2, 1, 0}};
  const FrfMatrixFitResult r = frf_matrix_fit(frf_of(truth, grid(0.1, 10.0, 200)), orders);
  ASSERT_TRUE(r.model.has_value()) << r.message;
  EXPECT_TRUE(r.converged()) << r.message;
  EXPECT_EQ(r.modes.size(), 2u);
  EXPECT_LT(largest_modal_error(r, truth, orders), 1e-9);
  EXPECT_NEAR((*r.model)[1].a[1], 0.4, 1e-10);
  EXPECT_NEAR(r.model->numerator(1, 2, 1)[0], 0.8, 1e-9);
}

TEST(FrfMatrixFit, AModeTheDataDoNotHoldIsRefusedInTheFitsOwnTerms) {
  // Two modes in the data, three in the structure: the third has no residue to fit, and vector
  // fitting puts a pole at the origin. That is a verdict in the FRF fit's own words (the
  // lines, a band), not an exception and not a time-domain estimator's wording.
  const MimoAdditiveModel modes = eight_mode_structure(3, 2, true);
  const MimoAdditiveModel truth(2, 3, {modes[0], modes[3]});
  const FrfMatrixFitResult r =
      frf_matrix_fit(frf_of(truth, grid(0.1, 10.0, 200)), std::vector<SubmodelOrder>(3, {2, 1, 0}));
  EXPECT_FALSE(r.verdict.usable);
  EXPECT_EQ(r.termination, Termination::no_solution);
  EXPECT_FALSE(r.model.has_value());
  const std::string summary = r.verdict.summary();
  EXPECT_THAT(summary, HasSubstr("the vector-fitting start placed a pole at the origin or at "
                                 "infinity: the 200 lines do not show as many modes"));
  EXPECT_THAT(summary, HasSubstr("a band (--band)"));
  EXPECT_THAT(summary, ::testing::Not(HasSubstr("instrument-regressor")));
}

TEST(FrfMatrixFit, BandLimitsTheLinesFitted) {
  const MimoAdditiveModel truth = four_mode_beam(2, 3, 4);
  FrfMatrixFitOptions options;
  options.min_frequency = 0.5;
  options.max_frequency = 15.0;
  const FrfMatrixFitResult r = frf_matrix_fit(frf_of(truth, grid(0.05, 20.0, 400)),
                                              std::vector<SubmodelOrder>(4, {2, 0, 0}), options);
  const Eigen::VectorXd w = grid(0.05, 20.0, 400);
  EXPECT_EQ(r.lines, (w.array() >= 0.5 && w.array() <= 15.0).count());
  EXPECT_LT(largest_modal_error(r, truth, std::vector<SubmodelOrder>(4, {2, 0, 0})), 1e-9);
}

TEST(FrfMatrixFit, ALineAtZeroFrequencyIsFitted) {
  // Analysers export the DC line too; it is a line like any other (s = 0).
  const MimoAdditiveModel truth = four_mode_beam(2, 3, 6);
  const std::vector<SubmodelOrder> orders(4, {2, 0, 0});
  const FrfMatrixFitResult r = frf_matrix_fit(frf_of(truth, grid(0.0, 20.0, 401)), orders);
  EXPECT_TRUE(r.converged()) << r.message;
  EXPECT_LT(largest_modal_error(r, truth, orders), 1e-9);
}

// Seeded Monte Carlo: complex white noise of a different level on each output, correlated
// between the outputs (as the errors of one H1 estimate are); the spread of
// w_n, zeta and the shape entries over the runs against the mean reported standard error, and
// the mean of w_n and zeta against the truth. 200 runs: the spread's own sampling error is
// about 5 %, so a 20 % band.
TEST(FrfMatrixFit, StandardErrorsMatchTheSpreadOfASeededMonteCarlo) {
  CTID_SKIP_UNDER_SANITIZERS("a Monte Carlo of fits the other FrfMatrixFit tests run once");
  const MimoAdditiveModel truth = four_mode_beam(2, 4, 21);
  const std::vector<SubmodelOrder> orders(4, {2, 0, 0});
  const MimoFrf clean = frf_of(truth, grid(0.05, 20.0, 300));
  const double levels[] = {0.01, 0.03, 0.02, 0.05};
  constexpr int kRuns = 200;
  const int modes = 4;
  Eigen::MatrixXd w(kRuns, modes), z(kRuns, modes), w_se(kRuns, modes), z_se(kRuns, modes);
  // Real parts of every shape entry (mode i, output j at column 4 i + j) and their errors.
  Eigen::MatrixXd shape(kRuns, 4 * modes), shape_se(kRuns, 4 * modes);
  std::mt19937_64 rng(2026);
  std::normal_distribution<double> normal;
  for (int run = 0; run < kRuns; ++run) {
    MimoFrf noisy = clean;
    for (Eigen::MatrixXcd& h : noisy.response) {
      for (int k = 0; k < h.cols(); ++k) {
        // A share common to the outputs: their errors correlate by 0.8 at each line and input.
        const std::complex<double> common(normal(rng), normal(rng));
        for (int j = 0; j < h.rows(); ++j) {
          const std::complex<double> own(normal(rng), normal(rng));
          h(j, k) += levels[j] / std::sqrt(2.0) * (0.8 * common + 0.6 * own);
        }
      }
    }
    const FrfMatrixFitResult r = frf_matrix_fit(noisy, orders, {}, truth);
    ASSERT_EQ(static_cast<int>(r.modes.size()), modes) << r.message;
    for (int i = 0; i < modes; ++i) {
      w(run, i) = r.modes[static_cast<size_t>(i)].natural_frequency;
      z(run, i) = r.modes[static_cast<size_t>(i)].damping_ratio;
      w_se(run, i) = r.modes[static_cast<size_t>(i)].natural_frequency_se;
      z_se(run, i) = r.modes[static_cast<size_t>(i)].damping_ratio_se;
      for (int j = 0; j < 4; ++j) {
        shape(run, 4 * i + j) = r.modes[static_cast<size_t>(i)].shape(j).real();
        shape_se(run, 4 * i + j) = r.modes[static_cast<size_t>(i)].shape_se_real(j);
      }
    }
  }
  const std::vector<MimoMode> expected = mimo_modes(truth, orders);
  const auto spread = [](const Eigen::VectorXd& x) {
    return std::sqrt((x.array() - x.mean()).square().sum() / (x.size() - 1.0));
  };
  for (int i = 0; i < modes; ++i) {
    const double ws = spread(w.col(i));
    const double zs = spread(z.col(i));
    for (int j = 0; j < 4; ++j) {
      EXPECT_NEAR(spread(shape.col(4 * i + j)) / shape_se.col(4 * i + j).mean(), 1.0, 0.2)
          << "Re shape entry " << j + 1 << " of mode " << i + 1;
    }
    EXPECT_NEAR(ws / w_se.col(i).mean(), 1.0, 0.2) << "w_n of mode " << i + 1;
    EXPECT_NEAR(zs / z_se.col(i).mean(), 1.0, 0.2) << "zeta of mode " << i + 1;
    // No bias beyond 4 standard errors of the mean.
    EXPECT_LT(std::abs(w.col(i).mean() - expected[static_cast<size_t>(i)].natural_frequency),
              4.0 * ws / std::sqrt(kRuns));
    EXPECT_LT(std::abs(z.col(i).mean() - expected[static_cast<size_t>(i)].damping_ratio),
              4.0 * zs / std::sqrt(kRuns));
  }
}

TEST(FrfMatrixFit, VarianceWeightingWithTheTrueVariancesGivesUnitNoiseLevel) {
  const MimoAdditiveModel truth = four_mode_beam(2, 3, 8);
  MimoFrf frf = frf_of(truth, grid(0.05, 20.0, 400));
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  for (size_t l = 0; l < frf.response.size(); ++l) {
    // Relative noise: 1 % of each entry's size, so the levels differ by orders of magnitude.
    const Eigen::MatrixXd sd = 0.01 * frf.response[l].cwiseAbs();
    frf.variance[l] = sd.cwiseAbs2();
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 2; ++k) {
        frf.response[l](j, k) +=
            sd(j, k) / std::sqrt(2.0) * std::complex<double>(normal(rng), normal(rng));
      }
    }
  }
  FrfMatrixFitOptions options;
  options.weighting = FrfWeighting::variance;
  const FrfMatrixFitResult r =
      frf_matrix_fit(frf, std::vector<SubmodelOrder>(4, {2, 0, 0}), options);
  EXPECT_TRUE(r.converged()) << r.message;
  EXPECT_TRUE(r.verdict.usable) << r.verdict.summary();
  for (int j = 0; j < 3; ++j) EXPECT_NEAR(r.noise_variance(j), 1.0, 0.15);
}

TEST(FrfMatrixFit, BadInputGetsOneClearMessage) {
  const MimoAdditiveModel truth = four_mode_beam(2, 3, 4);
  const MimoFrf good = frf_of(truth, grid(0.05, 20.0, 100));
  const std::vector<SubmodelOrder> four(4, {2, 0, 0});
  const auto fails = [&](const MimoFrf& frf, const std::vector<SubmodelOrder>& orders,
                         const FrfMatrixFitOptions& options, const char* text) {
    EXPECT_THAT([&] { frf_matrix_fit(frf, orders, options); },
                ThrowsMessage<InvalidArgument>(HasSubstr(text)));
  };
  MimoFrf frf = good;
  frf.response[7] = Eigen::MatrixXcd::Zero(2, 2);
  fails(frf, four, {}, "the response at frequency 8 is 2 x 2 but the FRF names 3 outputs and 2");
  frf = good;
  frf.response[3](1, 1) = std::complex<double>(std::nan(""), 0.0);
  fails(frf, four, {}, "the response at frequency 4");
  frf = good;
  frf.frequencies(5) = frf.frequencies(4);
  fails(frf, four, {}, "the frequencies must increase");
  frf = good;
  frf.frequencies(0) = -0.1;
  fails(frf, four, {},
        "frequency 1 is -0.1 rad/s; every frequency must be finite and not negative");
  frf = good;
  frf.response.pop_back();
  fails(frf, four, {}, "99 response matrices for 100 frequencies");
  fails(good, std::vector<SubmodelOrder>(50, {2, 0, 0}), {}, "100 lines are too few for 100 poles");
  fails(good, {{3, 0, 0}}, {}, "n = 1 or 2");
  fails(good, {{2, 3, 0}}, {}, "m = 3 > n = 2");
  fails(good, {{2, 0, 1}}, {}, "integrators");
  fails(good, {}, {}, "no submodels");
  FrfMatrixFitOptions direct;
  direct.direct_term = true;
  fails(good, {{2, 2, 0}}, direct, "counted twice");
  FrfMatrixFitOptions band;
  band.min_frequency = 10.0;
  band.max_frequency = 5.0;
  fails(good, four, band, "min_frequency 10 rad/s is not below max_frequency 5");
  band.min_frequency = 19.9;
  band.max_frequency = 0.0;
  fails(good, four, band, "in the band are too few");
  FrfMatrixFitOptions weighted;
  weighted.weighting = FrfWeighting::variance;
  frf = good;
  frf.variance.clear();
  fails(frf, four, weighted, "weighting 'variance' needs the FRF's variance");
  FrfMatrixFitOptions bad;
  bad.max_iterations = 0;
  fails(good, four, bad, "max_iterations");
  EXPECT_THAT([&] { frf_matrix_fit(good, four, {}, four_mode_beam(2, 4, 1)); },
              ThrowsMessage<InvalidArgument>(
                  HasSubstr("the initial model is 4 x 2 but the FRF is 3 x 2 (outputs x inputs)")));
}

}  // namespace
}  // namespace ctid::frf_matrix_fit_test
