// Output-error refinement of F and H in their 2(n+m) true unknowns (beyond De Iuliis, Germani,
// Manes 2017): removes the equation-error noise bias of step 1. White Gaussian output noise
// is assumed for the covariance at the estimate.
#pragma once

#include <string>

#include "ctid/core/hold.h"
#include "ctid/core/sampled_data.h"
#include "ctid/delayed_feedback/cramer_rao.h"
#include "ctid/estimation/termination.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid {

struct OutputErrorOptions {
  Hold hold = Hold::zero_order_hold;  ///< how the measured input is continued
  int substeps = 4;                   ///< RK4 steps per sample in the simulations
  int max_iterations = 200;
  /// Also estimate Δ (>= 0) jointly with ρ; the covariance still covers ρ only.
  bool estimate_delay = false;
  double relative_threshold = 0.1;  ///< for the separability verdict
  void validate() const;
};

/// converged, iteration_limit, or non_finite when the start itself cannot be simulated.
struct OutputErrorResult : Outcome {
  DelayedFeedbackLoop loop{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                           TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  double residual_rms = 0.0;
  SeparabilityReport quality;  ///< covariance at the estimate, σ² from the residuals
};

/// Minimises sum_k (y_k - ŷ_k(ρ))² by Levenberg-Marquardt from `start` (Δ kept fixed unless
/// options.estimate_delay).
/// An unstable or overflowing iterate is rejected as a failed step, never thrown.
OutputErrorResult refine_output_error(const SampledData& data, const DelayedFeedbackLoop& start,
                                      const OutputErrorOptions& options = {});

}  // namespace ctid
