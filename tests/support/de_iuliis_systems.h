// The systems of De Iuliis, Germani, Manes 2017, defined once for the tests, benchmarks and
// examples: the paper's Section 4 loop (F and H) and the informative record used throughout
// docs/algorithms/feedback-delay.md, a smooth multisine of `harmonics` lines of a
// `period`-second fundamental (random phases from seed 3, rms 1) sampled every 50 ms and
// continued linearly between samples.
#pragma once

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/sampled_data.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid::test_support {

inline constexpr double kFeedbackSampleTime = 0.05;

/// F = (2s² + s + 2)/(s³ + 3s² + 2s + 3), H = (s² + 5s + 1)/(s³ + 3s² + 2s + 2).
inline DelayedFeedbackLoop paper_feedback_loop(double delay = 0.5) {
  return {TransferFunction(Polynomial{2.0, 1.0, 2.0}, Polynomial{3.0, 2.0, 3.0, 1.0}),
          TransferFunction(Polynomial{1.0, 5.0, 1.0}, Polynomial{2.0, 2.0, 3.0, 1.0}), delay};
}

/// sum_j cos(2π j t / period + φ_j) / sqrt(harmonics / 2) at t = k δ, k = 0 … duration/δ.
inline Eigen::VectorXd smooth_multisine(double duration, double period, int harmonics,
                                        double delta = kFeedbackSampleTime) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * M_PI);
  std::vector<double> phases(static_cast<std::size_t>(harmonics));
  for (double& p : phases) p = phase(rng);
  Eigen::VectorXd u(std::lround(duration / delta) + 1);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    double sum = 0.0;
    for (int j = 1; j <= harmonics; ++j)
      sum += std::cos(2.0 * M_PI * j * static_cast<double>(k) * delta / period +
                      phases[static_cast<std::size_t>(j - 1)]);
    u(k) = sum / std::sqrt(harmonics / 2.0);
  }
  return u;
}

/// The loop's noise-free response to the smooth multisine (4 RK4 steps per sample).
inline SampledData feedback_record(const DelayedFeedbackLoop& loop, double duration = 30.0,
                                   double period = 15.0, int harmonics = 8,
                                   double delta = kFeedbackSampleTime) {
  const Eigen::VectorXd u = smooth_multisine(duration, period, harmonics, delta);
  return SampledData(delta, u,
                     simulate_delayed(to_delayed_state_space(loop), u, delta,
                                      Hold::first_order_hold, DelayedSimulationOptions{4}));
}

/// `clean` plus white Gaussian output noise of standard deviation sigma from mt19937_64(seed).
inline SampledData with_white_noise(const SampledData& clean, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma);
  Eigen::VectorXd y = clean.output();
  for (Eigen::Index k = 0; k < y.size(); ++k) y(k) += normal(rng);
  return SampledData(clean.sample_time(), clean.input(), y);
}

}  // namespace ctid::test_support
