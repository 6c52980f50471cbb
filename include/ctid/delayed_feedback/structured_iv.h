// Bias-corrected instrumental variables in the 2(n+m) true unknowns of F and H (beyond De
// Iuliis, Germani, Manes 2017, after Young's SRIVC).
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
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
  int max_iterations = 100;  ///< Levenberg-Marquardt steps per iteration
  double tolerance = 1e-8;   ///< stop when |Δρ| / max(1, |ρ|) falls below
  /// How the measured input is continued in the simulated instruments. Empty: the caller's
  /// (identify_delayed_feedback: output_error.hold; scan_feedback_delay: its hold), and
  /// first_order_hold when estimate_structured_step1_iv is called directly. A value that
  /// contradicts the caller's is rejected by the caller's validate().
  std::optional<Hold> hold;
  /// Subtract the estimator's error on the current model's own simulated output (indirect
  /// inference): ρ ← ρ + IV(data) − IV(simulated), so systematic regression errors cancel.
  bool bias_correction = true;
  /// RK4 steps per sample of those simulations; empty: the caller's, 4 when called directly.
  std::optional<int> substeps;

  static constexpr std::string_view type_name = "StructuredIvOptions";
  static constexpr auto fields() {
    using O = StructuredIvOptions;
    return std::tuple{
        field("iterations", &O::iterations, AtLeast{1}, "IV iterations."),
        field("max_iterations", &O::max_iterations, AtLeast{1},
              "Levenberg-Marquardt steps per iteration."),
        field("tolerance", &O::tolerance,
              Between{0.0, std::numeric_limits<double>::infinity(), true, false},
              "Stop when |d rho| / max(1, |rho|) falls below."),
        field("hold", &O::hold,
              "Input hold of the simulated instruments; None: the caller's (first_order_hold "
              "when called directly). Must agree with the caller's."),
        field("bias_correction", &O::bias_correction,
              "Subtract the estimator's error on the model's own simulated output."),
        field("substeps", &O::substeps, AtLeast{1},
              "RK4 steps per sample; None: the caller's (4 when called directly). Must agree "
              "with the caller's."),
    };
  }
  void validate() const { validate_fields(*this); }
  /// Rejects a hold or substeps that contradict the caller's (`path` names the IV options).
  void check_agrees(const std::string& path, Hold caller_hold, int caller_substeps) const;
};

/// converged (the tolerance was met), iteration_limit, non_finite (the start or an iterate is
/// unstable or overflows; the best iterate so far is kept) or no_solution (no stable start).
struct StructuredIvResult : Outcome {
  DelayedFeedbackLoop loop{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                           TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  double output_rms = 0.0;                 ///< of the returned loop on the data
  std::vector<double> output_rms_history;  ///< start, then each iterate (inf: unstable)

  static constexpr std::string_view type_name = "StructuredIvResult";
  static constexpr auto fields() {
    using R = StructuredIvResult;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("loop", &R::loop, "The iterate with the smallest output-error rms."),
            field("output_rms", &R::output_rms, "Its output-error rms on the data."),
            field("output_rms_history", &R::output_rms_history,
                  "Start, then each iterate (inf: unstable)."),
        });
  }
};

/// Throws InvalidArgument for an invalid start or data too short for the regression.
StructuredIvResult estimate_structured_step1_iv(const SampledData& data,
                                                const DelayedFeedbackLoop& start,
                                                const FeedbackRegressorOptions& regressors,
                                                const StructuredIvOptions& options = {});

}  // namespace ctid
