// Mode relocation, a global restart for the additive open-loop iteration (29) of González et
// al.: when it stops at a stationary point that leaves a lightly damped mode unexplained
// (Section 7: the beam's weak modes 3-4 from theta_i^1), a second-order submodel is moved to
// the residual's largest spectral peak and the iteration re-run; the move is kept only if the
// output error (of the poles, by default) falls. Ours, beyond the paper.
#pragma once

#include <array>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

/// How a candidate estimate is compared with the current one.
enum class RelocationCriterion {
  /// Mean squared output error with every numerator re-fitted by least squares for the
  /// estimate's denominators (the output error of its poles), or that of the start the
  /// iteration was run from if smaller and the moved mode stayed within the search window.
  /// Default: for a weak, very lightly damped mode the refined IV fixed point can fit worse
  /// than leaving the mode out (docs/algorithms/section7-beam.md), so the fixed point's own
  /// output error misranks the poles.
  projected_output_error,
  /// The estimate's own mean squared output error (EstimationResult::mean_squared_error):
  /// the final estimate's output error never exceeds the plain one.
  output_error,
};

inline constexpr std::array<Enumerator<RelocationCriterion>, 2> relocation_criterion_enumerators{{
    {RelocationCriterion::projected_output_error, "projected_output_error",
     "Output error of the estimate's poles (numerators re-fitted)."},
    {RelocationCriterion::output_error, "output_error", "The estimate's own output error."},
}};
constexpr std::span<const Enumerator<RelocationCriterion>> enumerators(RelocationCriterion) {
  return relocation_criterion_enumerators;
}

struct ModeRelocationOptions {
  /// Largest number of moves kept (0: the plain estimate). >= 0.
  int max_relocations = 4;
  /// Residual peaks examined per round, the highest above the local floor first. >= 1.
  int peaks_per_round = 6;
  /// A residual periodogram peak counts if it is at least this many times its local floor
  /// (the median periodogram over +-floor_half_width lines). > 1.
  double min_peak_to_floor = 8.0;
  /// Peaks are looked for only on lines where the input's local median periodogram is at
  /// least this fraction of its largest value (the excited band): outside it a mode can only
  /// fit the start-up transient, i.e. noise. In [0, 1].
  double min_input_level = 1e-2;
  /// Half-width of the window of the local floor, in DFT lines of the record. >= 1.
  int floor_half_width = 64;
  /// The residual's DFT is taken over this multiple of the record length (zero padding),
  /// so that peaks between lines are located. >= 1.
  int zero_padding = 4;
  /// Each peak is refined by an output-error least-squares search over
  /// +-search_half_width lines around it (peaks this close to a mode the model already has
  /// are skipped) ... > 0,
  double search_half_width = 1.0;
  /// ... on this many equally spaced frequencies (>= 3) ...
  int search_points = 41;
  /// ... and these damping ratios (each in (0, 1), at least one).
  std::vector<double> damping_ratios = {1e-4, 1e-3, 1e-2};
  /// Candidate starts (peak, submodel moved) re-run through the iteration per round, those
  /// with the smallest least-squares output error first; the first one that is kept ends the
  /// round. >= 1.
  int trials_per_round = 3;
  /// How candidates are compared.
  RelocationCriterion criterion = RelocationCriterion::projected_output_error;
  /// A move is kept if the iteration converges and the criterion falls below
  /// (1 - min_relative_decrease) times the current value. In [0, 1).
  double min_relative_decrease = 1e-6;

  static constexpr std::string_view type_name = "ModeRelocationOptions";
  static constexpr auto fields() {
    using O = ModeRelocationOptions;
    return std::tuple{
        field("max_relocations", &O::max_relocations, AtLeast{0},
              "Largest number of moves kept (0: the plain estimate)."),
        field("peaks_per_round", &O::peaks_per_round, AtLeast{1},
              "Residual peaks examined per round."),
        field("min_peak_to_floor", &O::min_peak_to_floor, Finite{GreaterThan{1}},
              "A peak counts at this many times its local floor."),
        field("min_input_level", &O::min_input_level, Between{0, 1, true, true},
              "Excited band: input level relative to its largest."),
        field("floor_half_width", &O::floor_half_width, AtLeast{1},
              "Half-width of the local floor window [DFT lines]."),
        field("zero_padding", &O::zero_padding, AtLeast{1}, "DFT length / record length."),
        field("search_half_width", &O::search_half_width, Finite{GreaterThan{0}},
              "Half-width of the search around a peak [DFT lines]."),
        field("search_points", &O::search_points, AtLeast{3},
              "Frequencies searched around a peak."),
        field("damping_ratios", &O::damping_ratios, Each{Between{0, 1}},
              "Damping ratios tried (at least one)."),
        field("trials_per_round", &O::trials_per_round, AtLeast{1},
              "Candidate starts re-run per round."),
        field("criterion", &O::criterion, "How candidates are compared."),
        field("min_relative_decrease", &O::min_relative_decrease, Between{0, 1, true, false},
              "Relative decrease of the criterion that keeps a move."),
    };
  }
  /// damping_ratios is not empty.
  void check_relations(const std::string& path) const;
  /// Throws InvalidArgument naming the first bad field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// One candidate start that was re-run through the iteration.
struct RelocationTrial {
  int round = 0;                 ///< 0 for the first round
  int submodel = 0;              ///< index of the submodel that was moved
  double moved_from = 0.0;       ///< its natural frequency before the move [rad/s]
  double peak_frequency = 0.0;   ///< the residual peak [rad/s]
  double peak_to_floor = 0.0;    ///< its periodogram over the local floor
  double start_frequency = 0.0;  ///< natural frequency of the start after the search [rad/s]
  double start_damping = 0.0;    ///< damping ratio of the start
  double start_mean_squared_error = 0.0;      ///< least-squares output error of the start
  double mean_squared_error = 0.0;            ///< after the iteration
  double projected_mean_squared_error = 0.0;  ///< after the iteration, numerators re-fitted
  double score = 0.0;  ///< the criterion's value for this trial (see RelocationCriterion)
  Termination termination = Termination::not_run;
  bool accepted = false;

  static constexpr std::string_view type_name = "RelocationTrial";
  static constexpr auto fields() {
    using S = RelocationTrial;
    return std::tuple{
        field("round", &S::round, "Round (0 for the first)."),
        field("submodel", &S::submodel, "Index of the submodel that was moved."),
        field("moved_from", &S::moved_from, "Its natural frequency before the move [rad/s]."),
        field("peak_frequency", &S::peak_frequency, "The residual peak [rad/s]."),
        field("peak_to_floor", &S::peak_to_floor, "Its periodogram over the local floor."),
        field("start_frequency", &S::start_frequency,
              "Natural frequency of the start after the search [rad/s]."),
        field("start_damping", &S::start_damping, "Damping ratio of the start."),
        field("start_mean_squared_error", &S::start_mean_squared_error,
              "Least-squares output error of the start."),
        field("mean_squared_error", &S::mean_squared_error, "Output error after the iteration."),
        field("projected_mean_squared_error", &S::projected_mean_squared_error,
              "The same with the numerators re-fitted."),
        field("score", &S::score, "The criterion's value for this trial."),
        field("termination", &S::termination, "How the iteration from this start stopped."),
        field("accepted", &S::accepted, "The move was kept."),
    };
  }
};

struct ModeRelocationResult {
  explicit ModeRelocationResult(EstimationResult result) : estimate(std::move(result)) {}

  /// The final estimate (with covariance if RefinedIvOptions::compute_covariance).
  EstimationResult estimate;
  double initial_mean_squared_error = 0.0;            ///< of the plain estimate, before any move
  double initial_projected_mean_squared_error = 0.0;  ///< the same, numerators re-fitted
  double projected_mean_squared_error = 0.0;          ///< of the final estimate
  double initial_score = 0.0;           ///< the criterion's value for the plain estimate
  double score = 0.0;                   ///< ... and for the kept one (never larger)
  int rounds = 0;                       ///< rounds that looked for peaks
  int relocations = 0;                  ///< moves kept
  std::vector<RelocationTrial> trials;  ///< every re-run, in order
  std::string message;                  ///< one sentence: what was tried and kept

  static constexpr std::string_view type_name = "ModeRelocationResult";
  static constexpr auto fields() {
    using S = ModeRelocationResult;
    return std::tuple{
        field("estimate", &S::estimate, "The final EstimationResult."),
        field("initial_mean_squared_error", &S::initial_mean_squared_error,
              "Output error of the plain estimate, before any move."),
        field("initial_projected_mean_squared_error", &S::initial_projected_mean_squared_error,
              "The same with the numerators re-fitted."),
        field("projected_mean_squared_error", &S::projected_mean_squared_error,
              "Of the final estimate, numerators re-fitted."),
        field("initial_score", &S::initial_score, "The criterion's value for the plain estimate."),
        field("score", &S::score, "The criterion's value for the kept one (never larger)."),
        field("rounds", &S::rounds, "Rounds that looked for peaks."),
        field("relocations", &S::relocations, "Moves kept."),
        field("trials", &S::trials, "Every re-run, in order."),
        field("message", &S::message, "One sentence: what was tried and kept."),
    };
  }
};

/// additive_srivc (open loop, options.input_delay_samples fixed), then up to max_relocations rounds
/// of: peaks of the residual (numerators re-fitted) on the excited band; for each, the mode
/// (frequency, damping) that explains most of it; candidate starts with one movable submodel
/// (second order, no integrators) replaced by that mode and every numerator re-fitted; the
/// iteration from the best candidates; the first that converges (or any, while the current
/// estimate has not converged) and is better by ModeRelocationOptions::criterion is kept.
/// Deterministic. Throws InvalidArgument for bad options or data (as additive_srivc does).
///
/// With a delay scan: run additive_srivc_delay_scan first, then this with
/// options.input_delay_samples = scan.best.input_delay_samples and options.initial_model =
/// scan.best.model (the plain run then stops at once); or pass a lambda calling this to
/// scan_input_delay. `progress`, if given, is called after each trial with the trials run and the
/// most there can be (max_relocations x trials_per_round; the relocation usually stops sooner).
ModeRelocationResult additive_srivc_relocated(const SampledData& data,
                                              const std::vector<SubmodelOrder>& orders,
                                              const RefinedIvOptions& options = {},
                                              const ModeRelocationOptions& relocation = {},
                                              const std::function<void(int, int)>& progress = {});

}  // namespace ctid
