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
#include "ctid/delayed_feedback/least_squares.h"
#include "ctid/delayed_feedback/regressors.h"
#include "ctid/delayed_feedback/separation.h"
#include "ctid/estimation/termination.h"
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
                                    double sample_time, Hold hold, double noise_sd,
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

struct StructuredIvResult {
  DelayedFeedbackLoop loop{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                           TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  double output_rms = 0.0;                 ///< of the returned loop on the data
  std::vector<double> output_rms_history;  ///< start, then each iterate (inf: unstable)
  int iterations = 0;
  bool converged = false;
  std::string message;
};

/// Throws InvalidArgument for an invalid start or data too short for the regression.
StructuredIvResult estimate_structured_step1_iv(const SampledData& data,
                                                const DelayedFeedbackLoop& start,
                                                const FeedbackRegressorOptions& regressors,
                                                const StructuredIvOptions& options = {});

struct OutputErrorOptions {
  Hold hold = Hold::zero_order_hold;  ///< how the measured input is continued
  int substeps = 4;                   ///< RK4 steps per sample in the simulations
  int max_iterations = 200;
  /// Also estimate Δ (>= 0) jointly with ρ; the covariance still covers ρ only.
  bool estimate_delay = false;
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

/// Minimises sum_k (y_k - ŷ_k(ρ))² by Levenberg-Marquardt from `start` (Δ kept fixed unless
/// options.estimate_delay).
/// An unstable or overflowing iterate is rejected as a failed step, never thrown.
OutputErrorResult refine_output_error(const SampledData& data, const DelayedFeedbackLoop& start,
                                      const OutputErrorOptions& options = {});

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

struct FeedbackDelayScanResult {
  Eigen::VectorXd delays;
  Eigen::VectorXd criterion;  ///< per DelayCriterion (inf: unstable or degenerate)
  double delay = 0.0;         ///< the minimiser
  double best_criterion = 0.0;
};

/// For each Δ: step 1 (batch) and the output error of W = α̂/(β̂ + γ̂ e^{-Δs}) on the data.
FeedbackDelayScanResult scan_feedback_delay(const SampledData& data, int forward_order,
                                            int feedback_order,
                                            const FeedbackDelayScanOptions& options = {});

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

struct FeedbackIdentificationResult {
  DelayedFeedbackLoop loop{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                           TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  ClosedLoopEstimate step1;       ///< α̂, β̂, γ̂ (Ŵ)
  double step1_output_rms = 0.0;  ///< output-error rms of Ŵ (inf: unstable)
  std::vector<SeparationCandidateReport> candidates;
  int best_candidate = -1;        ///< index into candidates
  double output_rms = 0.0;        ///< output-error rms of the returned loop
  SeparabilityReport cramer_rao;  ///< at the returned loop, σ² from the residuals
  std::string message;
};

/// Throws InvalidArgument for orders < 1, Δ < 0, too few samples or a record not longer than Δ.
FeedbackIdentificationResult identify_delayed_feedback(
    const SampledData& data, int forward_order, int feedback_order, double delay,
    const FeedbackIdentificationOptions& options = {});

/// Output-error rms of a loop on the data (+inf when the simulation overflows).
double loop_output_rms(const SampledData& data, const DelayedFeedbackLoop& loop, Hold hold,
                       int substeps);

/// Δ unknown: a grid scan (scan_feedback_delay; kRefinedOutputError is the criterion that works on
/// informative records, the grid may be finer than δ), the full identification at the best
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

struct DelayIdentificationResult {
  FeedbackDelayScanResult scan;
  FeedbackIdentificationResult identification;  ///< at the returned Δ (loop.delay)
  double delay = 0.0;
  int evaluations = 0;
};

DelayIdentificationResult identify_delayed_feedback_with_delay_scan(
    const SampledData& data, int forward_order, int feedback_order,
    const DelayIdentificationOptions& options = {});

}  // namespace ctid
