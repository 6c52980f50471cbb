// Measurement noise for simulated experiments: coloured noise v = H(q) e from seeded Gaussian
// white e (González et al. Section 6.1 uses H(q) = (q + 0.5)/(q - 0.85), var e = 0.02), run in
// before the record so that v is stationary, and scaling to a signal-to-noise ratio defined as
//   SNR = 10 log10( var(signal) / var(noise) )  [dB],
// with sample variances about the sample means.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "ctid/core/discrete_transfer_function.h"

namespace ctid {

/// Samples the filter needs before its output is stationary to `tolerance`: the slowest pole
/// radius rho satisfies rho^run_in <= tolerance (at least the filter order). Throws
/// InvalidArgument for an unstable or marginally stable filter.
int stationary_run_in(const DiscreteTransferFunction& filter, double tolerance = 1e-12);

/// Variance of the stationary output of `filter` driven by unit-variance white noise
/// (sum of the squared impulse response, from the discrete Lyapunov equation).
double stationary_variance_gain(const DiscreteTransferFunction& filter);

/// v = H(q) e over `length` samples, e zero-mean Gaussian white with the given variance.
/// e is white_noise(run_in + length, sqrt(variance), seed) and the first run_in outputs are
/// dropped; run_in < 0 means stationary_run_in(filter).
Eigen::VectorXd colored_noise(const DiscreteTransferFunction& filter, int length, double variance,
                              std::uint64_t seed, int run_in = -1);

/// 10 log10(var(signal) / var(noise)) in dB; equal lengths >= 2, non-constant noise.
double snr_db(const Eigen::VectorXd& signal, const Eigen::VectorXd& noise);

/// The noise times the positive factor that makes snr_db(signal, result) equal `snr` dB.
Eigen::VectorXd scale_noise_to_snr(const Eigen::VectorXd& signal, const Eigen::VectorXd& noise,
                                   double snr);

}  // namespace ctid
