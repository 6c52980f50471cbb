// Validation of separated forward/feedback models as in De Iuliis, Germani, Manes 2017,
// Section 4: the responses of the true and estimated transfer functions to the same
// unit-variance white noise held by a ZOH at t_c (0.005 s) over T (5 s), compared by
// MSE = (1/N) sum_{k=1}^{N} (ŷ(k t_c) - y(k t_c))², plus the exact expectation of that MSE
// over noise realisations, from the impulse response of the ZOH-discretised error system.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "ctid/core/transfer_function.h"

namespace ctid {

struct WhiteNoiseValidationOptions {
  double sample_time = 0.005;  ///< t_c [s]
  double duration = 5.0;       ///< T [s]; N = round(T / t_c)
  std::uint64_t seed = 1;
  void validate() const;
};

struct ResponseComparison {
  double mse = 0.0;           ///< this realisation; +inf if a response overflowed
  double expected_mse = 0.0;  ///< E[MSE] over white-noise realisations; +inf on overflow
  bool estimate_stable = true;
  Eigen::VectorXd truth;     ///< y(k t_c), k = 1..N
  Eigen::VectorXd estimate;  ///< ŷ(k t_c)
};

/// Both models must be strictly proper or proper, without delay.
ResponseComparison compare_white_noise_response(const TransferFunction& truth,
                                                const TransferFunction& estimate,
                                                const WhiteNoiseValidationOptions& options = {});

/// (1/N) sum_{k=1}^{N} sum_{j=0}^{k} g_j², g the impulse response of the ZOH-discretised
/// estimate - truth at t_c (g_0 its direct term).
double expected_white_noise_mse(const TransferFunction& truth, const TransferFunction& estimate,
                                double sample_time, int samples);

}  // namespace ctid
