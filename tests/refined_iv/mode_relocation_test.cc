// Mode relocation (mode_relocation.h) on a small three-mode system: a weak, lightly damped
// mode started far from the truth makes the additive iteration stop at a wrong stationary
// point; relocation must move it to the truth without ever worsening its criterion.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/mode_relocation.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"

namespace ctid::mode_relocation_test {
namespace {

using ::testing::HasSubstr;

constexpr double kH = 1.0 / 512.0;
constexpr int kN = 2048;
const std::vector<SubmodelOrder> kOrders(3, SubmodelOrder{2, 0, 0});

// theta = [a1, a2, b0] of a mode with natural frequency hz, damping zeta and static gain.
Eigen::VectorXd mode(double hz, double zeta, double gain) {
  const double w = 2.0 * M_PI * hz;
  Eigen::VectorXd theta(3);
  theta << 2.0 * zeta / w, 1.0 / (w * w), gain;
  return theta;
}

Eigen::VectorXd stack(const Eigen::VectorXd& a, const Eigen::VectorXd& b,
                      const Eigen::VectorXd& c) {
  Eigen::VectorXd out(9);
  out << a, b, c;
  return out;
}

// A strong mode at 2 Hz, a moderate one at 9 Hz and a weak, very lightly damped one at
// 31.3 Hz (0.1 % of the strong gain, half-power bandwidth 0.03 Hz).
AdditiveModel truth() {
  return AdditiveModel::from_parameters(
      kOrders, stack(mode(2.0, 0.01, 1.0), mode(9.0, 2e-3, 0.02), mode(31.3, 5e-4, 1e-3)));
}

// The weak mode starts at `weak_start_hz`, the others near the truth.
AdditiveModel start(double weak_start_hz) {
  return AdditiveModel::from_parameters(
      kOrders, stack(mode(1.8, 0.02, 0.8), mode(9.5, 5e-3, 0.05), mode(weak_start_hz, 1e-3, 1e-2)));
}

// One period of a random-phase multisine, 0.25-60 Hz, and the truth's response plus white
// noise at the given SNR (infinite: none).
SampledData data(double snr_db, std::uint64_t seed) {
  MultisineOptions m;
  m.period_length = kN;
  m.sample_time = kH;
  m.min_frequency = 0.25;
  m.max_frequency = 60.0;
  m.seed = 3;
  const Eigen::VectorXd u = multisine(m).signal;
  Eigen::VectorXd y = simulate(truth(), u, kH);
  if (std::isfinite(snr_db)) y += scale_noise_to_snr(y, white_noise(kN, 1.0, seed), snr_db);
  return SampledData(kH, u, y);
}

RefinedIvOptions options_from(double weak_start_hz) {
  RefinedIvOptions o;
  o.initial_model = start(weak_start_hz);
  o.noise = NoiseAssumption::white;
  o.max_iterations = 200;
  return o;
}

// The estimate's mode nearest in natural frequency to `t`.
const ModalEstimate& nearest(const EstimationResult& r, const ModalParameters& t) {
  const ModalEstimate* best = &r.modes.front();
  for (const ModalEstimate& m : r.modes) {
    if (std::abs(m.value.natural_frequency - t.natural_frequency) <
        std::abs(best->value.natural_frequency - t.natural_frequency)) {
      best = &m;
    }
  }
  return *best;
}

double weak_mode_error_in_standard_errors(const EstimationResult& r) {
  const ModalParameters t = *truth().modal_parameters(2);
  const ModalEstimate& m = nearest(r, t);
  return std::abs(m.value.natural_frequency - t.natural_frequency) /
         m.standard_error.natural_frequency;
}

TEST(ModeRelocation, WeakModeStartedFarOffIsMovedToTheTruth) {
  for (std::uint64_t seed : {1U, 2U}) {
    const SampledData d = data(30.0, seed);
    const EstimationResult plain = additive_srivc(d, kOrders, options_from(20.0));
    ASSERT_TRUE(plain.converged()) << plain.message;
    // Without relocation the weak mode stays far away, and its standard error does not say so.
    EXPECT_GT(weak_mode_error_in_standard_errors(plain), 10.0) << "seed " << seed;

    const ModeRelocationResult r = additive_srivc_relocated(d, kOrders, options_from(20.0));
    ASSERT_TRUE(r.estimate.converged()) << r.message;
    EXPECT_GE(r.relocations, 1) << r.message;
    EXPECT_DOUBLE_EQ(r.initial_mean_squared_error, plain.mean_squared_error);
    ASSERT_EQ(r.estimate.modes.size(), 3U);
    for (int i = 0; i < 3; ++i) {
      const ModalParameters t = *truth().modal_parameters(i);
      const ModalEstimate& m = nearest(r.estimate, t);
      EXPECT_LT(std::abs(m.value.natural_frequency - t.natural_frequency),
                3.0 * m.standard_error.natural_frequency)
          << "seed " << seed << ", mode " << i << ": " << r.message;
      EXPECT_LT(std::abs(m.value.damping_ratio - t.damping_ratio),
                3.0 * m.standard_error.damping_ratio)
          << "seed " << seed << ", mode " << i << ": " << r.message;
    }
    // The report names the move: the weak mode's submodel went to within a line of 31.3 Hz.
    bool moved = false;
    for (const RelocationTrial& t : r.trials) {
      if (t.accepted && t.submodel == 2) {
        moved = std::abs(t.start_frequency / (2.0 * M_PI) - 31.3) < 0.25;
      }
    }
    EXPECT_TRUE(moved) << r.message;
    // Peaks are taken only in the excited band (0.25-60 Hz; the floor's window blurs its edge
    // by half of +-64 lines of 0.25 Hz), never up to the Nyquist frequency (256 Hz).
    for (const RelocationTrial& t : r.trials) {
      EXPECT_LT(t.peak_frequency / (2.0 * M_PI), 60.0 + 8.0) << r.message;
    }
    EXPECT_THAT(r.message, HasSubstr("relocation(s) kept"));
  }
}

TEST(ModeRelocation, NoiseFreeExactEstimateIsKept) {
  const SampledData d = data(INFINITY, 0);
  RefinedIvOptions o = options_from(20.0);
  o.compute_covariance = false;
  // Without noise the plain iteration reaches the truth from this start; relocation must not
  // move it away (a move is kept only if it fits better, and nothing fits better).
  const EstimationResult plain = additive_srivc(d, kOrders, o);
  const Eigen::VectorXd beta = truth().parameters();
  EXPECT_LT((plain.parameters - beta).cwiseQuotient(beta).cwiseAbs().maxCoeff(), 1e-6);
  const ModeRelocationResult r = additive_srivc_relocated(d, kOrders, o);
  ASSERT_TRUE(r.estimate.converged()) << r.message;
  EXPECT_LT((r.estimate.parameters - beta).cwiseQuotient(beta).cwiseAbs().maxCoeff(), 1e-6)
      << r.message;
}

// Each criterion is never worse at the end than at the start, whatever the start.
TEST(ModeRelocation, NeverWorsensItsCriterion) {
  const SampledData d = data(30.0, 5);
  for (double weak_start : {14.0, 24.0, 45.0}) {
    ModeRelocationOptions by_output_error;
    by_output_error.criterion = RelocationCriterion::output_error;
    RefinedIvOptions o = options_from(weak_start);
    o.compute_covariance = false;
    const ModeRelocationResult a = additive_srivc_relocated(d, kOrders, o, by_output_error);
    EXPECT_LE(a.estimate.mean_squared_error, a.initial_mean_squared_error * (1.0 + 1e-12))
        << a.message;
    const ModeRelocationResult b = additive_srivc_relocated(d, kOrders, o);
    EXPECT_DOUBLE_EQ(b.initial_score, b.initial_projected_mean_squared_error);
    EXPECT_LE(b.score, b.initial_score) << b.message;
    // Every kept trial improved on the one kept before it and converged; its score is the
    // projected output error of the fixed point or of its start, whichever is smaller.
    double last = b.initial_score;
    for (const RelocationTrial& t : b.trials) {
      EXPECT_LE(t.score, t.projected_mean_squared_error);
      EXPECT_TRUE(t.score == t.projected_mean_squared_error ||
                  t.score == t.start_mean_squared_error);
      if (!t.accepted) continue;
      EXPECT_LT(t.score, last);
      EXPECT_EQ(t.termination, Termination::converged);
      last = t.score;
    }
    EXPECT_EQ(b.score, last);
  }
}

TEST(ModeRelocation, ZeroRelocationsIsThePlainEstimateAndRunsAreReplayable) {
  const SampledData d = data(40.0, 3);
  ModeRelocationOptions none;
  none.max_relocations = 0;
  const EstimationResult plain = additive_srivc(d, kOrders, options_from(20.0));
  const ModeRelocationResult r0 = additive_srivc_relocated(d, kOrders, options_from(20.0), none);
  EXPECT_EQ(r0.relocations, 0);
  EXPECT_TRUE(r0.trials.empty());
  EXPECT_EQ(r0.estimate.parameters, plain.parameters);
  const ModeRelocationResult r1 = additive_srivc_relocated(d, kOrders, options_from(20.0));
  const ModeRelocationResult r2 = additive_srivc_relocated(d, kOrders, options_from(20.0));
  EXPECT_EQ(r1.estimate.parameters, r2.estimate.parameters);
  EXPECT_EQ(r1.trials.size(), r2.trials.size());
}

TEST(ModeRelocation, OnlySecondOrderSubmodelsWithoutIntegratorsMove) {
  // Two first-order submodels: nothing can be relocated, the plain estimate comes back.
  const std::vector<SubmodelOrder> orders{{1, 0, 0}, {1, 0, 0}};
  const AdditiveModel g({Submodel{Polynomial{1.0, 0.5}, Polynomial{1.0}, 0},
                         Submodel{Polynomial{1.0, 0.05}, Polynomial{0.3}, 0}});
  const Eigen::VectorXd u = white_noise(1000, 1.0, 4);
  const Eigen::VectorXd y = simulate(g, u, 0.01) + white_noise(1000, 0.01, 5);
  const ModeRelocationResult r = additive_srivc_relocated(SampledData(0.01, u, y), orders);
  EXPECT_EQ(r.rounds, 0);
  EXPECT_EQ(r.relocations, 0);
}

// Outside the excited band a lightly damped mode can only fit the start-up transient, i.e.
// noise; with the band check off (min_input_level = 0) such peaks are tried.
TEST(ModeRelocation, PeaksOutsideTheExcitedBandAreTriedOnlyWithoutTheBandCheck) {
  const SampledData d = data(30.0, 2);
  auto highest_peak_hz = [&](double level) {
    ModeRelocationOptions o;
    o.min_input_level = level;
    const ModeRelocationResult r = additive_srivc_relocated(d, kOrders, options_from(20.0), o);
    double highest = 0.0;
    for (const RelocationTrial& t : r.trials) highest = std::max(highest, t.peak_frequency);
    return highest / (2.0 * M_PI);
  };
  EXPECT_LT(highest_peak_hz(1e-2), 68.0);
  EXPECT_GT(highest_peak_hz(0.0), 68.0);
}

TEST(ModeRelocation, OptionsNameTheBadField) {
  auto message = [](auto change) {
    ModeRelocationOptions o;
    change(o);
    try {
      o.validate();
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message([](ModeRelocationOptions&) {}), "accepted");
  EXPECT_THAT(message([](ModeRelocationOptions& o) { o.max_relocations = -1; }),
              HasSubstr("ModeRelocationOptions.max_relocations is -1; it must be >= 0"));
  EXPECT_THAT(message([](ModeRelocationOptions& o) { o.peaks_per_round = 0; }),
              HasSubstr("peaks_per_round is 0"));
  EXPECT_THAT(message([](ModeRelocationOptions& o) { o.min_peak_to_floor = 1.0; }),
              HasSubstr("min_peak_to_floor is 1; it must be finite and > 1"));
  EXPECT_THAT(message([](ModeRelocationOptions& o) { o.min_input_level = 2.0; }),
              HasSubstr("min_input_level is 2; it must be in [0, 1]"));
  EXPECT_THAT(message([](ModeRelocationOptions& o) { o.floor_half_width = 0; }),
              HasSubstr("floor_half_width is 0"));
  EXPECT_THAT(message([](ModeRelocationOptions& o) { o.zero_padding = 0; }),
              HasSubstr("zero_padding is 0"));
  EXPECT_THAT(message([](ModeRelocationOptions& o) { o.search_half_width = NAN; }),
              HasSubstr("search_half_width is NaN; it must be a number"));
  EXPECT_THAT(message([](ModeRelocationOptions& o) { o.search_points = 2; }),
              HasSubstr("search_points is 2; it must be >= 3"));
  EXPECT_THAT(message([](ModeRelocationOptions& o) { o.damping_ratios.clear(); }),
              HasSubstr("damping_ratios is empty"));
  EXPECT_THAT(message([](ModeRelocationOptions& o) {
                o.damping_ratios = {1e-3, 1.0};
              }),
              HasSubstr("damping_ratios[1] is 1; it must be in (0, 1)"));
  EXPECT_THAT(message([](ModeRelocationOptions& o) { o.trials_per_round = 0; }),
              HasSubstr("trials_per_round is 0"));
  EXPECT_THAT(message([](ModeRelocationOptions& o) { o.min_relative_decrease = 1.0; }),
              HasSubstr("min_relative_decrease is 1; it must be in [0, 1)"));
  // The estimator refuses bad options before doing any work.
  ModeRelocationOptions bad;
  bad.trials_per_round = 0;
  EXPECT_THROW(additive_srivc_relocated(data(40.0, 1), kOrders, options_from(20.0), bad),
               InvalidArgument);
}

}  // namespace
}  // namespace ctid::mode_relocation_test
