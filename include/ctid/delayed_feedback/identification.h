// The whole delayed-feedback identification of De Iuliis, Germani, Manes 2017 and beyond it:
// step 1, the separation candidates, the output-error refinement from each, and the same with
// the delay unknown.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
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
#include "ctid/simulation/delayed_feedback.h"

namespace ctid {

/// The whole identification: step 1 (batch or RLS) gives Ŵ = α̂/(β̂ + γ̂ e^{-Δs}); the
/// separation candidates are the approximate-GCD estimate and every refined start of min J
/// (the GCD start and each root split of β̂); the output-error refinement in the 2(n+m) true
/// unknowns runs from EACH candidate (screening_iterations steps), the smallest output-error
/// cost decides, and that candidate is refined to convergence. Candidates
/// whose simulation overflows or whose refinement fails are kept with an infinite cost.
enum class Step1Method { kBatch, kRecursive };
enum class SeparationMethod { kKronecker, kGcd, kBoth };

struct FeedbackIdentificationOptions {
  FeedbackRegressorOptions regressors{RegressorFilter::kLinearIntegralFilter, 1.0, true, -1};
  Step1Method step1 = Step1Method::kBatch;
  BatchLeastSquaresOptions batch;
  RecursiveLeastSquaresOptions recursive;
  SeparationMethod separation = SeparationMethod::kBoth;
  KroneckerSeparationOptions kronecker;
  OutputErrorOptions output_error;
  /// Also start from the structured step 1 (equation error in the 2(n+m) true unknowns).
  bool structured_candidate = true;
  StructuredStep1Options structured;
  /// Also start from the bias-corrected instrumental-variable iterations
  /// (estimate_structured_step1_iv) after a structured step 1 with the 1/(s + a)^q filter at
  /// each of these poles a; one candidate per pole ("structured iv a = ..."). Different poles
  /// weight different bands and land in different basins; empty: none. The IV hold and
  /// substeps follow output_error.
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
  void validate() const;
};

struct SeparationCandidateReport {
  std::string source;  ///< "gcd", "kronecker: gcd", "kronecker: roots split k"
  DelayedFeedbackLoop start{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                            TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  double kronecker_cost = 0.0;   ///< J of the start
  double start_rms = 0.0;        ///< output-error rms of the start (inf: unstable/overflow)
  double refined_rms = 0.0;      ///< after refinement (= start_rms when not refined)
  OutputErrorResult refinement;  ///< valid when refined
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
};

/// Throws InvalidArgument for orders < 1, Δ < 0, too few samples or a record not longer than Δ.
FeedbackIdentificationResult identify_delayed_feedback(
    const SampledData& data, int forward_order, int feedback_order, double delay,
    const FeedbackIdentificationOptions& options = {});

/// Δ unknown: a grid scan (scan_feedback_delay; kRefinedOutputError is the criterion that works
/// on informative records, the grid may be finer than δ), the full identification at the best
/// grid point, then either a joint output-error refinement of (ρ, Δ) from there (default) or a
/// golden-section search of the refined output-error cost over Δ within one grid step on each
/// side (each evaluation re-refines ρ from the best loop so far).
struct DelayIdentificationOptions {
  FeedbackDelayScanOptions scan = [] {
    FeedbackDelayScanOptions s;
    s.criterion = DelayCriterion::kRefinedOutputError;
    s.iv_filter_poles = {0.5};
    return s;
  }();
  FeedbackIdentificationOptions identification;
  bool joint_delay = true;  ///< joint (ρ, Δ) refinement; false: golden section
  int golden_iterations = 20;
  void validate() const;
};

/// The outcome of the identification at the returned Δ (no_solution when the scan found no
/// delay at which the regression can be built).
struct DelayIdentificationResult : Outcome {
  FeedbackDelayScanResult scan;
  FeedbackIdentificationResult identification;  ///< at the returned Δ (loop.delay)
  double delay = 0.0;
  int evaluations = 0;
};

DelayIdentificationResult identify_delayed_feedback_with_delay_scan(
    const SampledData& data, int forward_order, int feedback_order,
    const DelayIdentificationOptions& options = {});

}  // namespace ctid
