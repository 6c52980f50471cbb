// A scan of the feedback delay Δ (fractional delays included) by a criterion of the step-1
// model (beyond De Iuliis, Germani, Manes 2017, whose conclusion asks for estimating Δ).
#pragma once

#include <array>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
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
  output_error,    ///< mean squared output error of the step-1 model (inf when unstable)
  equation_error,  ///< mean squared residual of the step-1 regression
  /// mean squared output error of the structured step-1 loop (2(n+m) unknowns)
  structured_output_error,
  /// ... after refined_iterations output-error steps from it (slower, much sharper)
  refined_output_error,
};
inline constexpr std::array<Enumerator<DelayCriterion>, 4> delay_criterion_enumerators{{
    {DelayCriterion::output_error, "output_error",
     "Mean squared output error of the step-1 model."},
    {DelayCriterion::equation_error, "equation_error",
     "Mean squared residual of the step-1 regression."},
    {DelayCriterion::structured_output_error, "structured_output_error",
     "Mean squared output error of the structured step-1 loop."},
    {DelayCriterion::refined_output_error, "refined_output_error",
     "The same after refined_iterations output-error steps."},
}};
constexpr std::span<const Enumerator<DelayCriterion>> enumerators(DelayCriterion) {
  return delay_criterion_enumerators;
}

struct FeedbackDelayScanOptions {
  DelayCriterion criterion = DelayCriterion::output_error;
  int refined_iterations = 10;  ///< for refined_output_error
  /// refined_output_error also refines from the bias-corrected IV start at each of these filter
  /// poles and keeps the smallest cost (empty: the structured start only).
  std::vector<double> iv_filter_poles;
  StructuredIvOptions iv;
  double min_delay = 0.0;
  double max_delay = 1.0;
  int points = 41;     ///< grid (finer than δ is allowed: fractional delays)
  bool refine = true;  ///< golden-section search around the best grid point
  FeedbackRegressorOptions regressors;
  BatchLeastSquaresOptions least_squares;
  Hold hold = Hold::first_order_hold;
  int substeps = 4;

  static constexpr std::string_view type_name = "FeedbackDelayScanOptions";
  static constexpr auto fields() {
    using O = FeedbackDelayScanOptions;
    constexpr double inf = std::numeric_limits<double>::infinity();
    return std::tuple{
        field("criterion", &O::criterion, "What is scored at each delay."),
        field("refined_iterations", &O::refined_iterations, AtLeast{1},
              "Output-error steps of refined_output_error."),
        field("iv_filter_poles", &O::iv_filter_poles, Each{Between{0.0, inf}},
              "refined_output_error also refines from the IV start at each pole [rad/s]."),
        field("iv", &O::iv, "IV options; its hold and substeps must be empty or agree."),
        field("min_delay", &O::min_delay, Between{0.0, inf, true, false},
              "Smallest delay of the grid [s]."),
        field("max_delay", &O::max_delay, Between{0.0, inf},
              "Largest delay of the grid [s] (> min_delay)."),
        field("points", &O::points, Between{2.0, 10000.0, true, true},
              "Grid points, 2 to 10000 (finer than the sample time is allowed; each point is "
              "one step-1 fit)."),
        field("refine", &O::refine, "Golden-section search around the best grid point."),
        field("regressors", &O::regressors, "Step-1 regressors."),
        field("least_squares", &O::least_squares, "Step-1 batch least squares."),
        field("hold", &O::hold, "How the measured input is continued in every simulation."),
        field("substeps", &O::substeps, AtLeast{1}, "RK4 steps per sample in every simulation."),
    };
  }
  void validate() const { validate_fields(*this); }
  /// max_delay > min_delay; iv.hold and iv.substeps empty or equal to hold and substeps.
  void check_relations(const std::string& path) const;
};

/// converged when some delay has a finite criterion (iterations: criterion evaluations), else
/// no_solution (every delay unstable, degenerate or beyond the record).
struct FeedbackDelayScanResult : Outcome {
  Eigen::VectorXd delays;
  Eigen::VectorXd criterion;  ///< per DelayCriterion (inf: unstable or degenerate)
  double delay = 0.0;         ///< the minimiser
  double best_criterion = 0.0;

  static constexpr std::string_view type_name = "FeedbackDelayScanResult";
  static constexpr auto fields() {
    using R = FeedbackDelayScanResult;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("delays", &R::delays, "Delays of the grid [s]."),
            field("criterion", &R::criterion, "The criterion per delay (inf: unusable)."),
            field("delay", &R::delay, "The minimiser [s]."),
            field("best_criterion", &R::best_criterion, "The criterion there."),
        });
  }
};

/// For each Δ: step 1 (batch) and the output error of W = α̂/(β̂ + γ̂ e^{-Δs}) on the data.
/// `progress`, if given, is called after each grid point with the points done and
/// options.points.
FeedbackDelayScanResult scan_feedback_delay(const SampledData& data, int forward_order,
                                            int feedback_order,
                                            const FeedbackDelayScanOptions& options = {},
                                            const std::function<void(int, int)>& progress = {});

}  // namespace ctid
