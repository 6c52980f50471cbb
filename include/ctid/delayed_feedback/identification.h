// The whole delayed-feedback identification of De Iuliis, Germani, Manes 2017 and beyond it:
// step 1, the separation candidates, the output-error refinement from each, and the same with
// the delay unknown.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "ctid/core/sampled_data.h"
#include "ctid/delayed_feedback/cramer_rao.h"
#include "ctid/delayed_feedback/feedback_delay_scan.h"
#include "ctid/delayed_feedback/least_squares.h"
#include "ctid/delayed_feedback/loop_parameters.h"
#include "ctid/delayed_feedback/output_error.h"
#include "ctid/delayed_feedback/regressors.h"
#include "ctid/delayed_feedback/separation.h"
#include "ctid/delayed_feedback/structured_iv.h"
#include "ctid/delayed_feedback/structured_step1.h"
#include "ctid/estimation/termination.h"
#include "ctid/estimation/verdict.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid {

/// The whole identification: step 1 (batch or RLS) gives Ŵ = α̂/(β̂ + γ̂ e^{-Δs}); the
/// separation candidates are the approximate-GCD estimate and every refined start of min J
/// (the GCD start and each root split of β̂); the output-error refinement in the 2(n+m) true
/// unknowns runs from EACH candidate (screening_iterations steps), the smallest output-error
/// cost decides, and that candidate is refined to convergence. Candidates
/// whose simulation overflows or whose refinement fails are kept with an infinite cost.
enum class Step1Method { batch, recursive };
inline constexpr std::array<Enumerator<Step1Method>, 2> step1_method_enumerators{{
    {Step1Method::batch, "batch", "Batch least squares."},
    {Step1Method::recursive, "recursive", "Recursive least squares, eq. (13)."},
}};
constexpr std::span<const Enumerator<Step1Method>> enumerators(Step1Method) {
  return step1_method_enumerators;
}

enum class SeparationMethod { kronecker, gcd, both };
inline constexpr std::array<Enumerator<SeparationMethod>, 3> separation_method_enumerators{{
    {SeparationMethod::kronecker, "kronecker", "Every refined start of min J."},
    {SeparationMethod::gcd, "gcd", "The approximate GCD."},
    {SeparationMethod::both, "both", "Both."},
}};
constexpr std::span<const Enumerator<SeparationMethod>> enumerators(SeparationMethod) {
  return separation_method_enumerators;
}

struct FeedbackIdentificationOptions {
  FeedbackRegressorOptions regressors{RegressorFilter::linear_integral_filter, 1.0, true, -1};
  Step1Method step1 = Step1Method::batch;
  BatchLeastSquaresOptions batch;
  RecursiveLeastSquaresOptions recursive;
  SeparationMethod separation = SeparationMethod::both;
  KroneckerSeparationOptions kronecker;
  OutputErrorOptions output_error;
  /// Its hold and substeps are those of every stage (the IV instruments included).
  /// Also start from the structured step 1 (equation error in the 2(n+m) true unknowns).
  bool structured_candidate = true;
  StructuredStep1Options structured;
  /// Also start from the bias-corrected instrumental-variable iterations
  /// (estimate_structured_step1_iv) after a structured step 1 with the 1/(s + a)^q filter at
  /// each of these poles a; one candidate per pole ("structured iv a = ..."). Different poles
  /// weight different bands and land in different basins; empty: none. The IV hold and
  /// substeps are output_error's: iv.hold and iv.substeps must be empty or equal to them.
  std::vector<double> iv_filter_poles{0.3, 0.5, 1.0, 2.0};
  StructuredIvOptions iv;
  /// Output-error iterations given to every candidate before the best one continues up to
  /// output_error.max_iterations in total.
  int screening_iterations = 15;
  /// Before its screening on the whole record, each candidate is refined (screening_iterations
  /// each) on the first fraction of the record for each of these fractions in turn
  /// (continuation over the record length); empty: straight to the whole record.
  std::vector<double> continuation_fractions;
  /// Besides the best screened candidate, up to this many runner-ups whose screened output
  /// rms is within finalist_ratio of the best also continue to convergence, and the smallest
  /// final cost decides. A start far from the data can need more than the screening
  /// iterations to overtake a closer one that sits in a local minimum (seen at noise sd 1e-3;
  /// docs/algorithms/feedback-delay.md). 0: only the best continues.
  int extra_finalists = 0;
  double finalist_ratio = 1.1;
  bool refine = true;  ///< false: keep the candidate with the smallest step-1 output error

  static constexpr std::string_view type_name = "FeedbackIdentificationOptions";
  static constexpr auto fields() {
    using O = FeedbackIdentificationOptions;
    constexpr double inf = std::numeric_limits<double>::infinity();
    return std::tuple{
        field("regressors", &O::regressors, "Step-1 regressors."),
        field("step1", &O::step1, "Step-1 solver."),
        field("batch", &O::batch, "Batch least squares (step1 = batch).").with_flag("batch"),
        field("recursive", &O::recursive, "Recursive least squares (step1 = recursive).")
            .with_flag("rls"),
        field("separation", &O::separation, "Separation candidates from step 1."),
        field("kronecker", &O::kronecker, "min J separation.").with_flag("kronecker"),
        field("output_error", &O::output_error,
              "Output-error refinement; its hold and substeps are every stage's."),
        field("structured_candidate", &O::structured_candidate,
              "Also start from the structured step 1."),
        field("structured", &O::structured, "Structured step 1.").with_flag("structured"),
        field("iv_filter_poles", &O::iv_filter_poles, Each{Between{0.0, inf}},
              "One bias-corrected IV candidate per filter pole [rad/s]; empty: none."),
        field("iv", &O::iv,
              "IV iterations; hold and substeps must be empty or equal to output_error's.")
            .with_flag("iv"),
        field("screening_iterations", &O::screening_iterations, AtLeast{1},
              "Output-error iterations given to every candidate first."),
        field("continuation_fractions", &O::continuation_fractions, Each{Between{0.0, 1.0}},
              "Record fractions each candidate is first refined on, in turn."),
        field("extra_finalists", &O::extra_finalists, AtLeast{0},
              "Runner-ups within finalist_ratio also refined to convergence."),
        field("finalist_ratio", &O::finalist_ratio, Between{1.0, inf, true, false},
              "Screened rms ratio to the best within which a runner-up is a finalist."),
        field("refine", &O::refine,
              "Refine by output error (false: keep the smallest step-1 output error)."),
    };
  }
  void validate() const { validate_fields(*this); }
  /// iv.hold and iv.substeps empty or equal to output_error's.
  void check_relations(const std::string& path) const;
};

struct SeparationCandidateReport {
  std::string source;  ///< "gcd", "kronecker: gcd", "kronecker: roots split k"
  DelayedFeedbackLoop start{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                            TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  double kronecker_cost = 0.0;   ///< J of the start
  double start_rms = 0.0;        ///< output-error rms of the start (inf: unstable/overflow)
  double refined_rms = 0.0;      ///< after refinement (= start_rms when not refined)
  OutputErrorResult refinement;  ///< valid when refined

  static constexpr std::string_view type_name = "SeparationCandidateReport";
  static constexpr auto fields() {
    using R = SeparationCandidateReport;
    return std::tuple{
        field("source", &R::source,
              "'gcd', 'kronecker: <start>', 'structured step 1' or 'structured iv a = <pole>'."),
        field("start", &R::start, "The start loop."),
        field("kronecker_cost", &R::kronecker_cost, "J of the start."),
        field("start_rms", &R::start_rms, "Output-error rms of the start (inf: unstable)."),
        field("refined_rms", &R::refined_rms, "Output-error rms after refinement."),
        field("refinement", &R::refinement, "The output-error refinement (when refined)."),
    };
  }
};

/// The outcome is the chosen candidate's refinement (its termination and iterations; converged
/// when refine is off), or no_solution when no candidate exists or every one is unstable.
struct FeedbackIdentificationResult : Outcome {
  DelayedFeedbackLoop loop{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                           TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  ClosedLoopEstimate step1;       ///< α̂, β̂, γ̂ (Ŵ)
  double step1_output_rms = 0.0;  ///< output-error rms of Ŵ (inf: unstable)
  std::vector<SeparationCandidateReport> candidates;
  std::optional<std::size_t> best_candidate;  ///< index into candidates (none: no candidate)
  double output_rms = 0.0;                    ///< output-error rms of the returned loop
  SeparabilityReport cramer_rao;              ///< at the returned loop, σ² from the residuals
  /// Is the loop worth using (estimation/verdict.h): a candidate was found, the output error
  /// is finite and the output-error fit is not negative.
  Verdict verdict;

  static constexpr std::string_view type_name = "FeedbackIdentificationResult";
  static constexpr auto fields() {
    using R = FeedbackIdentificationResult;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("loop", &R::loop, "DelayedFeedbackLoop (F, H, delay)."),
            field("step1", &R::step1, "ClosedLoopEstimate of step 1 (W)."),
            field("step1_output_rms", &R::step1_output_rms,
                  "Output-error rms of the step-1 W (inf: unstable)."),
            field("candidates", &R::candidates, "Every separation candidate."),
            field("best_candidate", &R::best_candidate,
                  "Index of the chosen candidate (None: no candidate)."),
            field("output_rms", &R::output_rms, "Output-error rms of the returned loop."),
            field("cramer_rao", &R::cramer_rao,
                  "SeparabilityReport at the returned loop (sigma^2 from the residuals)."),
            field("verdict", &R::verdict,
                  "Verdict: usable, reasons, advice (docs/decisions/0007-quality-verdict.md)."),
        });
  }
};

/// Throws InvalidArgument for orders < 1, Δ < 0, too few samples or a record not longer than Δ.
FeedbackIdentificationResult identify_delayed_feedback(
    const SampledData& data, int forward_order, int feedback_order, double delay,
    const FeedbackIdentificationOptions& options = {});

/// Δ unknown: a grid scan (scan_feedback_delay; refined_output_error is the criterion that works
/// on informative records, the grid may be finer than δ), the full identification at the best
/// grid point, then either a joint output-error refinement of (ρ, Δ) from there (default) or a
/// golden-section search of the refined output-error cost over Δ within one grid step on each
/// side (each evaluation re-refines ρ from the best loop so far).
struct DelayIdentificationOptions {
  FeedbackDelayScanOptions scan = [] {
    FeedbackDelayScanOptions s;
    s.criterion = DelayCriterion::refined_output_error;
    s.iv_filter_poles = {0.5};
    return s;
  }();
  FeedbackIdentificationOptions identification;
  bool joint_delay = true;  ///< joint (ρ, Δ) refinement; false: golden section
  int golden_iterations = 20;

  static constexpr std::string_view type_name = "DelayIdentificationOptions";
  static constexpr auto fields() {
    using O = DelayIdentificationOptions;
    return std::tuple{
        field("scan", &O::scan,
              "The delay scan (its refine is not used); hold and substeps as identification's."),
        field("identification", &O::identification, "The identification at the scanned delay."),
        field("joint_delay", &O::joint_delay,
              "Refine F, H and the delay jointly (false: golden section over the delay)."),
        field("golden_iterations", &O::golden_iterations, AtLeast{0},
              "Golden-section reductions (joint_delay false)."),
    };
  }
  void validate() const { validate_fields(*this); }
  /// scan.hold and scan.substeps equal identification.output_error's (one record, one hold).
  void check_relations(const std::string& path) const;
};

/// The outcome of the identification at the returned Δ (no_solution when the scan found no
/// delay at which the regression can be built).
struct DelayIdentificationResult : Outcome {
  FeedbackDelayScanResult scan;
  FeedbackIdentificationResult identification;  ///< at the returned Δ (loop.delay)
  double delay = 0.0;
  int evaluations = 0;

  static constexpr std::string_view type_name = "DelayIdentificationResult";
  static constexpr auto fields() {
    using R = DelayIdentificationResult;
    return join_fields(Outcome::fields(),
                       std::tuple{
                           field("scan", &R::scan, "FeedbackDelayScanResult."),
                           field("identification", &R::identification,
                                 "FeedbackIdentificationResult at the returned delay."),
                           field("delay", &R::delay, "Estimated delay [s]."),
                           field("evaluations", &R::evaluations, "Refinements run after the scan."),
                       });
  }
};

/// `progress`, if given, is passed to scan_feedback_delay (one call per grid point).
DelayIdentificationResult identify_delayed_feedback_with_delay_scan(
    const SampledData& data, int forward_order, int feedback_order,
    const DelayIdentificationOptions& options = {},
    const std::function<void(int, int)>& progress = {});

}  // namespace ctid
