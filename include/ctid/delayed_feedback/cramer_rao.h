// The Cramér-Rao bound of the loop parameters ρ (loop_parameters.h) for an experiment with
// white Gaussian output noise: tells whether F and H are separable from it (beyond De Iuliis,
// Germani, Manes 2017, whose conclusion asks for the noisy case).
#pragma once

#include <string>
#include <string_view>
#include <tuple>

#include <Eigen/Core>

#include "ctid/core/fields.h"
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

  static constexpr std::string_view type_name = "SeparabilityReport";
  static constexpr auto fields() {
    using R = SeparabilityReport;
    return std::tuple{
        field("parameters", &R::parameters, "rho = [a_F | b_F | a_H | b_H]."),
        field("covariance", &R::covariance, "sigma^2 (J'J)^-1."),
        field("standard_deviations", &R::standard_deviations, "Square roots of its diagonal."),
        field("relative_standard_deviations", &R::relative_standard_deviations,
              "sd / max(|rho_i|, 1e-3)."),
        field("noise_variance", &R::noise_variance, "sigma^2."),
        field("condition_number", &R::condition_number, "Of the column-scaled sensitivity matrix."),
        field("separable", &R::separable, "Every relative sd below the threshold."),
        field("message", &R::message, "The verdict in one sentence."),
    };
  }
};

/// Cramér-Rao bound of ρ for the loop driven by `input` (held by `hold`) with white output
/// noise of standard deviation noise_sd. Sensitivities by central differences.
SeparabilityReport cramer_rao_bound(const DelayedFeedbackLoop& loop, const Eigen::VectorXd& input,
                                    double sample_time, Hold hold, double noise_sd,
                                    double relative_threshold = 0.1, int substeps = 4);

}  // namespace ctid
