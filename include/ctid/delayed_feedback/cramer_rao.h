// The Cramér-Rao bound of the loop parameters ρ (loop_parameters.h) for an experiment with
// white Gaussian output noise: tells whether F and H are separable from it (beyond De Iuliis,
// Germani, Manes 2017, whose conclusion asks for the noisy case).
#pragma once

#include <string>

#include <Eigen/Core>

#include "ctid/core/hold.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid {

/// How well the data determine ρ: covariance σ² (JᵀJ)^{-1}, J = ∂ŷ/∂ρ.
struct SeparabilityReport {
  Eigen::VectorXd parameters;
  Eigen::MatrixXd covariance;
  Eigen::VectorXd standard_deviations;
  Eigen::VectorXd relative_standard_deviations;  ///< sd / max(|ρ_i|, 1e-3)
  double noise_variance = 0.0;
  double condition_number = 0.0;  ///< of the column-scaled sensitivity matrix
  bool separable = false;         ///< every relative sd below the threshold
  std::string message;
};

/// Cramér-Rao bound of ρ for the loop driven by `input` (held by `hold`) with white output
/// noise of standard deviation noise_sd. Sensitivities by central differences.
SeparabilityReport cramer_rao_bound(const DelayedFeedbackLoop& loop, const Eigen::VectorXd& input,
                                    double sample_time, Hold hold, double noise_sd,
                                    double relative_threshold = 0.1, int substeps = 4);

}  // namespace ctid
