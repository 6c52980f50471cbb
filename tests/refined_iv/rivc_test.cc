// RIVC and CLRIVC (RefinedIvOptions::noise_model, decision 0056): exact on noise-free data in
// every form the engine runs (unfactored, additive, closed loop, several records), the white
// noise model is SRIVC, a seeded closed-loop Monte Carlo against CLSRIVC, the ARMA estimator
// on its own, and bad input refused by name. The open-loop efficiency Monte Carlo (200 runs
// against the Cramer-Rao bound) is python/tests/test_rivc_monte_carlo.py; the independent
// NumPy reference of the iteration is python/tests/test_reference_rivc.py.
#include <cmath>
#include <random>

#include <Eigen/Dense>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/estimation/arma.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/irregular_srivc.h"
#include "ctid/refined_iv/refined_iv.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/refined_iv/unstable_clsrivc.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"
#include "support/paper_systems.h"
#include "support/sanitizers.h"

namespace ctid::rivc_test {
namespace {

using ::testing::HasSubstr;

constexpr double kH = 0.05;

RefinedIvOptions with_noise_model(int ar, int ma) {
  RefinedIvOptions options;
  options.noise_model = NoiseModelOrders{.ar = ar, .ma = ma};
  return options;
}

// y = x + (C/D) e with D = 1 - rho q^-1, C = 1 + c q^-1, scaled to `level`.
Eigen::VectorXd arma_noise(int n, double rho, double c, double level, std::uint64_t seed) {
  const DiscreteTransferFunction h(Polynomial({c, 1.0}), Polynomial({-rho, 1.0}), kH);
  return colored_noise(h, n, level * level, seed);
}

TEST(Rivc, NoiseFreeOpenLoopIsExactUnfactoredAndAdditive) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const Eigen::VectorXd u = white_noise(3000, 1.0, 11);
  const SampledData data(kH, u, simulate(truth, u, kH));
  const EstimationResult unfactored = srivc(data, {4, 2, 0}, with_noise_model(1, 1));
  ASSERT_TRUE(unfactored.converged()) << unfactored.message;
  ASSERT_TRUE(unfactored.noise_model.has_value());
  const TransferFunction g = truth.to_transfer_function();
  EXPECT_LT(
      (unfactored.transfer_function.denominator().coefficients() - g.denominator().coefficients())
          .norm(),
      1e-9);
  const EstimationResult additive = additive_srivc(data, truth.orders(), with_noise_model(2, 0));
  ASSERT_TRUE(additive.converged()) << additive.message;
  EXPECT_LT((additive.parameters - truth.parameters()).norm() / truth.parameters().norm(), 1e-10);
  // The output error is rounding: no noise to model, so D = C = 1.
  EXPECT_EQ(additive.noise_model->ar, Eigen::VectorXd::Unit(3, 0));
}

TEST(Rivc, NoiseFreeClosedLoopIsExactAndSeveralRecordsAreOneFit) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const DiscreteTransferFunction controller = testing::closed_loop_pid();
  std::vector<SampledData> records;
  for (std::uint64_t seed : {21u, 22u}) {
    const Eigen::VectorXd r = white_noise(2500, 1.0, seed);
    const ClosedLoopSimulation loop = simulate_closed_loop(truth, controller, r);
    records.emplace_back(kH, loop.input, loop.output, r);
  }
  RefinedIvOptions options = with_noise_model(1, 1);
  options.initial_model = truth.with_parameters(truth.parameters() * 1.03);
  const EstimationResult one = additive_clsrivc(records[0], controller, truth.orders(), options);
  ASSERT_TRUE(one.converged()) << one.message;
  EXPECT_LT((one.parameters - truth.parameters()).norm() / truth.parameters().norm(), 1e-9);
  RefinedIvProblem problem;
  problem.records = {&records[0], &records[1]};
  problem.orders = truth.orders();
  problem.controller = &controller;
  const EstimationResult both = estimate_refined_iv(problem, options);
  ASSERT_TRUE(both.converged()) << both.message;
  EXPECT_LT((both.parameters - truth.parameters()).norm() / truth.parameters().norm(), 1e-9);
}

TEST(Rivc, AWhiteNoiseModelIsSrivc) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const Eigen::VectorXd u = white_noise(3000, 1.0, 31);
  const SampledData data(kH, u, simulate(truth, u, kH) + arma_noise(3000, 0.9, 0.3, 0.05, 32));
  RefinedIvOptions plain;
  plain.tolerance = 1e-13;
  RefinedIvOptions white = with_noise_model(0, 0);
  white.tolerance = 1e-13;
  const EstimationResult s = additive_srivc(data, truth.orders(), plain);
  const EstimationResult r = additive_srivc(data, truth.orders(), white);
  ASSERT_TRUE(s.converged() && r.converged()) << r.message;
  EXPECT_LT((s.parameters - r.parameters).norm() / s.parameters.norm(), 1e-9);
  // The covariances differ only by the variance's estimate (white noise, no sandwich).
  EXPECT_EQ(r.noise_model->ar_order() + r.noise_model->ma_order(), 0);
}

TEST(Rivc, ClosedLoopMonteCarloIsUnbiasedCalibratedAndBeatsClsrivc) {
  CTID_SKIP_UNDER_SANITIZERS("a Monte Carlo of closed-loop fits the noise-free test runs once");
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const DiscreteTransferFunction controller = testing::closed_loop_pid();
  const Eigen::VectorXd beta = truth.parameters();
  const int runs = 40;
  const Eigen::Index p = beta.size();
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(p);
  Eigen::VectorXd square = Eigen::VectorXd::Zero(p);
  Eigen::VectorXd reported = Eigen::VectorXd::Zero(p);
  Eigen::VectorXd square_plain = Eigen::VectorXd::Zero(p);
  for (int run = 0; run < runs; ++run) {
    const auto seed = static_cast<std::uint64_t>(run);
    const Eigen::VectorXd r = white_noise(4000, 1.0, 500 + seed);
    const ClosedLoopSimulation loop =
        simulate_closed_loop(truth, controller, r, arma_noise(4000, 0.9, 0.5, 0.02, 600 + seed));
    const SampledData data(kH, loop.input, loop.output, r);
    RefinedIvOptions options = with_noise_model(1, 1);
    options.initial_model = truth;
    RefinedIvOptions plain_options;
    plain_options.initial_model = truth;
    plain_options.compute_covariance = false;
    const EstimationResult c = additive_clsrivc(data, controller, truth.orders(), options);
    const EstimationResult plain =
        additive_clsrivc(data, controller, truth.orders(), plain_options);
    ASSERT_TRUE(c.converged()) << c.message;
    const Eigen::VectorXd error = (c.parameters - beta).cwiseQuotient(beta);
    mean += error / runs;
    square += error.cwiseAbs2() / runs;
    reported += c.standard_errors.cwiseQuotient(beta).cwiseAbs2() / runs;
    square_plain += (plain.parameters - beta).cwiseQuotient(beta).cwiseAbs2() / runs;
  }
  const Eigen::VectorXd spread = (square - mean.cwiseAbs2()).cwiseSqrt();
  for (Eigen::Index k = 0; k < p; ++k) {
    EXPECT_LT(std::abs(mean(k)), 3.5 * spread(k) / std::sqrt(runs)) << "parameter " << k;
    // 40 runs give the spread to about +-11 %: +-35 % is some 3 of those.
    EXPECT_NEAR(std::sqrt(reported(k)) / spread(k), 1.0, 0.35) << "parameter " << k;
  }
  // Paired on the same records: never clearly worse than CLSRIVC, and clearly better on the
  // faster mode, whose band the coloured noise fills.
  for (Eigen::Index k = 0; k < p; ++k) {
    EXPECT_LT(square(k), 1.1 * square_plain(k)) << "parameter " << k;
  }
  EXPECT_LT(square.tail(3).sum(), 0.8 * square_plain.tail(3).sum());
}

TEST(Rivc, AutomaticOrdersAreChosenByTheCriterion) {
  const Eigen::VectorXd u = white_noise(4000, 1.0, 41);
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const SampledData data(kH, u, simulate(truth, u, kH) + arma_noise(4000, 0.95, 0.0, 0.1, 42));
  RefinedIvOptions options;
  options.noise_model = NoiseModelOrders{.automatic = true};
  options.initial_model = truth;
  const EstimationResult r = additive_srivc(data, truth.orders(), options);
  ASSERT_TRUE(r.converged()) << r.message;
  ASSERT_TRUE(r.noise_model.has_value());
  // An AR(1) noise: the criterion keeps an AR part whose first coefficient is near -0.95.
  ASSERT_GE(r.noise_model->ar_order(), 1);
  EXPECT_NEAR(r.noise_model->ar(1), -0.95, 0.1);
  EXPECT_EQ(r.noise_model->spectrum.size(), r.noise_model->spectrum_frequencies.size());
}

TEST(Rivc, BadInputIsRefusedByName) {
  const AdditiveModel truth = testing::closed_loop_two_modes();
  const Eigen::VectorXd u = white_noise(100, 1.0, 51);
  const SampledData data(kH, u, simulate(truth, u, kH));
  try {
    (void)srivc(data, {2, 0, 0}, with_noise_model(5, 5));
    FAIL() << "an ARMA(5, 5) on 100 samples was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot hold an ARMA(5, 5) noise model"));
  }
  RefinedIvOptions too_high = with_noise_model(21, 0);
  EXPECT_THAT([&] { too_high.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("noise_model.ar")));
  const IrregularRecord stamps{Eigen::VectorXd::LinSpaced(100, 0.0, 99 * kH), u, data.output()};
  EXPECT_THAT(
      [&] {
        (void)srivc_irregular(stamps, {2, 0, 0}, with_noise_model(1, 0));
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("noise_model is set")));
  const SampledData loop(kH, u, data.output(), u);
  EXPECT_THAT(
      [&] {
        (void)unstable_clsrivc(loop, testing::closed_loop_pid(), {2, 0, 0}, too_high);
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("noise_model")));
}

TEST(NoiseModelOrders, WordsOfTheCommandLine) {
  EXPECT_FALSE(NoiseModelOrders::from_flag("none").has_value());
  EXPECT_TRUE(NoiseModelOrders::from_flag("auto")->automatic);
  const NoiseModelOrders o = *NoiseModelOrders::from_flag("3,2");
  EXPECT_EQ(o.ar, 3);
  EXPECT_EQ(o.ma, 2);
  for (const char* bad : {"3", "3,", ",2", "x,1", "1,2,3", "21,0", "-1,1", "1.5,1", ""}) {
    EXPECT_THAT([&] { (void)NoiseModelOrders::from_flag(bad); },
                ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("is not P,Q")))
        << bad;
  }
}

TEST(Arma, RecoversAnArmaModelWithinItsStandardErrors) {
  // D = 1 - 1.2 q^-1 + 0.5 q^-2, C = 1 + 0.4 q^-1.
  const DiscreteTransferFunction h(Polynomial({0.0, 0.4, 1.0}), Polynomial({0.5, -1.2, 1.0}), kH);
  const Eigen::VectorXd v = colored_noise(h, 20000, 1.0, 61);
  const ArmaModel m = fit_arma(v, 2, 1);
  ASSERT_TRUE(m.converged);
  const Eigen::Vector3d truth(-1.2, 0.5, 0.4);
  const Eigen::Vector3d estimate(m.ar(1), m.ar(2), m.ma(1));
  for (int k = 0; k < 3; ++k) {
    EXPECT_LT(std::abs(estimate(k) - truth(k)), 4.0 * m.standard_errors(k)) << k;
  }
  // The innovations are white and of the driving noise's variance.
  const Eigen::VectorXd e = arma_innovations(m, v);
  EXPECT_NEAR(e.squaredNorm() / static_cast<double>(e.size()), m.innovation_variance, 1e-3);
}

TEST(Arma, SpectrumAtZeroIsTheClosedForm) {
  ArmaModel m;
  m.ar = Eigen::Vector2d(1.0, -0.5);
  m.ma = Eigen::Vector2d(1.0, 0.25);
  m.innovation_variance = 2.0;
  arma_spectrum(m, 0.1, 11);
  // 2 h sigma^2 (C(1) / D(1))^2 at f = 0; (C(-1) / D(-1))^2 at Nyquist.
  EXPECT_NEAR(m.spectrum(0), 2.0 * 0.1 * 2.0 * std::pow(1.25 / 0.5, 2), 1e-12);
  EXPECT_NEAR(m.spectrum(10), 2.0 * 0.1 * 2.0 * std::pow(0.75 / 1.5, 2), 1e-12);
  EXPECT_NEAR(m.spectrum_frequencies(10), 5.0, 1e-12);
}

TEST(Arma, RecordsRestartTheFiltersAndBadInputIsNamed) {
  const Eigen::VectorXd v = white_noise(400, 1.0, 71);
  ArmaModel m = fit_arma(v, 1, 1, {200});
  // The innovations of the second record do not depend on the first.
  Eigen::VectorXd changed = v;
  changed.head(200).setConstant(5.0);
  EXPECT_EQ(arma_innovations(m, v, {200}).tail(200), arma_innovations(m, changed, {200}).tail(200));
  const ArmaModel zero = fit_arma(Eigen::VectorXd::Zero(100), 1, 1);
  EXPECT_EQ(zero.innovation_variance, 0.0);
  EXPECT_TRUE(std::isnan(zero.standard_errors(0)));
  EXPECT_THAT([&] { (void)fit_arma(v.head(30), 2, 2); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("cannot hold an ARMA(2, 2)")));
  EXPECT_THAT([&] { (void)fit_arma(v, 21, 0); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("must each lie in [0, 20]")));
  Eigen::VectorXd bad = v;
  bad(3) = std::nan("");
  EXPECT_THAT([&] { (void)fit_arma(bad, 1, 0); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("not finite")));
}

}  // namespace
}  // namespace ctid::rivc_test
