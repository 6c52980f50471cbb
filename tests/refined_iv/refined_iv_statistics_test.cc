// Statistical behaviour of the refined IV estimators on noisy data (small seeded Monte Carlo
// runs), automatic initialisation, delay scanning and the handling of bad input.
#include <cmath>
#include <random>

#include <Eigen/Dense>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/estimation/validation.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/input_delay_scan.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"
#include "support/paper_systems.h"
#include "support/sanitizers.h"

namespace ctid::refined_iv_statistics_test {
namespace {

using ::testing::HasSubstr;

Eigen::VectorXd perturbed(const Eigen::VectorXd& beta, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-0.05, 0.05);
  Eigen::VectorXd out = beta;
  for (Eigen::Index k = 0; k < out.size(); ++k) out(k) *= 1.0 + uniform(rng);
  return out;
}

// [a_i1, a_i2, b_i0] of every submodel: comparable across parameterisations (an unfactored
// estimate's partial fractions have first-order numerators).
Eigen::VectorXd modes(const AdditiveModel& model) {
  Eigen::VectorXd out(3 * model.size());
  for (int i = 0; i < model.size(); ++i) {
    out.segment(3 * i, 3) << model[i].a[1], model[i].a[2], model[i].b[0];
  }
  return out;
}

struct MonteCarloSummary {
  Eigen::VectorXd mean_error;
  Eigen::VectorXd sem;        // standard error of the mean error
  Eigen::VectorXd mse;        // mean squared error
  Eigen::VectorXd predicted;  // mean of the reported variances
};

MonteCarloSummary summarise(const std::vector<Eigen::VectorXd>& errors,
                            const std::vector<Eigen::VectorXd>& variances) {
  const auto r = static_cast<double>(errors.size());
  const Eigen::Index p = errors.front().size();
  MonteCarloSummary s{Eigen::VectorXd::Zero(p), Eigen::VectorXd::Zero(p), Eigen::VectorXd::Zero(p),
                      Eigen::VectorXd::Zero(p)};
  for (const auto& e : errors) {
    s.mean_error += e / r;
    s.mse += e.cwiseAbs2() / r;
  }
  for (const auto& v : variances) s.predicted += v / r;
  Eigen::VectorXd var = Eigen::VectorXd::Zero(p);
  for (const auto& e : errors) var += (e - s.mean_error).cwiseAbs2() / (r - 1.0);
  s.sem = (var / r).cwiseSqrt();
  return s;
}

TEST(RefinedIvMonteCarlo, OpenLoopColouredNoiseIsUnbiasedAndMatchesTheCovariance) {
  // Section 6.2's plant in open loop with the coloured noise of Section 6.1.
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const int n = 2000;
  const int runs = 40;
  std::vector<Eigen::VectorXd> errors;
  std::vector<Eigen::VectorXd> variances;
  for (int run = 0; run < runs; ++run) {
    const Eigen::VectorXd u = white_noise(n, 1.0, 1000 + static_cast<std::uint64_t>(run));
    const Eigen::VectorXd v = colored_noise(testing::open_loop_noise_filter(), n, 0.02,
                                            5000 + static_cast<std::uint64_t>(run));
    const SampledData data(0.05, u, simulate(truth, u, 0.05) + v);
    RefinedIvOptions options;
    options.initial_model = truth.with_parameters(
        perturbed(truth.parameters(), 9000 + static_cast<std::uint64_t>(run)));
    const EstimationResult r = additive_srivc(data, truth.orders(), options);
    ASSERT_TRUE(r.converged()) << "run " << run << ": " << r.message;
    errors.push_back(r.parameters - truth.parameters());
    variances.push_back(r.covariance.diagonal());
  }
  const MonteCarloSummary s = summarise(errors, variances);
  for (Eigen::Index k = 0; k < s.mse.size(); ++k) {
    EXPECT_LT(std::abs(s.mean_error(k)), 3.0 * s.sem(k)) << "parameter " << k;
    // R = 40 runs estimate an MSE to about +-sqrt(2/40) = 22 % (one standard deviation).
    const double ratio = s.mse(k) / s.predicted(k);
    EXPECT_GT(ratio, 0.45) << "parameter " << k;
    EXPECT_LT(ratio, 1.8) << "parameter " << k;
  }
}

TEST(RefinedIvMonteCarlo, ClosedLoopColouredNoiseBiasesDirectSrivcOnly) {
  CTID_SKIP_UNDER_SANITIZERS("a Monte Carlo of fits the other closed-loop tests run once");
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const DiscreteTransferFunction controller = testing::closed_loop_pid();
  const int n = 4000;
  const int runs = 20;
  std::vector<Eigen::VectorXd> direct;
  std::vector<Eigen::VectorXd> closed;
  std::vector<Eigen::VectorXd> additive;
  std::vector<Eigen::VectorXd> none;
  for (int run = 0; run < runs; ++run) {
    const auto seed = static_cast<std::uint64_t>(run);
    const Eigen::VectorXd r = white_noise(n, 1.0, 100 + seed);
    const Eigen::VectorXd v =
        colored_noise(testing::open_loop_noise_filter(), n, 0.005, 200 + seed);
    const ClosedLoopSimulation loop = simulate_closed_loop(truth, controller, r, v);
    const SampledData data(0.05, loop.input, loop.output, r);
    RefinedIvOptions options;
    options.initial_model = truth.with_parameters(perturbed(truth.parameters(), 300 + seed));
    options.compute_covariance = false;
    options.tolerance = 1e-7;  // as in Section 6.2
    RefinedIvOptions direct_options = options;
    direct_options.max_iterations = 30;  // biased and slow to settle; its mean is all we need
    const EstimationResult s = srivc(data, {4, 2, 0}, direct_options);
    const EstimationResult c = clsrivc(data, controller, {4, 2, 0}, options);
    const EstimationResult a = additive_clsrivc(data, controller, truth.orders(), options);
    ASSERT_TRUE(s.additive_view && c.additive_view);
    ASSERT_TRUE(a.converged()) << a.message;
    direct.push_back(modes(*s.additive_view) - modes(truth));
    closed.push_back(modes(*c.additive_view) - modes(truth));
    additive.push_back(modes(a.model) - modes(truth));
    none.push_back(Eigen::VectorXd::Zero(truth.parameter_count()));
  }
  const MonteCarloSummary sd = summarise(direct, none);
  const MonteCarloSummary sc = summarise(closed, none);
  const MonteCarloSummary sa = summarise(additive, none);
  // Direct SRIVC: some parameter well outside its sampling spread (about 5.6 SEM here).
  EXPECT_GT((sd.mean_error.cwiseAbs().cwiseQuotient(sd.sem)).maxCoeff(), 4.5);
  for (Eigen::Index k = 0; k < sa.mean_error.size(); ++k) {
    EXPECT_LT(std::abs(sc.mean_error(k)), 3.5 * sc.sem(k)) << "CLSRIVC parameter " << k;
    EXPECT_LT(std::abs(sa.mean_error(k)), 3.5 * sa.sem(k)) << "additive parameter " << k;
  }
}

TEST(RefinedIvInitialisation, OpenLoopSection61FromDataAlone) {
  const AdditiveModel truth = testing::open_loop_four_modes();
  const int n = 4000;
  const Eigen::VectorXd u = white_noise(n, 1.0, 41);
  const Eigen::VectorXd v = colored_noise(testing::open_loop_noise_filter(), n, 0.02, 42);
  const SampledData data(0.05, u, simulate(truth, u, 0.05) + v);
  const EstimationResult automatic = additive_srivc(data, truth.orders());
  ASSERT_TRUE(automatic.converged()) << automatic.message;
  RefinedIvOptions near_truth;
  near_truth.initial_model = truth;
  const EstimationResult reference = additive_srivc(data, truth.orders(), near_truth);
  ASSERT_TRUE(reference.converged()) << reference.message;
  EXPECT_LT((automatic.parameters - reference.parameters).norm() / reference.parameters.norm(),
            1e-6);
}

TEST(RefinedIvInitialisation, ClosedLoopSection62FromDataAlone) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const DiscreteTransferFunction controller = testing::closed_loop_pid();
  const int n = 4000;
  const Eigen::VectorXd r = white_noise(n, 1.0, 51);
  const Eigen::VectorXd v = white_noise(n, 0.1, 52);
  const ClosedLoopSimulation loop = simulate_closed_loop(truth, controller, r, v);
  const SampledData data(0.05, loop.input, loop.output, r);
  const EstimationResult automatic = additive_clsrivc(data, controller, truth.orders());
  ASSERT_TRUE(automatic.converged()) << automatic.message;
  RefinedIvOptions near_truth;
  near_truth.initial_model = truth;
  const EstimationResult reference = additive_clsrivc(data, controller, truth.orders(), near_truth);
  ASSERT_TRUE(reference.converged()) << reference.message;
  EXPECT_LT((automatic.parameters - reference.parameters).norm() / reference.parameters.norm(),
            1e-6);
}

TEST(RefinedIvDelay, ScanFindsTheInputDelay) {
  const AdditiveModel truth = testing::closed_loop_two_modes().with_input_delay(4 * 0.05);
  const int n = 2000;
  const Eigen::VectorXd u = white_noise(n, 1.0, 61);
  const SampledData data(0.05, u, simulate(truth, u, 0.05) + white_noise(n, 0.05, 62));
  RefinedIvOptions options;
  options.initial_model = truth.with_input_delay(0.0);
  const InputDelayScanResult scan = additive_srivc_delay_scan(data, truth.orders(), 0, 8, options);
  EXPECT_EQ(scan.best.input_delay_samples, 4);
  EXPECT_EQ(scan.delays.size(), 9u);
  EXPECT_NEAR(scan.best.model.input_delay(), 0.2, 1e-12);
}

TEST(RefinedIvDataChecks, ReportsExcitationAndSamplingRate) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const Eigen::VectorXd u = white_noise(1000, 1.0, 71);
  const SampledData data(0.05, u, simulate(truth, u, 0.05));
  RefinedIvOptions options;
  options.initial_model = truth;
  const EstimationResult r = additive_srivc(data, truth.orders(), options);
  EXPECT_TRUE(r.checks.persistently_exciting);
  EXPECT_EQ(r.checks.excitation_order_required, 8);
  EXPECT_TRUE(r.checks.sampling_rate_ok);
  EXPECT_NEAR(r.checks.nyquist_frequency, M_PI / 0.05, 1e-12);
  EXPECT_TRUE(r.checks.warnings.empty());

  EXPECT_EQ(persistent_excitation_order(Eigen::VectorXd::Constant(500, 2.0), 10), 1);
  Eigen::VectorXd sine(500);
  for (int k = 0; k < 500; ++k) sine(k) = std::sin(0.3 * k);
  EXPECT_EQ(persistent_excitation_order(sine, 10), 2);
  EXPECT_EQ(persistent_excitation_order(white_noise(500, 1.0, 3), 10), 10);
}

TEST(RefinedIvBadInput, ClearErrors) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const Eigen::VectorXd u = white_noise(1000, 1.0, 81);
  const SampledData data(0.05, u, simulate(truth, u, 0.05));
  // Too few samples.
  const SampledData short_data = data.segment(0, 20);
  EXPECT_THAT([&] { additive_srivc(short_data, truth.orders()); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("too few")));
  // A constant and a single sine do not excite six parameters.
  const SampledData constant(0.05, Eigen::VectorXd::Ones(1000),
                             simulate(truth, Eigen::VectorXd::Ones(1000), 0.05));
  EXPECT_THAT(
      [&] { additive_srivc(constant, truth.orders()); },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("persistently exciting of order 1")));
  Eigen::VectorXd sine(1000);
  for (int k = 0; k < 1000; ++k) sine(k) = std::sin(0.3 * k);
  const SampledData single(0.05, sine, simulate(truth, sine, 0.05));
  EXPECT_THAT(
      [&] {
        srivc(single, {4, 2, 0});
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("order 2 only")));
  // Impossible orders.
  EXPECT_THAT(
      [&] {
        srivc(data, {2, 3, 0});
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("improper")));
  EXPECT_THAT(
      [&] {
        additive_srivc(data, {{1, 1, 0}, {2, 2, 0}});
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("biproper")));
  EXPECT_THAT(
      [&] {
        srivc(data, {0, 0, 0});
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("no poles")));
  // Options.
  RefinedIvOptions bad;
  bad.tolerance = -1.0;
  EXPECT_THAT(
      [&] {
        srivc(data, {4, 2, 0}, bad);
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("RefinedIvOptions.tolerance")));
  // NaN never reaches an estimator: SampledData rejects it.
  Eigen::VectorXd with_nan = u;
  with_nan(10) = std::nan("");
  EXPECT_THROW(SampledData(0.05, with_nan, u), InvalidArgument);
  // Closed loop without a reference.
  EXPECT_THAT(
      [&] {
        clsrivc(data, testing::closed_loop_pid(), {4, 2, 0});
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("reference")));
}

TEST(RefinedIvBadInput, ControllerThatDoesNotStabiliseTheModelIsATermination) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const Eigen::VectorXd r = white_noise(1000, 1.0, 91);
  const ClosedLoopSimulation loop = simulate_closed_loop(truth, testing::closed_loop_pid(), r);
  const SampledData data(0.05, loop.input, loop.output, r);
  // A pure gain of -5 (positive feedback) cannot stabilise this plant.
  const DiscreteTransferFunction wrong(Polynomial{-5.0}, Polynomial{1.0}, 0.05);
  RefinedIvOptions options;
  options.initial_model = truth;
  const EstimationResult e = additive_clsrivc(data, wrong, truth.orders(), options);
  EXPECT_EQ(e.termination, Termination::closed_loop_unstable);
  EXPECT_THAT(e.message, HasSubstr("does not stabilise"));
  EXPECT_EQ(to_string(e.termination), "closed_loop_unstable");
  // Nothing was estimated, and the message says the model is the start. The verdict judges
  // the model, not the iteration count: the controller does not stabilise it, so it cannot
  // describe the recorded loop.
  EXPECT_THAT(e.message, HasSubstr("the model is the start"));
  EXPECT_FALSE(e.verdict.usable);
  EXPECT_THAT(e.verdict.summary(), HasSubstr("does not stabilise the fitted model"));
  EXPECT_EQ(e.start_fit_percent, e.fit_percent);
}

TEST(RefinedIvCovariance, AutoregressiveFitRecoversAnArProcess) {
  // x_k = 0.8 x_{k-1} + e_k: A(q^-1) = 1 - 0.8 q^-1.
  const Eigen::VectorXd e = white_noise(20000, 1.0, 5);
  Eigen::VectorXd x(e.size());
  x(0) = e(0);
  for (Eigen::Index k = 1; k < x.size(); ++k) x(k) = 0.8 * x(k - 1) + e(k);
  const AutoregressiveModel ar = fit_autoregressive(x, 10);
  ASSERT_GE(ar.coefficients.size(), 2);
  EXPECT_NEAR(ar.coefficients(1), -0.8, 0.02);
  EXPECT_NEAR(ar.innovation_variance, 1.0, 0.05);
}

TEST(RefinedIvCovariance, ColouredSandwichEqualsItsExplicitFormula) {
  // The covariance accumulates the AR-filtered outer products in blocks without forming the
  // filtered psi; it must equal the sandwich written out with adjoint_ar_filter, for records
  // shorter and longer than a block and an AR order the recursion carries across blocks.
  for (const int n : {7, 1024, 3001}) {
    Eigen::MatrixXd psi(n, 3);
    psi.col(0) = white_noise(n, 1.0, 11);
    psi.col(1) = white_noise(n, 1e-3, 12);
    psi.col(2) = white_noise(n, 1e4, 13) + psi.col(0);
    Eigen::VectorXd residual(n);
    const Eigen::VectorXd e = white_noise(n, 0.1, 14);
    residual(0) = e(0);
    for (int k = 1; k < n; ++k) residual(k) = 0.9 * residual(k - 1) + e(k);
    const AutoregressiveModel ar = fit_autoregressive(residual, 5);
    const Eigen::MatrixXd covariance =
        instrumental_variable_covariance(psi, residual, 3, NoiseAssumption::coloured, 5);
    const Eigen::MatrixXd r_inv = (psi.transpose() * psi).inverse();
    const Eigen::MatrixXd g = adjoint_ar_filter(psi, ar);
    const double e2 = ar.innovation_variance * n / (n - 3.0);
    const Eigen::MatrixXd expected = r_inv * (e2 * g * g.transpose()) * r_inv;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        EXPECT_NEAR(covariance(i, j), expected(i, j),
                    1e-9 * std::sqrt(expected(i, i) * expected(j, j)))
            << "n = " << n << ", entry " << i << ", " << j;
      }
    }
  }
}

}  // namespace
}  // namespace ctid::refined_iv_statistics_test
