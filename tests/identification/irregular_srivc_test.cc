// SRIVC on irregular time stamps (srivc_irregular, docs/decisions/0034): exact on noise-free
// records with ±30 % jitter, duplicate stamps and 1 % missing samples for the declared input
// hold (ZOH and FOH); the same estimate as srivc on a regular record; an N·MSE no larger than
// SRIVC on the record resampled onto a grid; one clear message for each bad record.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/core/preprocessing.h"
#include "ctid/identification/identification.h"
#include "ctid/refined_iv/irregular_srivc.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/excitation.h"
#include "support/sanitizers.h"

namespace ctid::irregular_srivc_test {
namespace {

constexpr double kStep = 0.05;  // median step [s]
const SubmodelOrder kOrder{2, 1, 0};

// (2 + 0.3 p) / (1 + 0.4 p + 0.25 p^2): w_n = 2 rad/s, zeta = 0.4; theta = [a1 a2 b0 b1].
Eigen::VectorXd true_parameters() {
  Eigen::VectorXd theta(4);
  theta << 0.4, 0.25, 2.0, 0.3;
  return theta;
}

AdditiveModel truth() { return AdditiveModel::from_parameters({kOrder}, true_parameters()); }

// Stamps k h with ±jitter h uniform noise, then 1 % of the samples dropped and 1 % of the
// remaining stamps repeated (the sample after it logged at the same time).
Eigen::VectorXd jittered_stamps(int n, double jitter, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> chance(0.0, 1.0);
  std::vector<double> t;
  for (int k = 0; t.size() < static_cast<size_t>(n); ++k) {
    const double stamp = k * kStep + jitter * kStep * unit(rng);
    if (k > 0 && chance(rng) < 0.01) continue;  // a missing sample: a gap
    t.push_back(stamp);
  }
  for (size_t k = 1; k + 1 < t.size(); ++k) {
    if (chance(rng) < 0.01) t[k] = t[k - 1];  // a duplicate stamp
  }
  return Eigen::Map<Eigen::VectorXd>(t.data(), static_cast<Eigen::Index>(t.size()));
}

// The model's response from rest at the stamps, the input continued by `hold`, from the
// discretisation of the model's own state-space realisation (not the estimator's filters) on
// each interval.
Eigen::VectorXd response_on_stamps(const AdditiveModel& g, const Eigen::VectorXd& t,
                                   const Eigen::VectorXd& u, Hold hold) {
  const StateSpace ss = g.to_transfer_function().to_state_space();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(ss.a.rows());
  Eigen::VectorXd y(u.size());
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    if (k > 0 && t(k) > t(k - 1)) {
      const double h = t(k) - t(k - 1);
      if (hold == Hold::zero_order_hold) {
        const ZohDiscretization d = discretize_zoh(ss.a, ss.b, h);
        x = d.phi * x + d.gamma.col(0) * u(k - 1);
      } else {
        const FohDiscretization d = discretize_foh(ss.a, ss.b, h);
        x = d.phi * x + d.gamma0.col(0) * u(k - 1) + d.gamma1.col(0) * u(k);
      }
    }
    y(k) = ss.c.dot(x) + ss.d * u(k);
  }
  return y;
}

IrregularRecord record(int n, double jitter, Hold hold, double noise, std::uint64_t seed) {
  IrregularRecord r;
  r.time = jittered_stamps(n, jitter, seed);
  r.input = white_noise(n, 1.0, seed + 100);
  r.output = response_on_stamps(truth(), r.time, r.input, hold);
  if (noise > 0.0) r.output += white_noise(n, noise, seed + 200);
  r.input_hold = hold;
  return r;
}

double largest_relative_error(const Eigen::VectorXd& estimate, const Eigen::VectorXd& truth) {
  return ((estimate - truth).cwiseAbs().array() / truth.cwiseAbs().array()).maxCoeff();
}

int count_duplicates(const Eigen::VectorXd& t) {
  int count = 0;
  for (Eigen::Index k = 1; k < t.size(); ++k) count += t(k) == t(k - 1) ? 1 : 0;
  return count;
}

TEST(IrregularSrivc, NoiseFreeJitteredRecordsAreFittedExactlyForTheDeclaredHold) {
  for (Hold hold : {Hold::zero_order_hold, Hold::first_order_hold}) {
    for (std::uint64_t seed : {1U, 2U}) {
      const IrregularRecord r = record(1500, 0.3, hold, 0.0, seed);
      ASSERT_GE(count_duplicates(r.time), 3) << "the record must hold duplicate stamps";
      RefinedIvOptions options;
      options.compute_covariance = false;
      const EstimationResult e = srivc_irregular(r, kOrder, options);
      ASSERT_TRUE(e.converged()) << e.brief_report();
      EXPECT_LT(largest_relative_error(e.parameters, true_parameters()), 1e-8)
          << enum_name(hold) << " seed " << seed << ": " << e.parameters.transpose();
      EXPECT_TRUE(e.verdict.usable) << e.verdict.summary();
      EXPECT_GT(e.fit_percent, 99.999);
    }
  }
}

TEST(IrregularSrivc, ZeroOrderHoldAssumedOnAPiecewiseLinearInputIsBiased) {
  IrregularRecord r = record(1500, 0.3, Hold::first_order_hold, 0.0, 3);
  r.input_hold = Hold::zero_order_hold;
  RefinedIvOptions options;
  options.compute_covariance = false;
  const EstimationResult e = srivc_irregular(r, kOrder, options);
  EXPECT_GT(largest_relative_error(e.parameters, true_parameters()), 1e-4);
}

TEST(IrregularSrivc, RegularRecordGivesTheEstimateOfSrivc) {
  // Noisy, so the fixed point is not the truth; both start from the same perturbed model.
  const int n = 1200;
  IrregularRecord r;
  r.time = Eigen::VectorXd::LinSpaced(n, 0.0, (n - 1) * kStep);
  r.input = white_noise(n, 1.0, 7);
  r.output =
      response_on_stamps(truth(), r.time, r.input, Hold::zero_order_hold) + white_noise(n, 0.3, 8);
  RefinedIvOptions options;
  Eigen::VectorXd start = true_parameters();
  start(0) *= 1.1;
  start(3) *= 0.9;
  options.initial_model = AdditiveModel::from_parameters({kOrder}, start);
  options.noise = NoiseAssumption::white;
  const EstimationResult irregular = srivc_irregular(r, kOrder, options);
  const EstimationResult regular = srivc(SampledData(kStep, r.input, r.output), kOrder, options);
  ASSERT_TRUE(irregular.converged()) << irregular.brief_report();
  ASSERT_TRUE(regular.converged()) << regular.brief_report();
  EXPECT_GT(largest_relative_error(regular.parameters, true_parameters()), 1e-3);
  EXPECT_LT(largest_relative_error(irregular.parameters, regular.parameters), 1e-9)
      << irregular.parameters.transpose() << " vs " << regular.parameters.transpose();
  EXPECT_LT(largest_relative_error(irregular.standard_errors, regular.standard_errors), 1e-6);
  EXPECT_NEAR(irregular.fit_percent, regular.fit_percent, 1e-8);
}

// Resampled onto a grid of step h (equal stamps reduced to their last sample), then srivc.
Eigen::VectorXd resampled_estimate(const IrregularRecord& r, double h) {
  std::vector<double> t, u, y;
  for (Eigen::Index k = 0; k < r.time.size(); ++k) {
    if (!t.empty() && r.time(k) == t.back()) {
      u.back() = r.input(k);
      y.back() = r.output(k);
      continue;
    }
    t.push_back(r.time(k));
    u.push_back(r.input(k));
    y.push_back(r.output(k));
  }
  auto vec = [](std::vector<double>& v) {
    return Eigen::VectorXd(
        Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
  };
  RefinedIvOptions options;
  options.compute_covariance = false;
  const SampledData grid = resample(vec(t), vec(u), vec(y), std::nullopt, h, r.input_hold);
  return srivc(grid, kOrder, options).parameters;
}

TEST(IrregularSrivc, MonteCarloMeanSquaredErrorIsNoLargerThanTheResampledEstimates) {
  CTID_SKIP_UNDER_SANITIZERS("a 40-run Monte Carlo; the exactness tests cover the same code");
  constexpr int kRuns = 40;
  constexpr int kN = 600;
  const Eigen::VectorXd theta = true_parameters();
  // Per estimator: sum over runs of the squared relative errors, per parameter.
  Eigen::VectorXd irregular = Eigen::VectorXd::Zero(4);
  Eigen::VectorXd at_median = Eigen::VectorXd::Zero(4);
  Eigen::VectorXd at_half = Eigen::VectorXd::Zero(4);
  RefinedIvOptions options;
  options.compute_covariance = false;
  for (int run = 0; run < kRuns; ++run) {
    const IrregularRecord r = record(kN, 0.3, Hold::zero_order_hold, 0.2, 1000 + run);
    const Eigen::VectorXd e = srivc_irregular(r, kOrder, options).parameters;
    const double h = r.median_step();
    irregular += ((e - theta).array() / theta.array()).square().matrix();
    at_median += ((resampled_estimate(r, h) - theta).array() / theta.array()).square().matrix();
    at_half += ((resampled_estimate(r, h / 2) - theta).array() / theta.array()).square().matrix();
  }
  // N · MSE summed over the parameters (relative to each parameter's size).
  const double n_mse_irregular = kN * irregular.sum() / kRuns;
  const double n_mse_median = kN * at_median.sum() / kRuns;
  const double n_mse_half = kN * at_half.sum() / kRuns;
  const double best_resampled = std::min(n_mse_median, n_mse_half);
  std::cout << "N*MSE (sum of relative squared errors, " << kRuns << " runs, N = " << kN
            << "): irregular " << n_mse_irregular << ", resampled at the median step "
            << n_mse_median << ", at half of it " << n_mse_half << "\n";
  // A Monte Carlo of R runs estimates an MSE to about ±sqrt(2/R) (22 % for 40 runs).
  EXPECT_LE(n_mse_irregular, best_resampled * (1.0 + std::sqrt(2.0 / kRuns)));
}

void expect_refused(const IrregularRecord& r, const std::string& words) {
  try {
    (void)srivc_irregular(r, kOrder);
    ADD_FAILURE() << "no error; expected one saying '" << words << "'";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(IrregularSrivc, BadRecordsAreRefusedWithOneClearMessage) {
  const IrregularRecord good = record(200, 0.3, Hold::zero_order_hold, 0.0, 5);
  IrregularRecord backwards = good;
  backwards.time(50) = backwards.time(48);
  expect_refused(backwards, "time stamp 50");
  expect_refused(backwards, "goes back");
  IrregularRecord nan_stamp = good;
  nan_stamp.time(7) = std::nan("");
  expect_refused(nan_stamp, "time stamp 7 is nan");
  IrregularRecord few = good;
  few.time.conservativeResize(20);
  few.input.conservativeResize(20);
  few.output.conservativeResize(20);
  expect_refused(few, "too few for 4 parameters");
  IrregularRecord sizes = good;
  sizes.output.conservativeResize(100);
  expect_refused(sizes, "the sizes must agree");
  IrregularRecord constant = good;
  constant.time.setConstant(1.0);
  expect_refused(constant, "spans no time");
  RefinedIvOptions delayed;
  delayed.input_delay_samples = 2;
  EXPECT_THROW((void)srivc_irregular(good, kOrder, delayed), InvalidArgument);
}

TEST(IrregularSrivc, TheFrontDoorRunsItForAnUnfactoredOpenLoopStructureOnly) {
  const IrregularRecord r = record(600, 0.3, Hold::zero_order_hold, 0.1, 11);
  IdentificationOptions options;
  options.refined_iv.compute_covariance = false;
  const IdentificationResult front = identify(r, ModelStructure::unfactored(2, 1), options);
  EXPECT_EQ(front.estimator, RefinedIvEstimator::srivc_irregular);
  EXPECT_EQ(enum_name(front.estimator), "srivc_irregular");
  EXPECT_FALSE(front.closed_loop);
  const EstimationResult direct = srivc_irregular(r, kOrder, options.refined_iv);
  EXPECT_EQ(front.estimate.parameters, direct.parameters);
  EXPECT_THROW((void)identify(r, ModelStructure::modes(1), options), InvalidArgument);
  IdentificationOptions closed = options;
  closed.controller = DiscreteTransferFunction(Polynomial{1.0}, Polynomial{1.0}, kStep);
  try {
    (void)identify(r, ModelStructure::unfactored(2, 1), closed);
    ADD_FAILURE() << "closed loop was not refused";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("controller is set (closed loop)"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace ctid::irregular_srivc_test
