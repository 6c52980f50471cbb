// The front door of the refined IV module (González et al.): one call that takes data, a model
// structure and options and runs what `ctid fit` runs: the estimator the structure and the
// loop call for (SRIVC / CLSRIVC, Remark 4 eq. 30; the additive iteration (29) in open or
// closed loop), its automatic start, an optional input-delay scan (Section 7), optional mode
// relocation, the covariance (Theorem 3.2) and the data checks (Assumptions 1 and 4).
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"
#include "ctid/core/transfer_function.h"
#include "ctid/identification/two_stage.h"
#include "ctid/output_error/output_error_polish.h"
#include "ctid/process_model/process_model.h"
#include "ctid/process_model/process_response.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/input_delay_scan.h"
#include "ctid/refined_iv/irregular_srivc.h"
#include "ctid/refined_iv/mode_relocation.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

/// One unfactored transfer function or a sum of submodels.
enum class ModelKind {
  unfactored,  ///< B(p) / (p^l A(p)): SRIVC or CLSRIVC
  additive,    ///< sum of B_i / (p^l_i A_i): the iteration (29)
};

inline constexpr std::array<Enumerator<ModelKind>, 2> model_kind_enumerators{{
    {ModelKind::unfactored, "unfactored", "One transfer function B/(p^l A) (SRIVC, CLSRIVC)."},
    {ModelKind::additive, "additive", "A sum of submodels B_i/(p^l_i A_i) (iteration (29))."},
}};
constexpr std::span<const Enumerator<ModelKind>> enumerators(ModelKind) {
  return model_kind_enumerators;
}

/// The most submodels (modes) a structure may have.
inline constexpr int kMaxSubmodels = 1000;

/// The model to estimate: its kind and the orders {n, m, l} of its one (unfactored) or K
/// (additive, in any order) submodels.
struct ModelStructure {
  ModelKind kind = ModelKind::unfactored;
  std::vector<SubmodelOrder> orders{SubmodelOrder{}};

  /// B(p) / (p^integrators A(p)) with deg A = poles, deg B = zeros.
  static ModelStructure unfactored(int poles, int zeros, int integrators = 0);
  /// Submodels with these orders, listed from the slowest to the fastest.
  static ModelStructure additive(std::vector<SubmodelOrder> orders);
  /// `count` second-order modes b_0 / (1 + a_1 p + a_2 p^2).
  static ModelStructure modes(int count);

  bool is_additive() const { return kind == ModelKind::additive; }

  static constexpr std::string_view type_name = "ModelStructure";
  static constexpr auto fields() {
    using S = ModelStructure;
    return std::tuple{
        field("kind", &S::kind, "unfactored (one transfer function) or additive (submodels)."),
        field("orders", &S::orders,
              "SubmodelOrder {n, m, integrators} of each submodel (one if unfactored)."),
    };
  }
  /// Unfactored: exactly one order; additive: at least one.
  void check_relations(const std::string& path) const;
  /// At most kMaxSubmodels orders (checked first: a huge list would make the per-order checks
  /// themselves the unbounded work).
  void check_size(const std::string& path = std::string(type_name)) const;
  /// Throws InvalidArgument naming the bad field (the orders themselves are checked by the
  /// estimator, which knows the data).
  void validate() const {
    check_size();
    validate_fields(*this);
  }
};

/// An inclusive range of whole-sample input delays to scan.
struct DelayRange {
  int min = 0;
  int max = 0;

  static constexpr std::string_view type_name = "DelayRange";
  /// On the command line one flag, "--delay-scan-samples 0:10".
  static constexpr std::string_view flag_form = "MIN:MAX";
  static constexpr auto fields() {
    return std::tuple{
        field("min", &DelayRange::min, AtLeast{0}, "Smallest delay tried [samples]."),
        field("max", &DelayRange::max, AtLeast{0}, "Largest delay tried [samples], >= min."),
    };
  }
  void check_relations(const std::string& path) const;
  void validate() const { validate_fields(*this); }
};

/// An interval of input delays [s] within which the delay is estimated as a continuous
/// parameter together with the model.
struct DelayInterval {
  double min = 0.0;
  double max = 0.0;

  static constexpr std::string_view type_name = "DelayInterval";
  /// On the command line one flag, "--delay-range 0:0.5".
  static constexpr std::string_view flag_form = "MIN:MAX";
  static constexpr auto fields() {
    return std::tuple{
        field("min", &DelayInterval::min, Finite{AtLeast{0.0}}, "Smallest delay [s]."),
        field("max", &DelayInterval::max, Finite{AtLeast{0.0}}, "Largest delay [s], >= min."),
    };
  }
  void check_relations(const std::string& path) const;
  void validate() const { validate_fields(*this); }
};

/// Which refined IV estimator identify() ran.
enum class RefinedIvEstimator {
  srivc,             ///< unfactored, open loop
  clsrivc,           ///< unfactored, closed loop
  additive_srivc,    ///< additive, open loop
  additive_clsrivc,  ///< additive, closed loop
  srivc_irregular,   ///< unfactored, open loop, on irregular time stamps (irregular_srivc.h)
  rivc,              ///< unfactored, open loop, with an ARMA noise model
  clrivc,            ///< unfactored, closed loop, with an ARMA noise model
  additive_rivc,     ///< additive, open loop, with an ARMA noise model
  additive_clrivc,   ///< additive, closed loop, with an ARMA noise model
  /// unfactored, closed loop with a continuous-time controller (clsrivc_continuous.h)
  clsrivc_continuous,
};

inline constexpr std::array<Enumerator<RefinedIvEstimator>, 10> refined_iv_estimator_enumerators{{
    {RefinedIvEstimator::srivc, "srivc", "SRIVC: unfactored, open loop (eq. 30, instrument (10))."},
    {RefinedIvEstimator::clsrivc, "clsrivc",
     "CLSRIVC: unfactored, closed loop (eq. 30, instrument (20))."},
    {RefinedIvEstimator::additive_srivc, "additive_srivc",
     "Additive, open loop (eq. 29, instrument (10))."},
    {RefinedIvEstimator::additive_clsrivc, "additive_clsrivc",
     "Additive, closed loop (eq. 29, instrument (20))."},
    {RefinedIvEstimator::srivc_irregular, "srivc_irregular",
     "SRIVC on irregular time stamps: filters discretised on each interval (decision 0034)."},
    {RefinedIvEstimator::rivc, "rivc",
     "RIVC: unfactored, open loop, with an ARMA noise model (decision 0056)."},
    {RefinedIvEstimator::clrivc, "clrivc",
     "CLRIVC: unfactored, closed loop, with an ARMA noise model (decision 0056)."},
    {RefinedIvEstimator::additive_rivc, "additive_rivc",
     "Additive, open loop, with an ARMA noise model (decision 0056)."},
    {RefinedIvEstimator::additive_clrivc, "additive_clrivc",
     "Additive, closed loop, with an ARMA noise model (decision 0056)."},
    {RefinedIvEstimator::clsrivc_continuous, "clsrivc_continuous",
     "Unfactored, closed loop with a continuous-time controller: the loop's output error "
     "from r (decision 0067)."},
}};
constexpr std::span<const Enumerator<RefinedIvEstimator>> enumerators(RefinedIvEstimator) {
  return refined_iv_estimator_enumerators;
}

/// The estimator for a structure: unfactored or additive, closed loop when a controller is known,
/// with a noise model when one is asked for (RefinedIvOptions::noise_model).
RefinedIvEstimator choose_estimator(const ModelStructure& structure, bool closed_loop,
                                    bool noise_model = false);

struct IdentificationOptions {
  /// The known discrete controller u_k = C_d(q)(r_k - y_k) of closed-loop data (the data
  /// must then hold the reference); none: open loop.
  std::optional<DiscreteTransferFunction> controller;
  /// The known continuous-time controller u = C(p)(r - y) of an analog loop (the data must
  /// then hold the reference, held between samples as the data's input hold says):
  /// clsrivc_continuous, one unfactored model, one record, no delay (decision 0067). None:
  /// open loop, or the discrete controller.
  std::optional<TransferFunction> continuous_controller;
  /// Scan these whole-sample input delays and keep the best output-error fit (converged fits
  /// first); none: the known delay refined_iv.input_delay_samples (which must then be 0 if set).
  std::optional<DelayRange> delay_scan_samples;
  /// Estimate the input delay as a continuous parameter in this interval [s]: the whole
  /// samples in it are scanned as with delay_scan_samples, then the output error is minimised over
  /// the delay within a sample of the best (Brent's method, each point a converged fit), and
  /// the final fit reports the delay's standard error (EstimationResult::delay_standard_error,
  /// its sensitivity in the covariance). None: a known delay or delay_scan_samples.
  std::optional<DelayInterval> delay_range;
  /// After the fit (at the delay the scan chose), move second-order submodels to peaks of
  /// the residual spectrum and keep moves that fit better (mode_relocation.h). Additive
  /// structure, open loop only.
  bool relocate_modes = false;
  /// Options of the relocation (used with relocate_modes).
  ModeRelocationOptions relocation;
  /// After the fit, polish it by continuous-time output error (prediction error with a noise
  /// model; output_error/output_error_polish.h, decision 0057) and report the polished model
  /// beside it in IdentificationResult::polish. Open loop, one record. Without it the polish
  /// still runs when the refined IV iteration does not converge (see identify()).
  bool polish = false;
  /// Options of the polish; the initial state is estimated when refined_iv estimates it too.
  OutputErrorPolishOptions polish_options;
  /// Known coefficients, bounds and a known DC gain (decision 0057). They imply the polish,
  /// which imposes all of them; the refined IV iteration holds the coefficients they determine
  /// (held values, and the one b0 left free by a DC gain) as well.
  CoefficientConstraints constraints;
  /// Options of the estimator (iterations, tolerance, start, known delay, covariance, ...).
  RefinedIvOptions refined_iv;
  /// Closed loop with an unknown controller (two_stage.h, decision 0043): the map r -> u by
  /// an FIR model, then the plant by the open-loop estimator from the simulated input; the
  /// data must hold the reference and no controller is given. None: open loop, or CLSRIVC
  /// with the known controller.
  std::optional<TwoStageOptions> two_stage;

  static constexpr std::string_view type_name = "IdentificationOptions";
  static constexpr auto fields() {
    using O = IdentificationOptions;
    return std::tuple{
        field("controller", &O::controller,
              "Known discrete controller of closed-loop data, or none (open loop)."),
        field("continuous_controller", &O::continuous_controller,
              "Known continuous-time controller of an analog loop, or none.")
            .with_flag("controller"),
        field("delay_scan_samples", &O::delay_scan_samples,
              "DelayRange of input delays to scan, or none (the known "
              "refined_iv.input_delay_samples)."),
        field("delay_range", &O::delay_range,
              "DelayInterval [s] in which the delay is estimated as a continuous parameter."),
        field("relocate_modes", &O::relocate_modes,
              "Move second-order submodels to residual peaks after the fit (additive, open loop)."),
        field("relocation", &O::relocation, "ModeRelocationOptions of relocate_modes.")
            .with_flag("relocation"),
        field("polish", &O::polish,
              "Polish the fit by output (prediction) error and report it beside (open loop)."),
        field("polish_options", &O::polish_options, "OutputErrorPolishOptions of the polish.")
            .with_flag("polish"),
        field("constraints", &O::constraints,
              "CoefficientConstraints: held and bounded coefficients, a known DC gain."),
        field("refined_iv", &O::refined_iv, "RefinedIvOptions of the estimator."),
        field("two_stage", &O::two_stage,
              "TwoStageOptions of the two-stage method (unknown controller), or none."),
    };
  }
  void check_relations(const std::string& path) const;
  /// Throws InvalidArgument naming the first bad field by its full path, its value and the rule.
  void validate() const { validate_fields(*this); }
  /// The polish is asked for: polish, or a constraint (which the polish imposes).
  bool polish_asked() const { return polish || !constraints.empty(); }
};

/// What identify() ran and found.
struct IdentificationResult {
  explicit IdentificationResult(EstimationResult result) : estimate(std::move(result)) {}

  RefinedIvEstimator estimator = RefinedIvEstimator::srivc;
  /// Closed loop: a controller was given, or the two-stage method ran.
  bool closed_loop = false;
  /// The final estimate (after the delay scan and the relocation, when asked for).
  EstimationResult estimate;
  /// Every delay tried, with IdentificationOptions::delay_scan_samples.
  std::optional<InputDelayScanResult> delay_scan;
  /// What the relocation tried and kept, with IdentificationOptions::relocate_modes.
  std::optional<ModeRelocationResult> mode_relocation;
  /// Stage 1 of the two-stage method, with IdentificationOptions::two_stage.
  std::optional<TwoStageResult> two_stage;
  /// The output-error polish of the fit: with IdentificationOptions::polish, or when the
  /// refined IV iteration did not converge (open loop, one record).
  std::optional<OutputErrorPolishResult> polish;
  /// The iteration had not converged, and its restart from the polished model did: `estimate`
  /// is that restart.
  bool restarted_from_polish = false;

  static constexpr std::string_view type_name = "IdentificationResult";
  static constexpr auto fields() {
    using R = IdentificationResult;
    return std::tuple{
        field("estimator", &R::estimator, "The refined IV estimator that ran."),
        field("closed_loop", &R::closed_loop,
              "Closed loop (a controller was given, or the two-stage method ran)."),
        field("estimate", &R::estimate, "The final EstimationResult."),
        field("delay_scan", &R::delay_scan, "InputDelayScanResult of the delay scan, or none."),
        field("mode_relocation", &R::mode_relocation,
              "ModeRelocationResult of the relocation, or none."),
        field("two_stage", &R::two_stage, "TwoStageResult of the two-stage method, or none."),
        field("polish", &R::polish, "OutputErrorPolishResult of the polish, or none."),
        field("restarted_from_polish", &R::restarted_from_polish,
              "The estimate is the refined IV restarted from the polished model."),
    };
  }
};

/// Progress reports of identify() for a caller that shows them; each, if given, is called with
/// (done, total) as the run goes.
struct IdentificationProgress {
  /// After each whole-sample delay of the delay scan (delay_scan_samples, or the scan of
  /// delay_range).
  std::function<void(int, int)> delay_scan;
  /// After each trial of the mode relocation (additive_srivc_relocated's progress).
  std::function<void(int, int)> relocation;
};

/// Throws InvalidArgument if the structure or the options are bad or do not go together
/// (relocation of an unfactored or closed-loop model). identify() calls it first.
void validate_identification(const ModelStructure& structure, const IdentificationOptions& options);

/// Estimates `structure` from `data` with the estimator choose_estimator() names: over the
/// delay scan if one is asked for (scan_input_delay), or with the delay estimated in
/// delay_range (which must end before the record does), then with mode relocation if asked for
/// (additive_srivc_relocated, started from that estimate at its delay, so the plain iteration
/// stops at once and the scan is not repeated). Then, open loop on one record, the
/// output-error polish (decision 0057): with options.polish it is reported beside the fit;
/// without it, it runs only when the iteration did not converge, from the last iterate at its
/// delay, and the refined IV restarted from the polished model replaces the fit when that
/// restart converges to a usable model. Throws InvalidArgument for bad input (as the
/// estimators do); how the iteration ended is result.estimate.termination.
IdentificationResult identify(const SampledData& data, const ModelStructure& structure,
                              const IdentificationOptions& options = {},
                              const IdentificationProgress& progress = {});

/// identify() on several records of one system (separate experiments, or pieces of one
/// record): one parameter vector fitted to all of them, each record's filters starting at
/// its own first sample and, with InitialConditions::estimate, its own initial state. The
/// records share the sample time, the input hold, the signals (a reference in closed loop)
/// and the input delay; the start comes from the longest record. Mode relocation takes one
/// record. One record gives exactly identify(data, ...).
IdentificationResult identify(const std::vector<SampledData>& records,
                              const ModelStructure& structure,
                              const IdentificationOptions& options = {},
                              const IdentificationProgress& progress = {});

/// identify() on a record at irregular time stamps (docs/decisions/0034): srivc_irregular,
/// the filters discretised on each interval as it is. Only what that estimator does is taken:
/// an unfactored structure, open loop, no delay scan or range, no mode relocation; anything
/// else is refused with InvalidArgument naming the field. estimator is srivc_irregular.
IdentificationResult identify(const IrregularRecord& record, const ModelStructure& structure,
                              const IdentificationOptions& options = {});

/// A process model (procest's P1D, P2DU, ...; process_model/process_model.h, decision 0040)
/// through the front door: the output-error fit of its physical parameters, open loop, from
/// the automatic start or the starts, held values and bounds of `options`. The refined IV
/// options do not apply; the automatic start runs SRIVC of the matching order.
ProcessModelResult identify(const SampledData& data, const ProcessStructure& structure,
                            const ProcessModelOptions& options = {});

/// Throws InvalidArgument if the process-model options are bad or do not go with the structure
/// (validate_process_model: a parameter it does not have, a start outside its bounds, ...);
/// identify(data, ProcessStructure, ...) checks the same, so a caller may check before reading
/// the data.
void validate_identification(const ProcessStructure& structure, const ProcessModelOptions& options);

/// The step or impulse response of a process-model estimate with its band and the step
/// characteristics' standard errors, by the delta method in the process parameters
/// (process_model/process_response.h): what `ctid step` and `ctid impulse` print for a
/// `ctid fit --process` result.
TimeResponse time_response(const ProcessModelResult& result,
                           const TimeResponseOptions& options = {});

}  // namespace ctid
