// The first-order perturbation standard errors of SSI-cov (decision 0036): the linearised
// change of frequency, damping and shape along each column of the Hankel covariance factor
// against central differences of the whole identification (no statistics), and a seeded Monte
// Carlo calibration of both kinds of standard error on the chain (coverage of the truth within
// 3 reported standard errors, Monte Carlo variance against the mean reported variance).
#include "ctid/oma/ssi_uncertainty.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/oma/oma.h"
#include "ctid/oma/ssi_cov.h"
#include "oma/calibration.h"
#include "oma/chain_model.h"
#include "support/sanitizers.h"

namespace ctid::ssi_uncertainty_test {
namespace {

using oma_test::Calibration;
using oma_test::ChainModel;
using oma_test::expect_quoted;

std::complex<double> discrete_pole(const oma_test::TrueMode& m, double h) {
  const double wn = 2.0 * std::numbers::pi * m.frequency_hz;
  const std::complex<double> s(-m.damping_ratio * wn,
                               wn * std::sqrt(1.0 - m.damping_ratio * m.damping_ratio));
  return std::exp(s * h);
}

// Central differences of the whole path (SVD, O, A, eigenvalues, normalised shape) along
// each column of T, against the linearised change: the derivative itself, to 1e-6.
TEST(SsiUncertainty, LinearisedChangeMatchesCentralDifferences) {
  const ChainModel model;
  const Eigen::MatrixXd y = model.simulate(20000, 0.05, 21);
  const std::vector<int> refs = {0, 1, 2, 3};
  const int p = 12;
  const Eigen::MatrixXd hankel =
      oma_detail::correlation_hankel(oma_detail::output_correlations(y, refs, 2 * p - 1), p);
  const Eigen::MatrixXd t = oma_detail::hankel_covariance_factor(y, refs, p, 10);
  ASSERT_EQ(t.rows(), hankel.size());
  ASSERT_EQ(t.cols(), 10);
  const Eigen::MatrixXd none(hankel.size(), 0);
  for (const int order : {8, 12}) {
    for (const auto& truth : model.modes) {
      SCOPED_TRACE(::testing::Message()
                   << "order " << order << ", " << truth.frequency_hz << " Hz");
      const auto at =
          oma_detail::pole_sensitivity(hankel, 4, order, model.h, discrete_pole(truth, model.h), t);
      ASSERT_TRUE(at.has_value());
      EXPECT_NEAR(at->frequency_hz / truth.frequency_hz, 1.0, 0.01);
      // The same pole and shape as the identification reports.
      const auto poles = oma_detail::ssi_poles(
          oma_detail::ssi_factor(oma_detail::output_correlations(y, refs, 2 * p - 1), p, order),
          order, model.h, 0.2);
      double closest = 1e300;
      for (const auto& q : poles) {
        closest = std::min(closest, std::abs(q.frequency_hz - at->frequency_hz));
      }
      EXPECT_LT(closest, 1e-9 * at->frequency_hz);
      Eigen::RowVectorXd df(t.cols()), dz(t.cols());
      Eigen::MatrixXcd dphi(4, t.cols());
      for (Eigen::Index k = 0; k < t.cols(); ++k) {
        const double eps = 1e-5 * hankel.norm() / t.col(k).norm();
        const Eigen::Map<const Eigen::MatrixXd> dh(t.col(k).data(), hankel.rows(), hankel.cols());
        // Fourth-order central difference: truncation O(eps^4), so eps can stay well above
        // the rounding floor.
        std::vector<oma_detail::PoleSensitivity> at_step;
        for (const double step : {-2.0, -1.0, 1.0, 2.0}) {
          const auto q = oma_detail::pole_sensitivity(hankel + step * eps * dh, 4, order, model.h,
                                                      at->lambda, none);
          ASSERT_TRUE(q.has_value());
          at_step.push_back(*q);
        }
        const auto& q = at_step;
        df(k) = (8.0 * (q[2].frequency_hz - q[1].frequency_hz) -
                 (q[3].frequency_hz - q[0].frequency_hz)) /
                (12.0 * eps);
        dz(k) = (8.0 * (q[2].damping_ratio - q[1].damping_ratio) -
                 (q[3].damping_ratio - q[0].damping_ratio)) /
                (12.0 * eps);
        dphi.col(k) = (8.0 * (q[2].shape - q[1].shape) - (q[3].shape - q[0].shape)) / (12.0 * eps);
      }
      // Relative to the standard error each implies (the norm over the columns of T).
      const double ef = (df - at->frequency).norm() / at->frequency.norm();
      const double ez = (dz - at->damping).norm() / at->damping.norm();
      const double es = (dphi - at->shape_change).norm() / at->shape_change.norm();
      std::printf("order %d %.3f Hz: %.2e %.2e %.2e\n", order, truth.frequency_hz, ef, ez, es);
      EXPECT_LT(ef, 1e-6);
      EXPECT_LT(ez, 1e-6);
      EXPECT_LT(es, 1e-6);
    }
  }
}

// The seeded records of every calibration: the 4-mass chain (6.3, 19.6, 30.1 and 38.2 Hz,
// damping 0.8-1.3 %), 20000 samples, sensor noise 5 % of each channel's deviation.
constexpr int kSamples = 20000;
constexpr int kBlockRows = 20;
Eigen::MatrixXd record(const ChainModel& model, int run) {
  return model.simulate(kSamples, 0.05, 5000u + static_cast<unsigned>(run));
}

// The propagation alone: each mode at the chain's true order 8 from H and T of each record.
std::vector<Calibration> at_true_order(const ChainModel& model, int runs) {
  const std::vector<int> refs = {0, 1, 2, 3};
  std::vector<Calibration> cal(model.modes.size());
  for (int run = 0; run < runs; ++run) {
    const Eigen::MatrixXd y = record(model, run);
    const Eigen::MatrixXd hankel = oma_detail::correlation_hankel(
        oma_detail::output_correlations(y, refs, 2 * kBlockRows - 1), kBlockRows);
    const Eigen::MatrixXd t = oma_detail::hankel_covariance_factor(y, refs, kBlockRows, 10);
    for (std::size_t i = 0; i < model.modes.size(); ++i) {
      const auto& truth = model.modes[i];
      const auto q =
          oma_detail::pole_sensitivity(hankel, 4, 8, model.h, discrete_pole(truth, model.h), t);
      if (!q.has_value()) continue;
      cal[i].add(truth, q->frequency_hz, q->frequency.norm(), q->damping_ratio, q->damping.norm());
    }
  }
  return cal;
}

// What a user gets: oma() over orders 2..24 with the modes named (so that every run reports
// every mode), standard errors of the kind asked for.
std::vector<Calibration> through_oma(const ChainModel& model, int runs, OmaUncertainty kind,
                                     OmaMethod method = OmaMethod::ssi_cov) {
  OmaOptions o;
  o.method = method;
  o.max_order = 24;
  o.block_rows = kBlockRows;
  o.uncertainty = kind;
  for (const auto& m : model.modes) o.modes_near_hz.push_back(m.frequency_hz);
  std::vector<Calibration> cal(model.modes.size());
  for (int run = 0; run < runs; ++run) {
    const OmaResult r = oma(record(model, run), model.h, o);
    for (std::size_t i = 0; i < model.modes.size(); ++i) {
      const auto& truth = model.modes[i];
      const OmaMode* m = oma_test::nearest(r, truth.frequency_hz);
      if (m == nullptr || std::abs(m->frequency_hz / truth.frequency_hz - 1.0) > 0.02) continue;
      cal[i].add(truth, m->frequency_hz, m->frequency_hz_std, m->damping_ratio,
                 m->damping_ratio_std);
    }
  }
  return cal;
}

// Always on: 20 records at the true order; the truth within 3 reported standard errors in at
// least 17 of them and the root-mean-square reported standard error within a factor 1.6 of the
// observed spread (20 runs: the observed one is itself uncertain by about 16 %).
TEST(SsiUncertainty, FewRunsAtTheTrueOrderCoverTheTruth) {
  const ChainModel model;
  const auto cal = at_true_order(model, 20);
  for (std::size_t i = 0; i < cal.size(); ++i) {
    SCOPED_TRACE(i);
    ASSERT_EQ(cal[i].f.size(), 20u);
    EXPECT_GE(cal[i].f_inside, 17);
    EXPECT_GE(cal[i].z_inside, 17);
    EXPECT_GT(cal[i].ratio_f(), 1.0 / (1.6 * 1.6));
    EXPECT_LT(cal[i].ratio_f(), 1.6 * 1.6);
    EXPECT_GT(cal[i].ratio_z(), 1.0 / (1.6 * 1.6));
    EXPECT_LT(cal[i].ratio_z(), 1.6 * 1.6);
  }
}

// The 200-run calibrations (docs/oma.md, "Standard errors"). With 200 runs the Monte Carlo
// variance is uncertain by sqrt(2/199) = 10 % and the mean of the reported variances (each
// from 10 blocks, 9 degrees of freedom) by sqrt(2/9/200) = 3 %, so a ratio is known to about
// 11 %: ±25 % is 2.3 of those, and a variance 30 % off would leave it. Not every figure is
// inside ±25 % (docs/oma.md says which and why); the figures are pinned instead.
TEST(SsiUncertainty, PerturbationAtTheTrueOrderIsCalibrated) {
  CTID_SKIP_UNDER_SANITIZERS("200 Monte Carlo runs; FewRunsAtTheTrueOrderCoverTheTruth runs 20");
  const ChainModel model;
  expect_quoted(at_true_order(model, 200),
                {{99.0, 97.5, 1.16, 1.37},
                 {98.5, 96.5, 0.92, 1.12},
                 {99.0, 99.0, 0.98, 1.15},
                 {99.0, 97.5, 1.01, 0.89}},
                200, "perturbation, order 8");
}

TEST(SsiUncertainty, PerturbationThroughOmaIsCalibrated) {
  CTID_SKIP_UNDER_SANITIZERS("200 Monte Carlo runs; FewRunsAtTheTrueOrderCoverTheTruth runs 20");
  const ChainModel model;
  expect_quoted(through_oma(model, 200, OmaUncertainty::perturbation),
                {{98.5, 98.5, 0.91, 0.80},
                 {100.0, 96.5, 0.71, 0.75},
                 {100.0, 99.0, 0.74, 0.92},
                 {99.0, 97.5, 0.84, 0.61}},
                200, "perturbation, oma()");
}

TEST(SsiUncertainty, SegmentsThroughOmaAreCalibrated) {
  CTID_SKIP_UNDER_SANITIZERS("200 Monte Carlo runs; Oma.MonteCarloSpread... covers segments");
  const ChainModel model;
  expect_quoted(through_oma(model, 200, OmaUncertainty::segments),
                {{99.0, 99.5, 0.68, 0.48},
                 {98.5, 98.5, 0.70, 0.68},
                 {99.0, 98.5, 0.78, 0.80},
                 {99.5, 98.5, 0.88, 0.72}},
                200, "segments, oma()");
}

// Data-driven SSI has no perturbation estimate (decision 0036): its segment standard errors,
// the mode re-identified on each of the 10 blocks, calibrated on the same records.
TEST(SsiUncertainty, SsiDataSegmentsThroughOmaAreCalibrated) {
  CTID_SKIP_UNDER_SANITIZERS("200 Monte Carlo runs; Release only");
  const ChainModel model;
  expect_quoted(through_oma(model, 200, OmaUncertainty::segments, OmaMethod::ssi_data),
                {{99.5, 99.5, 0.65, 0.27},
                 {99.5, 98.0, 0.66, 0.72},
                 {99.5, 99.0, 0.70, 0.80},
                 {99.5, 99.0, 0.79, 0.72}},
                200, "ssi-data segments, oma()");
}

}  // namespace
}  // namespace ctid::ssi_uncertainty_test
