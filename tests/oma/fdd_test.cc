// Frequency-domain decomposition (oma(), method fdd and efdd) and its numerical core: the
// spectral matrix against closed forms (a sinusoid's line, white noise's level, Hermitian and
// positive semi-definite), the modes of seeded simulated ambient records of a known chain
// (frequency within a line, shapes MAC >= 0.99, a seeded Monte Carlo of EFDD's frequency and
// damping). Records with no resonance: oma_test.cc, for every method.
#include "ctid/oma/fdd.h"

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/oma/oma.h"
#include "ctid/oma/ssi_cov.h"
#include "oma/chain_model.h"
#include "support/sanitizers.h"

namespace ctid::fdd_test {
namespace {

using oma_test::ChainModel;

OmaOptions options(OmaMethod method) {
  OmaOptions o;
  o.method = method;
  return o;
}

// A sinusoid A cos(2 pi f t) on line m of a Hann-windowed L-sample segment: one-sided density
// A^2 h (sum w)^2 / (2 sum w^2) = A^2 h L / 3 there (sum w = L/2, sum w^2 = 3L/8), and the
// cross density of two channels a, b of it is a b times that, real.
TEST(FddSpectralMatrix, ASinusoidOnALineHasItsClosedFormDensity) {
  const int length = 256, line = 20;
  const double h = 0.01, amplitude = 3.0;
  Eigen::MatrixXd y(4 * length, 2);
  for (Eigen::Index k = 0; k < y.rows(); ++k) {
    const double c = amplitude * std::cos(2.0 * std::numbers::pi * line * k / length);
    y(k, 0) = c;
    y(k, 1) = -0.5 * c;
  }
  const oma_detail::SpectralMatrix s = oma_detail::output_spectral_matrix(y, h, length);
  EXPECT_EQ(s.segments, 7);  // half overlap
  EXPECT_DOUBLE_EQ(s.frequency_hz(line), line / (length * h));
  const double expected = amplitude * amplitude * h * length / 3.0;
  const Eigen::MatrixXcd& g = s.g[line];
  EXPECT_NEAR(g(0, 0).real(), expected, 1e-10 * expected);
  EXPECT_NEAR(g(0, 1).real(), -0.5 * expected, 1e-10 * expected);
  EXPECT_NEAR(std::abs(g(0, 1).imag()), 0.0, 1e-10 * expected);
  EXPECT_NEAR(g(1, 1).real(), 0.25 * expected, 1e-10 * expected);
  // Two lines off, the Hann window's leakage is exactly zero.
  EXPECT_LT(s.g[line + 2].norm(), 1e-20 * expected);
}

// White noise of variance sigma^2 has the one-sided density 2 sigma^2 h; averaged over
// 2000 lines and 31 segments the estimate's relative spread is about 0.5 %.
TEST(FddSpectralMatrix, WhiteNoiseHasItsLevelAndEveryLineIsHermitianAndSemiDefinite) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 2.0);
  Eigen::MatrixXd y(64000, 3);
  for (Eigen::Index k = 0; k < y.rows(); ++k) {
    for (Eigen::Index j = 0; j < y.cols(); ++j) y(k, j) = normal(rng);
  }
  const double h = 0.002;
  const oma_detail::SpectralMatrix s = oma_detail::output_spectral_matrix(y, h, 4000);
  double level = 0.0;
  int counted = 0;
  for (std::size_t k = 1; k + 1 < s.g.size(); ++k) {
    const Eigen::MatrixXcd& g = s.g[k];
    ASSERT_LT((g - g.adjoint()).norm(), 1e-12 * g.norm());
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> eig(g);
    ASSERT_GE(eig.eigenvalues().minCoeff(), -1e-12 * g.norm());
    level += g.trace().real() / 3.0;
    ++counted;
  }
  EXPECT_NEAR(level / counted, 2.0 * 4.0 * h, 0.03 * 2.0 * 4.0 * h);
}

TEST(Fdd, SimulatedChainRecordGivesEveryModeWithinALineAndItsShape) {
  const ChainModel model;
  const Eigen::MatrixXd y = model.simulate(40000, 0.05, 11);
  for (const OmaMethod method : {OmaMethod::fdd, OmaMethod::efdd}) {
    const OmaResult r = oma(y, model.h, options(method));
    EXPECT_TRUE(r.verdict.usable) << r.verdict.summary();
    EXPECT_EQ(r.method, method);
    ASSERT_EQ(r.modes.size(), model.modes.size()) << r.message;
    const double line_hz = 1.0 / (4096 * model.h);  // the automatic segment: N/8 -> 4096
    EXPECT_THAT(r.message, ::testing::HasSubstr("4096-sample segments"));
    for (std::size_t i = 0; i < r.modes.size(); ++i) {
      SCOPED_TRACE(model.modes[i].frequency_hz);
      EXPECT_LT(std::abs(r.modes[i].frequency_hz - model.modes[i].frequency_hz), 2.0 * line_hz);
      EXPECT_GE(oma_detail::modal_assurance(oma_test::shape_of(r.modes[i]), model.modes[i].shape),
                0.99);
      EXPECT_GT(r.modes[i].mpc, 0.95);
      EXPECT_TRUE(std::isnan(r.modes[i].frequency_hz_std));
      EXPECT_EQ(std::isnan(r.modes[i].damping_ratio), method == OmaMethod::fdd);
    }
  }
}

// 24 seeded records of 40000 samples: EFDD's frequencies unbiased to 0.2 % with a spread under
// 0.5 %; its damping ratios (each bell spans few lines of 4096-sample segments, 18 averaged)
// within 35 % on average, the spread under 40 %, and one mode per resonance in every record.
TEST(Fdd, MonteCarloOfEfddFrequencyAndDamping) {
  CTID_SKIP_UNDER_SANITIZERS("24 records of 40000 samples; the single-record tests run here");
  const ChainModel model;
  const std::size_t modes = model.modes.size();
  std::vector<double> f_sum(modes), f_sq(modes), z_sum(modes), z_sq(modes);
  const int runs = 24;
  for (int run = 0; run < runs; ++run) {
    const OmaResult r = oma(model.simulate(40000, 0.05, 500u + static_cast<unsigned>(run)), model.h,
                            options(OmaMethod::efdd));
    ASSERT_EQ(r.modes.size(), modes) << "seed " << 500 + run;
    for (std::size_t i = 0; i < modes; ++i) {
      const double f = r.modes[i].frequency_hz / model.modes[i].frequency_hz - 1.0;
      const double z = r.modes[i].damping_ratio / model.modes[i].damping_ratio - 1.0;
      f_sum[i] += f / runs;
      f_sq[i] += f * f / runs;
      z_sum[i] += z / runs;
      z_sq[i] += z * z / runs;
    }
  }
  for (std::size_t i = 0; i < modes; ++i) {
    SCOPED_TRACE(model.modes[i].frequency_hz);
    EXPECT_LT(std::abs(f_sum[i]), 0.002);
    EXPECT_LT(std::sqrt(f_sq[i] - f_sum[i] * f_sum[i]), 0.005);
    EXPECT_LT(std::abs(z_sum[i]), 0.35);
    EXPECT_LT(std::sqrt(z_sq[i] - z_sum[i] * z_sum[i]), 0.4);
  }
}

TEST(Fdd, ModesNearPicksTheNamedPeaksOnly) {
  const ChainModel model;
  const Eigen::MatrixXd y = model.simulate(40000, 0.05, 13);
  OmaOptions o = options(OmaMethod::fdd);
  o.modes_near_hz = {model.modes[2].frequency_hz * 1.02, model.modes[0].frequency_hz};
  const OmaResult r = oma(y, model.h, o);
  ASSERT_EQ(r.modes.size(), 2u);
  EXPECT_NEAR(r.modes[0].frequency_hz, model.modes[0].frequency_hz, 0.01 * 6.3);
  EXPECT_NEAR(r.modes[1].frequency_hz, model.modes[2].frequency_hz, 0.01 * 30.1);
  o.modes_near_hz = {1000.0};
  const OmaResult none = oma(y, model.h, o);
  EXPECT_FALSE(none.verdict.usable);
  EXPECT_THAT(none.verdict.summary(),
              ::testing::HasSubstr("no mode near 1000 Hz: it is not below the Nyquist frequency "
                                   "100 Hz"));
  o.modes_near_hz = {0.001};  // below the first line (0.049 Hz): none within 10 %
  const OmaResult low = oma(y, model.h, o);
  EXPECT_THAT(low.verdict.summary(), ::testing::HasSubstr("no spectral line within 10 % of 0.001"));
}

}  // namespace
}  // namespace ctid::fdd_test
