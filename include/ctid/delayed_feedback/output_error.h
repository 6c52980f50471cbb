// Output-error refinement of F and H in their 2(n+m) true unknowns (beyond De Iuliis, Germani,
// Manes 2017): removes the equation-error noise bias of step 1. White Gaussian output noise
// is assumed for the covariance at the estimate.
#pragma once

#include <string>
#include <string_view>
#include <tuple>

#include "ctid/core/hold.h"
#include "ctid/core/sampled_data.h"
#include "ctid/delayed_feedback/cramer_rao.h"
#include "ctid/estimation/termination.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid {

struct OutputErrorOptions {
  /// How the measured input is continued: first_order_hold, as the step-1 regressors (linear
  /// between samples), the CLI and Python assume.
  Hold hold = Hold::first_order_hold;
  int substeps = 4;  ///< RK4 steps per sample in the simulations
  int max_iterations = 200;
  /// Also estimate Δ (>= 0) jointly with ρ; the covariance still covers ρ only.
  bool estimate_delay = false;
  double relative_threshold = 0.1;  ///< for the separability verdict

  static constexpr std::string_view type_name = "OutputErrorOptions";
  static constexpr auto fields() {
    using O = OutputErrorOptions;
    return std::tuple{
        field("hold", &O::hold,
              "How the measured input is continued between samples in the simulations; in "
              "identify_delayed_feedback also the hold of the IV instruments and of every "
              "candidate's output error."),
        field("substeps", &O::substeps, AtLeast{1},
              "RK4 steps per sample in the simulations (in identify_delayed_feedback: every "
              "stage's)."),
        field("max_iterations", &O::max_iterations, AtLeast{1}, "Levenberg-Marquardt iterations."),
        field("estimate_delay", &O::estimate_delay,
              "Also estimate the delay (>= 0) jointly with rho."),
        field("relative_threshold", &O::relative_threshold, GreaterThan{0.0},
              "Relative sd below which a parameter counts as determined (separability)."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// converged, iteration_limit, or non_finite when the start itself cannot be simulated.
struct OutputErrorResult : Outcome {
  DelayedFeedbackLoop loop{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                           TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  double residual_rms = 0.0;
  SeparabilityReport quality;  ///< covariance at the estimate, σ² from the residuals

  static constexpr std::string_view type_name = "OutputErrorResult";
  static constexpr auto fields() {
    using R = OutputErrorResult;
    return join_fields(Outcome::fields(),
                       std::tuple{
                           field("loop", &R::loop, "DelayedFeedbackLoop (F, H, delay)."),
                           field("residual_rms", &R::residual_rms, "rms of y - y_hat."),
                           field("quality", &R::quality,
                                 "SeparabilityReport at the estimate (sigma^2 from residuals)."),
                       });
  }
};

/// Minimises sum_k (y_k - ŷ_k(ρ))² by Levenberg-Marquardt from `start` (Δ kept fixed unless
/// options.estimate_delay).
/// An unstable or overflowing iterate is rejected as a failed step, never thrown.
OutputErrorResult refine_output_error(const SampledData& data, const DelayedFeedbackLoop& start,
                                      const OutputErrorOptions& options = {});

}  // namespace ctid
