// A scan of the feedback delay Δ (fractional delays included) by a criterion of the step-1
// model (beyond De Iuliis, Germani, Manes 2017, whose conclusion asks for estimating Δ).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "ctid/core/hold.h"
#include "ctid/core/sampled_data.h"
#include "ctid/delayed_feedback/least_squares.h"
#include "ctid/delayed_feedback/regressors.h"
#include "ctid/delayed_feedback/structured_iv.h"
#include "ctid/estimation/termination.h"

namespace ctid {

enum class DelayCriterion {
  kOutputError,    ///< mean squared output error of the step-1 model (inf when unstable)
  kEquationError,  ///< mean squared residual of the step-1 regression
  /// mean squared output error of the structured step-1 loop (2(n+m) unknowns)
  kStructuredOutputError,
  /// ... after refined_iterations output-error steps from it (slower, much sharper)
  kRefinedOutputError,
};

struct FeedbackDelayScanOptions {
  DelayCriterion criterion = DelayCriterion::kOutputError;
  int refined_iterations = 10;  ///< for kRefinedOutputError
  /// kRefinedOutputError also refines from the bias-corrected IV start at each of these filter
  /// poles and keeps the smallest cost (empty: the structured start only).
  std::vector<double> iv_filter_poles;
  StructuredIvOptions iv;
  double min_delay = 0.0;
  double max_delay = 1.0;
  int points = 41;     ///< grid (finer than δ is allowed: fractional delays)
  bool refine = true;  ///< golden-section search around the best grid point
  FeedbackRegressorOptions regressors;
  BatchLeastSquaresOptions least_squares;
  Hold hold = Hold::zero_order_hold;
  int substeps = 4;
  void validate() const;
};

/// converged when some delay has a finite criterion (iterations: criterion evaluations), else
/// no_solution (every delay unstable, degenerate or beyond the record).
struct FeedbackDelayScanResult : Outcome {
  Eigen::VectorXd delays;
  Eigen::VectorXd criterion;  ///< per DelayCriterion (inf: unstable or degenerate)
  double delay = 0.0;         ///< the minimiser
  double best_criterion = 0.0;
};

/// For each Δ: step 1 (batch) and the output error of W = α̂/(β̂ + γ̂ e^{-Δs}) on the data.
FeedbackDelayScanResult scan_feedback_delay(const SampledData& data, int forward_order,
                                            int feedback_order,
                                            const FeedbackDelayScanOptions& options = {});

}  // namespace ctid
