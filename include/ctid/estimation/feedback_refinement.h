// Beyond De Iuliis, Germani, Manes 2017 (its conclusion asks for the noisy case and for
// estimating Δ): an output-error refinement of F and H in their 2(n+m) true unknowns, which
// removes the equation-error noise bias; the Cramér-Rao bound of an experiment, telling
// whether F and H are separable from it; and a scan of Δ (fractional delays included) by the
// output error of the step-1 model. Parameters ρ = [a_F | b_F | a_H | b_H], ascending
// coefficients below the monic leading ones. White Gaussian output noise is assumed.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/sampled_data.h"
#include "ctid/estimation/feedback_least_squares.h"
#include "ctid/estimation/feedback_regressors.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid {

/// ρ of a loop (F, H normalised to monic denominators) and back.
Eigen::VectorXd loop_parameters(const DelayedFeedbackLoop& loop);
DelayedFeedbackLoop loop_from_parameters(const Eigen::VectorXd& rho, int forward_order,
                                         int feedback_order, double delay);

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
                                    double sample_time, InputHold hold, double noise_sd,
                                    double relative_threshold = 0.1, int substeps = 4);

/// Structured step 1: the equation error |target - C θ(ρ)|² (nuisance columns projected out)
/// minimised over the 2(n+m) true unknowns, where θ(ρ) stacks β = D_F D_H, γ = N_F N_H,
/// α = N_F D_H. Starts: alternating least squares (the residual is affine in F's parameters
/// for fixed H and vice versa) from D_H = (s + w)^m for each w in start_frequencies, then
/// Levenberg-Marquardt; the smallest cost is kept. The trade between β and γ that makes the
/// unstructured θ ill-determined is not available inside this manifold.
struct StructuredStep1Options {
  std::vector<double> start_frequencies{0.3, 1.0, 3.0};
  int alternating_iterations = 100;
  int max_iterations = 100;
  void validate() const;
};

struct StructuredStep1Result {
  DelayedFeedbackLoop loop{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                           TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  double cost = 0.0;  ///< residual sum of squares
  int starts = 0;
};

StructuredStep1Result estimate_structured_step1(const FeedbackRegression& regression,
                                                const StructuredStep1Options& options = {});

struct OutputErrorOptions {
  InputHold hold = InputHold::kZeroOrder;  ///< how the measured input is continued
  int substeps = 4;                        ///< RK4 steps per sample in the simulations
  int max_iterations = 50;
  double relative_threshold = 0.1;  ///< for the separability verdict
  void validate() const;
};

struct OutputErrorResult {
  DelayedFeedbackLoop loop{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                           TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  double residual_rms = 0.0;
  int iterations = 0;
  bool converged = false;
  std::string message;
  SeparabilityReport quality;  ///< covariance at the estimate, σ² from the residuals
};

/// Minimises sum_k (y_k - ŷ_k(ρ))² by Levenberg-Marquardt from `start` (Δ kept fixed).
/// An unstable or overflowing iterate is rejected as a failed step, never thrown.
OutputErrorResult refine_output_error(const SampledData& data, const DelayedFeedbackLoop& start,
                                      const OutputErrorOptions& options = {});

struct DelayScanOptions {
  double min_delay = 0.0;
  double max_delay = 1.0;
  int points = 41;     ///< grid (finer than δ is allowed: fractional delays)
  bool refine = true;  ///< golden-section search around the best grid point
  FeedbackRegressorOptions regressors;
  BatchLeastSquaresOptions least_squares;
  InputHold hold = InputHold::kZeroOrder;
  int substeps = 4;
  void validate() const;
};

struct DelayScanResult {
  Eigen::VectorXd delays;
  Eigen::VectorXd criterion;  ///< mean squared output error of the step-1 model (inf: unstable)
  double delay = 0.0;         ///< the minimiser
  double best_criterion = 0.0;
};

/// For each Δ: step 1 (batch) and the output error of W = α̂/(β̂ + γ̂ e^{-Δs}) on the data.
DelayScanResult scan_delay(const SampledData& data, int forward_order, int feedback_order,
                           const DelayScanOptions& options = {});

}  // namespace ctid
