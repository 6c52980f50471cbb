// SSI-cov on exact correlations of a known discrete stochastic model (the Lyapunov solution):
// the model's continuous poles and shapes come back to rounding at every order >= the true one.
#include "ctid/oma/ssi_cov.h"

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "oma/chain_model.h"

namespace ctid::ssi_cov_test {
namespace {

using oma_test::ChainModel;

void expect_true_modes(const std::vector<oma_detail::ModalPole>& poles, const ChainModel& model,
                       double tolerance) {
  for (const auto& mode : model.modes) {
    const oma_detail::ModalPole* best = nullptr;
    for (const auto& p : poles) {
      if (best == nullptr || std::abs(p.frequency_hz - mode.frequency_hz) <
                                 std::abs(best->frequency_hz - mode.frequency_hz)) {
        best = &p;
      }
    }
    ASSERT_NE(best, nullptr);
    EXPECT_NEAR(best->frequency_hz / mode.frequency_hz, 1.0, tolerance);
    EXPECT_NEAR(best->damping_ratio / mode.damping_ratio, 1.0, tolerance);
    EXPECT_NEAR((best->shape - mode.shape).cwiseAbs().maxCoeff(), 0.0, tolerance);
  }
}

TEST(SsiCov, ExactCorrelationsGiveTheModelsModesAtTheTrueOrder) {
  const ChainModel model;
  for (const std::vector<int>& refs : {std::vector<int>{0, 1, 2, 3}, std::vector<int>{1, 3}}) {
    const int p = 12;
    const auto r = model.correlations(refs, 2 * p - 1);
    const auto factor = oma_detail::ssi_factor(r, p, 8);
    const auto poles = oma_detail::ssi_poles(factor, 8, model.h, 0.2);
    ASSERT_EQ(poles.size(), model.modes.size());
    expect_true_modes(poles, model, 1e-10);
  }
}

TEST(SsiCov, HigherOrdersFromTheSameFactorKeepTheTrueModes) {
  const ChainModel model;
  const int p = 12;
  const auto r = model.correlations({0, 1, 2, 3}, 2 * p - 1);
  const auto factor = oma_detail::ssi_factor(r, p, 20);
  for (int n = 8; n <= 20; n += 2) {
    SCOPED_TRACE(n);
    // Beyond the numerical rank of H the extra singular directions are rounding noise; those
    // orders are identified at the rank, so the model comes back to rounding at every one.
    expect_true_modes(oma_detail::ssi_poles(factor, n, model.h, 0.2), model, 1e-10);
  }
}

TEST(SsiCov, FftCorrelationsEqualTheLagSums) {
  const ChainModel model;
  const Eigen::MatrixXd y = model.simulate(500, 0.1, 3);
  const auto r = oma_detail::output_correlations(y, {0, 2}, 7);
  const Eigen::RowVectorXd mean = y.colwise().mean();
  for (int i = 1; i <= 7; ++i) {
    Eigen::MatrixXd direct = Eigen::MatrixXd::Zero(4, 2);
    for (int k = 0; k + i < y.rows(); ++k) {
      const Eigen::VectorXd a = (y.row(k + i) - mean).transpose();
      const Eigen::VectorXd b = (y.row(k) - mean).transpose();
      direct.col(0) += a * b(0);
      direct.col(1) += a * b(2);
    }
    direct /= static_cast<double>(y.rows());
    EXPECT_LT((r[static_cast<std::size_t>(i - 1)] - direct).cwiseAbs().maxCoeff(),
              1e-12 * direct.cwiseAbs().maxCoeff());
  }
}

TEST(SsiCov, IndicatorsOfARealShapeAndARotatedOne) {
  Eigen::VectorXcd real(3);
  real << 1.0, -0.5, 0.25;
  EXPECT_NEAR(oma_detail::modal_phase_collinearity(real), 1.0, 1e-15);
  EXPECT_NEAR(oma_detail::mean_phase_deviation(real), 0.0, 1e-12);
  const Eigen::VectorXcd rotated = real * std::polar(2.0, 0.7);
  EXPECT_NEAR(oma_detail::modal_phase_collinearity(rotated), 1.0, 1e-12);
  EXPECT_NEAR(oma_detail::mean_phase_deviation(rotated), 0.0, 1e-9);
  const Eigen::VectorXcd n = oma_detail::normalise_shape(rotated);
  EXPECT_EQ(n(0), std::complex<double>(1.0, 0.0));
  EXPECT_NEAR((n - real).cwiseAbs().maxCoeff(), 0.0, 1e-15);
  Eigen::VectorXcd complex_shape(2);
  complex_shape << 1.0, std::complex<double>(0.0, 1.0);
  EXPECT_NEAR(oma_detail::modal_phase_collinearity(complex_shape), 0.0, 1e-15);
  EXPECT_NEAR(oma_detail::mean_phase_deviation(complex_shape), 45.0, 1e-9);
}

}  // namespace
}  // namespace ctid::ssi_cov_test
