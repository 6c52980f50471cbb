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
#include <cstdlib>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/oma/oma.h"
#include "ctid/oma/ssi_cov.h"
#include "oma/chain_model.h"
#include "support/sanitizers.h"

namespace ctid::ssi_uncertainty_test {
namespace {

using oma_test::ChainModel;

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

// Per mode and kind of standard error: estimates, reported variances and coverage.
struct Calibration {
  int runs = 0;
  std::vector<double> f, z, f_var, z_var;
  int f_inside = 0, z_inside = 0;

  static double variance(const std::vector<double>& v) {
    double mean = 0.0;
    for (double x : v) mean += x / static_cast<double>(v.size());
    double ss = 0.0;
    for (double x : v) ss += (x - mean) * (x - mean);
    return ss / static_cast<double>(v.size() - 1);
  }
  static double mean(const std::vector<double>& v) {
    double m = 0.0;
    for (double x : v) m += x / static_cast<double>(v.size());
    return m;
  }
  double coverage_f() const { return static_cast<double>(f_inside) / runs; }
  double coverage_z() const { return static_cast<double>(z_inside) / runs; }
  /// Monte Carlo variance over the mean reported variance.
  double ratio_f() const { return variance(f) / mean(f_var); }
  double ratio_z() const { return variance(z) / mean(z_var); }
};

struct MonteCarlo {
  std::vector<Calibration> perturbation, segments;  // one per mode
};

// `runs` seeded records of the chain, each identified once per kind of standard error with
// the modes named (so that every run has every mode); the frequencies and damping ratios of
// both are the same estimates.
MonteCarlo calibrate(const ChainModel& model, int runs, int samples, OmaMethod method) {
  OmaOptions o;
  o.method = method;
  o.max_order = std::getenv("MCO") ? std::atoi(std::getenv("MCO")) : 16;
  o.block_rows = std::getenv("MCP") ? std::atoi(std::getenv("MCP")) : 12;
  for (const auto& m : model.modes) o.modes_near_hz.push_back(m.frequency_hz);
  MonteCarlo mc;
  mc.perturbation.resize(model.modes.size());
  mc.segments.resize(model.modes.size());
  for (int run = 0; run < runs; ++run) {
    const Eigen::MatrixXd y = model.simulate(samples, 0.05, 5000u + static_cast<unsigned>(run));
    for (const OmaUncertainty kind : {OmaUncertainty::perturbation, OmaUncertainty::segments}) {
      if (method == OmaMethod::ssi_data && kind == OmaUncertainty::perturbation) continue;
      o.uncertainty = kind;
      const OmaResult r = oma(y, model.h, o);
      auto& cal = kind == OmaUncertainty::perturbation ? mc.perturbation : mc.segments;
      for (std::size_t i = 0; i < model.modes.size(); ++i) {
        const auto& truth = model.modes[i];
        const OmaMode* m = oma_test::nearest(r, truth.frequency_hz);
        Calibration& c = cal[i];
        ++c.runs;
        if (m == nullptr || std::abs(m->frequency_hz / truth.frequency_hz - 1.0) > 0.02) continue;
        c.f.push_back(m->frequency_hz);
        c.z.push_back(m->damping_ratio);
        c.f_var.push_back(m->frequency_hz_std * m->frequency_hz_std);
        c.z_var.push_back(m->damping_ratio_std * m->damping_ratio_std);
        if (std::abs(m->frequency_hz - truth.frequency_hz) < 3.0 * m->frequency_hz_std) {
          ++c.f_inside;
        }
        if (std::abs(m->damping_ratio - truth.damping_ratio) < 3.0 * m->damping_ratio_std) {
          ++c.z_inside;
        }
      }
    }
  }
  return mc;
}

void print(const char* name, const std::vector<Calibration>& cal, const ChainModel& model) {
  for (std::size_t i = 0; i < cal.size(); ++i) {
    const Calibration& c = cal[i];
    if (c.runs == 0) continue;
    std::printf(
        "%s mode %zu (%.3f Hz, zeta %.4f): found %zu/%d, coverage f %.3f zeta %.3f, "
        "MC/reported variance f %.3f zeta %.3f\n",
        name, i, model.modes[i].frequency_hz, model.modes[i].damping_ratio, c.f.size(), c.runs,
        c.coverage_f(), c.coverage_z(), c.ratio_f(), c.ratio_z());
  }
}

TEST(SsiUncertainty, ChainModes) {
  const ChainModel model;
  for (const auto& m : model.modes)
    std::printf("%.4f Hz zeta %.5f\n", m.frequency_hz, m.damping_ratio);
  const MonteCarlo mc = calibrate(model, std::atoi(std::getenv("MCR")), 20000, OmaMethod::ssi_cov);
  print("perturbation", mc.perturbation, model);
  print("segments", mc.segments, model);
}

}  // namespace
}  // namespace ctid::ssi_uncertainty_test
