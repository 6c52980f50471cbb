// Step 1 of the delayed-feedback identification: regressors, batch LS and RLS.
#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/QR>
#include <unsupported/Eigen/MatrixFunctions>

#include "ctid/core/error.h"
#include "ctid/delayed_feedback/least_squares.h"
#include "ctid/delayed_feedback/regressors.h"
#include "ctid/simulation/delayed_feedback.h"
#include "support/de_iuliis_systems.h"

namespace ctid::step1_test {
namespace {

// max over the excited band of |Ŵ - W| / |W|: the closed loop is what step 1 identifies; its
// 3q - 1 coefficients are not well determined one by one (e^{-Δs} is nearly polynomial on the
// band, so β and γ can trade large amounts at almost no cost in the equation error).
double closed_loop_error(const ClosedLoopEstimate& est, const DelayedFeedbackLoop& loop,
                         double max_frequency) {
  double worst = 0.0;
  for (double w = 0.05; w <= max_frequency; w *= 1.2) {
    const std::complex<double> s(0.0, w);
    const std::complex<double> truth = loop.closed_loop_response(s);
    const std::complex<double> fit =
        est.alpha(s) / (est.beta(s) + est.gamma(s) * std::exp(-loop.delay * s));
    worst = std::max(worst, std::abs(fit - truth) / std::abs(truth));
  }
  return worst;
}

DelayedFeedbackLoop paper_loop() { return test_support::paper_feedback_loop(); }

SampledData fourier_data(const DelayedFeedbackLoop& loop, double delta, double duration,
                         double period) {
  const int samples = static_cast<int>(std::lround(duration / delta)) + 1;
  const FourierBasisInput input{12, period};
  Eigen::VectorXd u(samples);
  for (int k = 0; k < samples; ++k) u(k) = input(k * delta);
  const Eigen::VectorXd y = simulate_delayed(
      to_delayed_state_space(loop), std::function<double(double)>(input), delta, samples,
      DelayedSimulationOptions{std::max(2, static_cast<int>(std::lround(delta / 0.0025)))});
  return SampledData(delta, u, y);
}

TEST(FeedbackRegressors, ChainStepMatchesMatrixExponential) {
  for (int q : {1, 3, 6}) {
    for (double tau : {0.05, 0.013, 1.7}) {
      const FilterStep chain = integrator_chain_step(q, tau);
      Eigen::MatrixXd m = Eigen::MatrixXd::Zero(q + 2, q + 2);
      for (int i = 0; i + 1 < q; ++i) m(i, i + 1) = 1.0;
      m(q - 1, q) = 1.0;
      m(q, q + 1) = 1.0;
      const Eigen::MatrixXd e = (m * tau).exp();
      EXPECT_LT((chain.a - e.topLeftCorner(q, q)).norm(), 1e-13 * e.norm());
      EXPECT_LT((chain.b - e.block(0, q, q, 1)).norm(), 1e-13 * e.norm());
      EXPECT_LT((chain.g - e.block(0, q + 1, q, 1)).norm(), 1e-13 * e.norm());
    }
  }
}

TEST(FeedbackRegressors, ChainIntegratesLinearSignalsExactly) {
  // y(t) = 1 + 2t is reproduced exactly by piecewise-linear interpolation, so the chain
  // states are its exact repeated integrals: v_i = t^r/r! + 2 t^{r+1}/(r+1)!, r = q - i + 1.
  const int q = 4;
  const double delta = 0.1;
  const FilterStep step = integrator_chain_step(q, delta);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(q);
  for (int k = 0; k < 30; ++k) x = step.a * x + step.b * (1.0 + 2.0 * k * delta) + step.g * 2.0;
  const double t = 30 * delta;
  for (int i = 0; i < q; ++i) {
    const int r = q - i;
    const double expected =
        std::pow(t, r) / std::tgamma(r + 1.0) + 2.0 * std::pow(t, r + 1) / std::tgamma(r + 2.0);
    EXPECT_NEAR(x(i), expected, 1e-12 * expected);
  }
}

TEST(FeedbackRegressors, IntegralFilterWithZeroPoleIsTheChainAndLimitIsSmooth) {
  const FilterStep a = integral_filter_step(5, 1e-9, 0.05);
  const FilterStep b = integrator_chain_step(5, 0.05);
  EXPECT_LT((a.a - b.a).norm(), 1e-8);
  EXPECT_LT((a.g - b.g).norm(), 1e-8);
}

TEST(FeedbackRegressors, EquationErrorAtTrueThetaIsSmallOnlyWithBoundaryTerms) {
  // The paper's record: the piecewise-linear boundary terms make y - C θ_true large; the
  // nuisance columns absorb them (FEEDBACK-DELAY-NOTES.md).
  const DelayedFeedbackLoop loop = paper_loop();
  const SampledData data = fourier_data(loop, 0.05, 5.0, 5.0);
  const Eigen::VectorXd theta = closed_loop_theta(loop.alpha(), loop.beta(), loop.gamma());
  const FeedbackRegression plain = build_feedback_regression(data, 3, 3, 0.5);
  EXPECT_EQ(plain.regressor.rows(), 91);
  EXPECT_EQ(plain.regressor.cols(), 17);
  const double y_rms = plain.target.norm() / std::sqrt(91.0);
  const double e_plain = (plain.target - plain.regressor * theta).norm() / std::sqrt(91.0);
  FeedbackRegressorOptions with_terms;
  with_terms.initial_condition_terms = true;
  const FeedbackRegression aug = build_feedback_regression(data, 3, 3, 0.5, with_terms);
  EXPECT_EQ(aug.nuisance_size, 6);
  const Eigen::VectorXd rest = aug.target - aug.regressor.leftCols(17) * theta;
  const Eigen::VectorXd eta = aug.regressor.rightCols(6).colPivHouseholderQr().solve(rest);
  const double e_aug = (rest - aug.regressor.rightCols(6) * eta).norm() / std::sqrt(91.0);
  EXPECT_GT(e_plain, 0.5 * y_rms);
  EXPECT_LT(e_aug, 0.05 * e_plain);
}

TEST(FeedbackRegressors, FineSamplingMakesTheEquationHoldAtTrueTheta) {
  const DelayedFeedbackLoop loop = paper_loop();
  const SampledData data = fourier_data(loop, 0.005, 5.0, 5.0);
  const Eigen::VectorXd theta = closed_loop_theta(loop.alpha(), loop.beta(), loop.gamma());
  FeedbackRegressorOptions options;
  options.filter = RegressorFilter::linear_integral_filter;
  options.filter_pole = 2.0;
  options.initial_condition_terms = true;
  const FeedbackRegression reg = build_feedback_regression(data, 3, 3, 0.5, options);
  const Eigen::VectorXd rest = reg.target - reg.regressor.leftCols(17) * theta;
  const Eigen::VectorXd eta =
      reg.regressor.rightCols(reg.nuisance_size).colPivHouseholderQr().solve(rest);
  EXPECT_LT((rest - reg.regressor.rightCols(reg.nuisance_size) * eta).norm(),
            1e-3 * reg.target.norm());
}

TEST(FeedbackLeastSquares, RecoversClosedLoopOnAnInformativeExperiment) {
  // Three periods of a 10 s Fourier input sampled at 10 ms, fractional delay 0.503 s.
  DelayedFeedbackLoop loop = paper_loop();
  loop.delay = 0.503;
  const SampledData data = fourier_data(loop, 0.01, 30.0, 10.0);
  FeedbackRegressorOptions options;
  options.filter = RegressorFilter::linear_integral_filter;
  options.filter_pole = 2.0;
  options.initial_condition_terms = true;
  const FeedbackRegression reg = build_feedback_regression(data, 3, 3, 0.503, options);
  const ClosedLoopEstimate est = estimate_closed_loop_batch(reg);
  EXPECT_LT(closed_loop_error(est, loop, 7.5), 2e-3);  // harmonics up to 7.5 rad/s
  EXPECT_LT(est.residual_rms, 1e-3 * reg.target.norm() / std::sqrt(reg.target.size()));
  BatchLeastSquaresOptions svd;
  svd.solver = LeastSquaresSolver::svd;
  EXPECT_LT(closed_loop_error(estimate_closed_loop_batch(reg, svd), loop, 7.5), 2e-3);
}

TEST(FeedbackLeastSquares, RlsWithUnitForgettingEqualsRegularisedBatch) {
  // With λ = 1, RLS from (θ0, P0) minimises |y - Cθ|² + (θ - θ0)' P0^{-1} (θ - θ0).
  const DelayedFeedbackLoop loop = paper_loop();
  const SampledData data = fourier_data(loop, 0.05, 10.0, 5.0);
  FeedbackRegressorOptions ro;
  ro.filter = RegressorFilter::linear_integral_filter;
  ro.filter_pole = 1.0;
  const FeedbackRegression reg = build_feedback_regression(data, 3, 3, 0.5, ro);
  const int p = reg.theta_size;
  Eigen::VectorXd theta0 = Eigen::VectorXd::LinSpaced(p, -1.0, 1.0);
  Eigen::VectorXd p_diag = Eigen::VectorXd::LinSpaced(p, 0.5, 20.0);
  RecursiveLeastSquaresOptions options;
  options.forgetting = 1.0;
  options.initial_theta = theta0;
  options.initial_covariance_matrix = Eigen::MatrixXd(p_diag.asDiagonal());
  options.keep_history = true;
  const ClosedLoopEstimate rls = estimate_closed_loop_recursive(reg, options);
  Eigen::MatrixXd stacked(reg.regressor.rows() + p, p);
  Eigen::VectorXd rhs(reg.regressor.rows() + p);
  stacked << reg.regressor, Eigen::MatrixXd(p_diag.cwiseSqrt().cwiseInverse().asDiagonal());
  rhs << reg.target, theta0.cwiseQuotient(p_diag.cwiseSqrt());
  const Eigen::VectorXd batch = stacked.colPivHouseholderQr().solve(rhs);
  EXPECT_LT((rls.theta - batch).norm(), 1e-7 * batch.norm());
  EXPECT_EQ(static_cast<int>(rls.theta_history.size()), reg.regressor.rows());
  EXPECT_EQ(rls.theta_history.back(), rls.theta);
}

TEST(FeedbackLeastSquares, GcvRidgeStaysCloseOnCleanData) {
  DelayedFeedbackLoop loop = paper_loop();
  const SampledData data = fourier_data(loop, 0.01, 30.0, 10.0);
  FeedbackRegressorOptions ro;
  ro.filter = RegressorFilter::linear_integral_filter;
  ro.filter_pole = 2.0;
  ro.initial_condition_terms = true;
  const FeedbackRegression reg = build_feedback_regression(data, 3, 3, 0.5, ro);
  BatchLeastSquaresOptions options;
  options.regularisation = Regularisation::gcv;
  const ClosedLoopEstimate est = estimate_closed_loop_batch(reg, options);
  EXPECT_LT(closed_loop_error(est, loop, 7.5), 5e-3);
  EXPECT_GT(est.ridge, 0.0);
  // A heavy fixed ridge shrinks θ: the fit gets visibly worse, so the weight is used.
  options.regularisation = Regularisation::fixed;
  options.ridge = 1e-2;
  EXPECT_GT(closed_loop_error(estimate_closed_loop_batch(reg, options), loop, 7.5), 1e-2);
}

TEST(FeedbackLeastSquares, BadInputIsNamed) {
  const DelayedFeedbackLoop loop = paper_loop();
  const SampledData data = fourier_data(loop, 0.05, 5.0, 5.0);
  using ::testing::HasSubstr;
  using ::testing::ThrowsMessage;
  EXPECT_THAT([&] { build_feedback_regression(data, 0, 3, 0.5); },
              ThrowsMessage<InvalidArgument>(HasSubstr("forward order n must be >= 1")));
  EXPECT_THAT([&] { build_feedback_regression(data, 3, 0, 0.5); },
              ThrowsMessage<InvalidArgument>(HasSubstr("feedback order m must be >= 1")));
  EXPECT_THAT([&] { build_feedback_regression(data, 3, 3, -0.1); },
              ThrowsMessage<InvalidArgument>(HasSubstr("delay must be finite and >= 0")));
  EXPECT_THAT([&] { build_feedback_regression(data, 3, 3, 6.0); },
              ThrowsMessage<InvalidArgument>(HasSubstr("longer than the delay")));
  EXPECT_THAT([&] { build_feedback_regression(data.segment(0, 20), 3, 3, 0.5); },
              ThrowsMessage<InvalidArgument>(HasSubstr("too few samples")));
  // A singular regressor is a numerical outcome, not bad input: a result, never an exception.
  const SampledData zero(0.05, Eigen::VectorXd::Zero(101), Eigen::VectorXd::Zero(101));
  const ClosedLoopEstimate singular =
      estimate_closed_loop_batch(build_feedback_regression(zero, 3, 3, 0.5));
  EXPECT_EQ(singular.termination, Termination::singular_equations);
  EXPECT_THAT(singular.message, HasSubstr("singular regressor"));
  RecursiveLeastSquaresOptions rls;
  rls.forgetting = 1.5;
  EXPECT_THAT([&] { rls.validate(); },
              ThrowsMessage<InvalidArgument>(HasSubstr(
                  "RecursiveLeastSquaresOptions.forgetting is 1.5; it must be in (0, 1]")));
}

}  // namespace
}  // namespace ctid::step1_test
