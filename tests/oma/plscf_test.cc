// pLSCF (decision 0066): exact correlations of the chain give its modes to rounding at the exact
// polynomial order (the half-spectra on the M-point grid are exactly rational), a simulated
// ambient record gives every mode within its segment standard errors and the SSI-cov shapes,
// records with no resonance give a verdict, and too short a record is refused naming what is
// wrong.
#include "ctid/oma/plscf.h"

#include <cmath>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/oma/oma.h"
#include "oma/calibration.h"
#include "oma/chain_model.h"
#include "support/sanitizers.h"

namespace ctid::plscf_test {
namespace {

using oma_test::ChainModel;

// 4 modes (8 poles): with r references the exact polynomial order is 8 / r.
TEST(Plscf, ExactCorrelationsGiveTheModesToRoundingAtTheExactOrder) {
  const ChainModel model;
  for (const std::vector<int>& refs :
       {std::vector<int>{0}, std::vector<int>{0, 3}, std::vector<int>{0, 1, 2, 3}}) {
    SCOPED_TRACE(refs.size());
    const int order = 8 / static_cast<int>(refs.size());
    const auto spectra = oma_detail::half_spectra(model.correlations(refs, 400), model.h, order);
    const auto poles = oma_detail::plscf_poles(spectra, order, 0.2);
    ASSERT_EQ(poles.size(), model.modes.size());
    for (std::size_t i = 0; i < poles.size(); ++i) {
      EXPECT_NEAR(poles[i].frequency_hz / model.modes[i].frequency_hz, 1.0, 1e-9);
      EXPECT_NEAR(poles[i].damping_ratio / model.modes[i].damping_ratio, 1.0, 1e-7);
      EXPECT_LT((poles[i].shape - model.modes[i].shape).cwiseAbs().maxCoeff(), 1e-7);
    }
  }
}

OmaOptions plscf_options() {
  OmaOptions o;
  o.method = OmaMethod::plscf;
  o.max_order = 12;
  o.reference_channels = {0, 3};
  return o;
}

TEST(Plscf, SimulatedChainRecordGivesEveryModeWithinItsStandardErrors) {
  const ChainModel model;
  const Eigen::MatrixXd y = model.simulate(40000, 0.05, 11);
  const OmaResult r = oma(y, model.h, plscf_options());
  EXPECT_EQ(r.method, OmaMethod::plscf);
  EXPECT_TRUE(r.verdict.usable) << r.verdict.summary();
  EXPECT_THAT(r.message, ::testing::HasSubstr("standard errors from 10 segments of"));
  OmaOptions ssi = plscf_options();
  ssi.method = OmaMethod::ssi_cov;
  ssi.max_order = 24;  // states, where pLSCF's 12 are polynomial orders of 2 poles each
  const OmaResult reference = oma(y, model.h, ssi);
  ASSERT_EQ(r.modes.size(), model.modes.size());
  for (const auto& truth : model.modes) {
    SCOPED_TRACE(truth.frequency_hz);
    const OmaMode* m = oma_test::expect_found_within_errors(r, truth);
    const OmaMode* s = oma_test::nearest(reference, truth.frequency_hz);
    ASSERT_TRUE(m != nullptr && s != nullptr);
    EXPECT_LT(std::abs(m->frequency_hz / s->frequency_hz - 1.0), 0.005);
    EXPECT_GE(oma_detail::modal_assurance(oma_test::shape_of(*m), oma_test::shape_of(*s)), 0.99);
  }
}

// 200 seeded ambient records of the chain: the truth within 3 segment standard errors in at
// least 90 % of the records for every mode's frequency and damping ratio (issue 34's bound),
// and the Monte Carlo variance over the mean reported variance as docs/oma.md quotes it.
TEST(Plscf, SegmentStandardErrorsCoverTheTruthInMonteCarlo) {
  CTID_SKIP_UNDER_SANITIZERS("200 analyses; Release only");
  const ChainModel model;
  const int runs = 200;
  std::vector<oma_test::Calibration> cal(model.modes.size());
  for (int run = 0; run < runs; ++run) {
    const OmaResult r = oma(model.simulate(20000, 0.05, 500u + static_cast<unsigned>(run)), model.h,
                            plscf_options());
    for (std::size_t i = 0; i < model.modes.size(); ++i) {
      const auto& truth = model.modes[i];
      const OmaMode* m = oma_test::nearest(r, truth.frequency_hz);
      if (m == nullptr || std::abs(m->frequency_hz / truth.frequency_hz - 1.0) > 0.02) continue;
      cal[i].add(truth, m->frequency_hz, m->frequency_hz_std, m->damping_ratio,
                 m->damping_ratio_std);
    }
  }
  oma_test::expect_quoted(cal,
                          {{98.5, 99.0, 0.87, 0.74},
                           {99.0, 97.5, 1.02, 0.94},
                           {96.5, 98.5, 1.14, 0.70},
                           {99.5, 100.0, 0.88, 0.87}},
                          runs, "plscf segments, oma()");
}

TEST(Plscf, WhiteNoiseHasNoMode) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd y(20000, 4);
  for (Eigen::Index k = 0; k < y.rows(); ++k) {
    for (Eigen::Index j = 0; j < y.cols(); ++j) y(k, j) = normal(rng);
  }
  const OmaResult r = oma(y, 0.01, plscf_options());
  EXPECT_TRUE(r.modes.empty()) << r.modes.size();
  EXPECT_FALSE(r.verdict.usable);
  EXPECT_THAT(r.verdict.summary(), ::testing::HasSubstr("no mode found"));
}

TEST(Plscf, TooShortARecordIsRefusedNamingTheOrder) {
  const ChainModel model;
  const Eigen::MatrixXd y = model.simulate(300, 0.05, 3);
  OmaOptions o = plscf_options();
  o.max_order = 20;
  try {
    (void)oma(y, model.h, o);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("samples; plscf to polynomial order 20"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("a lower --max-order"));
  }
}

}  // namespace
}  // namespace ctid::plscf_test
