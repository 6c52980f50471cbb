// Section 7 of González et al. on a simulated beam: the paper's converged four-mode estimate
// (theta_hat_1..4) is the true system, with a 4-sample input delay, h = 1/4096 s, and one
// period (8192 samples, 2 s) of a random-phase multisine flat from 0.5 to 500 Hz. The
// additive open-loop estimator starts from the paper's deliberately wrong theta_i^1. The
// numbers these tests bound are discussed in docs/algorithms/section7-beam.md.
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "ctid/filtering/filter_bank.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/input_delay_scan.h"
#include "ctid/refined_iv/mode_relocation.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/noise.h"
#include "ctid/simulation/simulate.h"
#include "support/paper_systems.h"
#include "support/sanitizers.h"

namespace ctid::beam_section7_test {
namespace {

// The beam of tests/support/paper_systems.h, sampled over one period of the multisine.
constexpr double kSampleTime = testing::kBeamSampleTime;
constexpr int kSamples = testing::kBeamPeriod;
constexpr int kDelay = testing::kBeamDelay;

const std::vector<SubmodelOrder> kOrders = testing::beam_orders();

// The paper's excitation; an optional white dither can be added on top.
Eigen::VectorXd beam_input(double dither_rms) {
  MultisineOptions options;
  options.period_length = kSamples;
  options.sample_time = kSampleTime;
  options.min_frequency = 0.5;
  options.max_frequency = 500.0;
  options.seed = 1;
  Eigen::VectorXd u = multisine(options).signal;
  if (dither_rms > 0.0) u += white_noise(kSamples, dither_rms, 99);
  return u;
}

SampledData beam_data(double snr_db, std::uint64_t noise_seed, double dither_rms = 0.0) {
  const Eigen::VectorXd u = beam_input(dither_rms);
  Eigen::VectorXd y = simulate(testing::beam(), u, kSampleTime);
  if (std::isfinite(snr_db)) {
    y += scale_noise_to_snr(y, white_noise(kSamples, 1.0, noise_seed), snr_db);
  }
  return SampledData(kSampleTime, u, y);
}

RefinedIvOptions options_from(const Eigen::VectorXd& start) {
  RefinedIvOptions options;
  options.initial_model = AdditiveModel::from_parameters(kOrders, start);
  options.max_iterations = 200;
  options.noise = NoiseAssumption::white;
  return options;
}

// Modal parameters of the truth, in the order of the submodels.
std::vector<ModalParameters> true_modes() {
  const AdditiveModel g = testing::beam();
  std::vector<ModalParameters> modes;
  for (int i = 0; i < g.size(); ++i) modes.push_back(*g.modal_parameters(i));
  return modes;
}

// The estimate's mode closest in natural frequency to `truth` (submodels may come back in
// another order).
const ModalEstimate& closest_mode(const EstimationResult& r, const ModalParameters& truth) {
  const ModalEstimate* best = &r.modes.front();
  for (const ModalEstimate& m : r.modes) {
    if (std::abs(m.value.natural_frequency - truth.natural_frequency) <
        std::abs(best->value.natural_frequency - truth.natural_frequency)) {
      best = &m;
    }
  }
  return *best;
}

TEST(BeamSection7, NoiseFreeConvergesFromThePapersStartWithTheDelayEstimated) {
  RefinedIvOptions options = options_from(testing::beam_start_parameters());
  options.compute_covariance = false;
  const InputDelayScanResult scan =
      additive_srivc_delay_scan(beam_data(INFINITY, 0), kOrders, 2, 6, options);
  const EstimationResult& r = scan.best;
  EXPECT_EQ(r.input_delay_samples, kDelay);
  ASSERT_TRUE(r.converged()) << r.message;
  ASSERT_EQ(r.model.size(), 4);
  // Without covariance the result has no ModalEstimate list; read the modes off the model.
  for (const ModalParameters& truth : true_modes()) {
    std::optional<ModalParameters> best;
    for (int i = 0; i < r.model.size(); ++i) {
      const std::optional<ModalParameters> m = r.model.modal_parameters(i);
      if (m && (!best || std::abs(m->natural_frequency - truth.natural_frequency) <
                             std::abs(best->natural_frequency - truth.natural_frequency))) {
        best = m;
      }
    }
    ASSERT_TRUE(best.has_value());
    EXPECT_NEAR(best->natural_frequency / truth.natural_frequency, 1.0, 1e-4)
        << "mode at " << truth.natural_frequency << " rad/s";
    EXPECT_NEAR(best->damping_ratio / truth.damping_ratio, 1.0, 1e-4);
    EXPECT_NEAR(best->gain / truth.gain, 1.0, 1e-4);
  }
}

TEST(BeamSection7, SixtyDecibelsConvergesFromThePapersStartWithinThreeStandardErrors) {
  const InputDelayScanResult scan = additive_srivc_delay_scan(
      beam_data(60.0, 7), kOrders, 3, 5, options_from(testing::beam_start_parameters()));
  const EstimationResult& r = scan.best;
  EXPECT_EQ(r.input_delay_samples, kDelay);
  ASSERT_TRUE(r.converged()) << r.message;
  ASSERT_EQ(r.modes.size(), 4U);
  for (const ModalParameters& truth : true_modes()) {
    const ModalEstimate& m = closest_mode(r, truth);
    const double w_error = m.value.natural_frequency - truth.natural_frequency;
    const double z_error = m.value.damping_ratio - truth.damping_ratio;
    EXPECT_LT(std::abs(w_error) / truth.natural_frequency, 1e-4)
        << "mode at " << truth.natural_frequency << " rad/s";
    EXPECT_LT(std::abs(w_error), 3.0 * m.standard_error.natural_frequency);
    EXPECT_LT(std::abs(z_error), 3.0 * m.standard_error.damping_ratio);
  }
}

// At 30 dB the two weak modes (static gains 3e-4 and 1e-4 against 11.8, damping ~1e-4) carry
// little of the output power: their estimates spread, and the standard errors must widen to
// cover it. Started at the true modes, so this checks the covariance, not the basin.
TEST(BeamSection7, ThirtyDecibelsWeakModesDegradeAndTheirStandardErrorsSaySo) {
  const std::vector<ModalParameters> truth = true_modes();
  for (std::uint64_t seed : {7U, 8U}) {
    RefinedIvOptions options = options_from(testing::beam_parameters());
    options.input_delay_samples = kDelay;
    const EstimationResult r = additive_srivc(beam_data(30.0, seed), kOrders, options);
    ASSERT_TRUE(r.converged()) << r.message;
    std::vector<double> relative_se;
    for (const ModalParameters& t : truth) {
      const ModalEstimate& m = closest_mode(r, t);
      EXPECT_LT(std::abs(m.value.natural_frequency - t.natural_frequency),
                3.0 * m.standard_error.natural_frequency)
          << "seed " << seed << ", mode at " << t.natural_frequency << " rad/s";
      EXPECT_LT(std::abs(m.value.damping_ratio - t.damping_ratio),
                3.0 * m.standard_error.damping_ratio)
          << "seed " << seed << ", mode at " << t.natural_frequency << " rad/s";
      relative_se.push_back(m.standard_error.damping_ratio / t.damping_ratio);
    }
    // The weak modes' damping is known an order of magnitude worse than the strong modes'.
    EXPECT_GT(relative_se[2], 10.0 * relative_se[1]) << "seed " << seed;
    EXPECT_GT(relative_se[3], 10.0 * relative_se[1]) << "seed " << seed;
  }
}

// From the paper's start at 30-50 dB the plain iteration stops with modes 3-4 near their
// wrong starting frequencies (a stationary point with a slightly larger output error, see the
// doc). Mode relocation moves them.
ModeRelocationResult relocate(const SampledData& data) {
  RefinedIvOptions options = options_from(testing::beam_start_parameters());
  options.input_delay_samples = kDelay;
  return additive_srivc_relocated(data, kOrders, options);
}

// |error| / standard error of the natural frequency and of the damping ratio.
std::pair<double, double> errors_in_standard_errors(const EstimationResult& r,
                                                    const ModalParameters& t) {
  const ModalEstimate& m = closest_mode(r, t);
  return {std::abs(m.value.natural_frequency - t.natural_frequency) /
              m.standard_error.natural_frequency,
          std::abs(m.value.damping_ratio - t.damping_ratio) / m.standard_error.damping_ratio};
}

// Output error of the true denominators with every numerator re-fitted by least squares:
// what the truth's poles can explain of these data (an independent reference for the
// relocation's projected criterion).
double true_poles_projected_mse(const SampledData& data) {
  const Eigen::VectorXd u = delay_samples(data.input(), kDelay);
  const AdditiveModel g = testing::beam();
  Eigen::MatrixXd x(kSamples, g.size());
  for (int i = 0; i < g.size(); ++i) {
    x.col(i) = filter_derivatives(g[i].a, u, kSampleTime, Hold::zero_order_hold).col(0);
  }
  const Eigen::VectorXd norms = x.colwise().norm().transpose();
  const Eigen::MatrixXd scaled = x * norms.cwiseInverse().asDiagonal();
  const Eigen::VectorXd fitted = scaled * scaled.colPivHouseholderQr().solve(data.output());
  return (data.output() - fitted).squaredNorm() / kSamples;
}

void expect_all_modes_within_three_standard_errors(double snr_db, std::uint64_t seed) {
  const ModeRelocationResult r = relocate(beam_data(snr_db, seed));
  const std::string where =
      "SNR " + std::to_string(snr_db) + " dB, seed " + std::to_string(seed) + ": " + r.message;
  ASSERT_TRUE(r.estimate.converged()) << where;
  ASSERT_EQ(r.estimate.modes.size(), 4U) << where;
  EXPECT_LE(r.estimate.mean_squared_error, r.initial_mean_squared_error) << where;
  for (const ModalParameters& t : true_modes()) {
    const auto [w, z] = errors_in_standard_errors(r.estimate, t);
    EXPECT_LT(w, 3.0) << where << "; mode at " << t.natural_frequency << " rad/s";
    EXPECT_LT(z, 3.0) << where << "; mode at " << t.natural_frequency << " rad/s";
  }
}

TEST(BeamSection7, FortyDecibelsFromThePapersStartRelocationReachesEveryMode) {
  CTID_SKIP_UNDER_SANITIZERS(
      "SixtyDecibelsConvergesFromThePapersStartWithinThreeStandardErrors runs the same beam fit; "
      "ModeRelocation tests run the relocation");
  for (std::uint64_t seed : {7U, 8U, 9U}) expect_all_modes_within_three_standard_errors(40.0, seed);
}

TEST(BeamSection7, FiftyDecibelsFromThePapersStartRelocationReachesEveryMode) {
  CTID_SKIP_UNDER_SANITIZERS(
      "SixtyDecibelsConvergesFromThePapersStartWithinThreeStandardErrors runs the same beam fit; "
      "ModeRelocation tests run the relocation");
  for (std::uint64_t seed : {10U, 11U, 12U}) {
    expect_all_modes_within_three_standard_errors(50.0, seed);
  }
}

// At 30 dB mode 4 explains about 9 noise variances of the output's sum of squares, about as
// much as the largest noise peak a lightly damped mode can fit in the 0.5-500 Hz band. Modes
// 1-3 must always be found; mode 4 must be found unless the data themselves prefer the
// noise peak, i.e. unless the estimate's poles fit better than the true poles do.
TEST(BeamSection7, ThirtyDecibelsFromThePapersStartRelocationFindsTheWeakModesTheDataSupport) {
  CTID_SKIP_UNDER_SANITIZERS(
      "SixtyDecibelsConvergesFromThePapersStartWithinThreeStandardErrors runs the same beam fit; "
      "ModeRelocation tests run the relocation");
  const std::vector<ModalParameters> truth = true_modes();
  int mode_4_found = 0;
  for (std::uint64_t seed : {7U, 8U, 9U, 10U, 11U, 12U}) {
    const SampledData data = beam_data(30.0, seed);
    const ModeRelocationResult r = relocate(data);
    const std::string where = "seed " + std::to_string(seed) + ": " + r.message;
    ASSERT_TRUE(r.estimate.converged()) << where;
    ASSERT_EQ(r.estimate.modes.size(), 4U) << where;
    EXPECT_GE(r.relocations, 1) << where;
    for (size_t i = 0; i < 3; ++i) {
      const auto [w, z] = errors_in_standard_errors(r.estimate, truth[i]);
      EXPECT_LT(w, 3.0) << where << "; mode " << i + 1;
      EXPECT_LT(z, 3.0) << where << "; mode " << i + 1;
    }
    const auto [w4, z4] = errors_in_standard_errors(r.estimate, truth[3]);
    if (w4 < 3.0 && z4 < 3.0) {
      ++mode_4_found;
    } else {
      EXPECT_LT(r.projected_mean_squared_error, true_poles_projected_mse(data)) << where;
    }
  }
  EXPECT_GE(mode_4_found, 5);
}

// The delay and the relocation together: scan the delay with the plain iteration (the
// stuck weak modes barely change the output error, the delay changes it a lot), then
// relocate at the chosen delay, starting from the scan's estimate.
TEST(BeamSection7, DelayScanThenRelocationFromThePapersStart) {
  CTID_SKIP_UNDER_SANITIZERS(
      "NoiseFreeConvergesFromThePapersStartWithTheDelayEstimated and "
      "Identify.DelayScanKeepsTheBestDelayAndItsTable run the delay search");
  const SampledData data = beam_data(40.0, 13);
  RefinedIvOptions options = options_from(testing::beam_start_parameters());
  options.compute_covariance = false;
  const InputDelayScanResult scan = additive_srivc_delay_scan(data, kOrders, 3, 5, options);
  ASSERT_EQ(scan.best.input_delay_samples, kDelay);
  RefinedIvOptions from_scan = options_from(testing::beam_start_parameters());
  from_scan.input_delay_samples = scan.best.input_delay_samples;
  from_scan.initial_model = scan.best.model;
  const ModeRelocationResult r = additive_srivc_relocated(data, kOrders, from_scan);
  ASSERT_TRUE(r.estimate.converged()) << r.message;
  ASSERT_EQ(r.estimate.modes.size(), 4U) << r.message;
  for (const ModalParameters& t : true_modes()) {
    const auto [w, z] = errors_in_standard_errors(r.estimate, t);
    EXPECT_LT(w, 3.0) << r.message << "; mode at " << t.natural_frequency << " rad/s";
    EXPECT_LT(z, 3.0) << r.message << "; mode at " << t.natural_frequency << " rad/s";
  }
}

// The paper's own excitation, without dither, must be accepted: 1000 lines in the band make
// it persistently exciting of any order the estimator needs, although its unit-spacing lag
// windows are numerically singular (it is 4x oversampled).
TEST(BeamSection7, PaperMultisineWithoutDitherIsAccepted) {
  RefinedIvOptions options = options_from(testing::beam_start_parameters());
  options.input_delay_samples = kDelay;
  options.compute_covariance = false;
  const EstimationResult r = additive_srivc(beam_data(INFINITY, 0, 0.0), kOrders, options);
  EXPECT_TRUE(r.converged()) << r.message;
}

}  // namespace
}  // namespace ctid::beam_section7_test
