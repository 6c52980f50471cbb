// Bias-corrected instrumental variables in the 2(n+m) true unknowns of F and H (beyond De
// Iuliis, Germani, Manes 2017, after Young's SRIVC).
#pragma once

#include <string>
#include <vector>

#include "ctid/core/hold.h"
#include "ctid/core/sampled_data.h"
#include "ctid/delayed_feedback/regressors.h"
#include "ctid/estimation/termination.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid {

/// Iterated instrumental variables in the same 2(n+m) unknowns (beyond the paper, after
/// Young's SRIVC): the noisy output inside the regressors makes the equation error biased,
/// so each iteration rebuilds the regressors from the current loop's noise-free simulated
/// output as instruments and minimises the projection of the equation error on their span
/// (two-stage least squares, Levenberg-Marquardt from the current ρ). Δ stays fixed. The
/// iterate with the smallest output-error rms is returned: it is a start for the output error.
struct StructuredIvOptions {
  int iterations = 4;
  int max_iterations = 100;            ///< Levenberg-Marquardt steps per iteration
  double tolerance = 1e-8;             ///< stop when |Δρ| / max(1, |ρ|) falls below
  Hold hold = Hold::first_order_hold;  ///< for the simulated instruments
  /// Subtract the estimator's error on the current model's own simulated output (indirect
  /// inference): ρ ← ρ + IV(data) − IV(simulated), so systematic regression errors cancel.
  bool bias_correction = true;
  int substeps = 4;
  void validate() const;
};

/// converged (the tolerance was met), iteration_limit, non_finite (the start or an iterate is
/// unstable or overflows; the best iterate so far is kept) or no_solution (no stable start).
struct StructuredIvResult : Outcome {
  DelayedFeedbackLoop loop{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                           TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  double output_rms = 0.0;                 ///< of the returned loop on the data
  std::vector<double> output_rms_history;  ///< start, then each iterate (inf: unstable)
};

/// Throws InvalidArgument for an invalid start or data too short for the regression.
StructuredIvResult estimate_structured_step1_iv(const SampledData& data,
                                                const DelayedFeedbackLoop& start,
                                                const FeedbackRegressorOptions& regressors,
                                                const StructuredIvOptions& options = {});

}  // namespace ctid
