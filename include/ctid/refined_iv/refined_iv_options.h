// Options shared by the refined instrumental-variable estimators (SRIVC, CLSRIVC and the
// additive open/closed-loop iteration (29) of González et al.). Plain struct with defaults;
// validate() names the field, its value and the rule.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string_view>
#include <tuple>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/hold.h"

namespace ctid {

/// How the asymptotic covariance treats the output noise (Theorem 3.2).
enum class NoiseAssumption {
  white,     ///< sigma^2 (sum psi psi')^-1
  coloured,  ///< sandwich R^-1 Q R^-1 with Q from an AR model of the residuals
};

inline constexpr std::array<Enumerator<NoiseAssumption>, 2> noise_assumption_enumerators{{
    {NoiseAssumption::white, "white", "sigma^2 (sum psi psi')^-1."},
    {NoiseAssumption::coloured, "coloured",
     "Sandwich R^-1 Q R^-1, Q from an AR model of the residuals."},
}};
constexpr std::span<const Enumerator<NoiseAssumption>> enumerators(NoiseAssumption) {
  return noise_assumption_enumerators;
}

/// How a start is found from the data when no initial model is given (initialization.h).
enum class StartMethod {
  automatic,  ///< every candidate below, the lowest output error after refinement kept
  lssvf,      ///< LSSVF over a grid of filter bandwidths, each refined by SRIVC
  frf,        ///< resonance peaks of the record's FRF with half-power damping, refined by SRIVC
};

inline constexpr std::array<Enumerator<StartMethod>, 3> start_method_enumerators{{
    {StartMethod::automatic, "auto",
     "Every candidate start (LSSVF grid, FRF peaks); the lowest output error kept."},
    {StartMethod::lssvf, "lssvf", "LSSVF over a grid of filter bandwidths, refined by SRIVC."},
    {StartMethod::frf, "frf", "Resonance peaks of the record's FRF, refined by SRIVC."},
}};
constexpr std::span<const Enumerator<StartMethod>> enumerators(StartMethod) {
  return start_method_enumerators;
}

/// What the refined IV estimators assume about the state of the system at the first sample.
enum class InitialConditions {
  zero,      ///< at rest (the paper's estimators; exact for records that start at rest)
  estimate,  ///< unknown: each submodel's free response is a nuisance parameter
};

inline constexpr std::array<Enumerator<InitialConditions>, 2> initial_conditions_enumerators{{
    {InitialConditions::zero, "zero", "The system is at rest at the first sample (the paper)."},
    {InitialConditions::estimate, "estimate",
     "Each submodel's free response from an unknown initial state is estimated with the "
     "parameters; the covariance accounts for it."},
}};
constexpr std::span<const Enumerator<InitialConditions>> enumerators(InitialConditions) {
  return initial_conditions_enumerators;
}

/// The discrete-time ARMA noise model C(q^-1)/D(q^-1) that RIVC and CLRIVC estimate with the
/// plant (the hybrid Box-Jenkins model, estimation/arma.h): its orders given, or chosen by the
/// Bayesian information criterion on the residual of the start.
struct NoiseModelOrders {
  int ar = 1;              ///< p = deg D(q^-1), the autoregressive part
  int ma = 0;              ///< q = deg C(q^-1), the moving-average part
  bool automatic = false;  ///< orders in 0..max_order each, chosen by the criterion
  int max_order = 3;       ///< automatic: the largest AR and MA order tried

  static constexpr std::string_view type_name = "NoiseModelOrders";
  /// On the command line one flag: "--noise-model 2,1", "--noise-model auto" or
  /// "--noise-model none" (from_flag).
  static constexpr std::string_view flag_form = "P,Q|auto|none";
  static constexpr auto fields() {
    using O = NoiseModelOrders;
    return std::tuple{
        field("ar", &O::ar, Between{0.0, 20.0, true, true}, "p = deg D(q^-1), the AR order."),
        field("ma", &O::ma, Between{0.0, 20.0, true, true}, "q = deg C(q^-1), the MA order."),
        field("automatic", &O::automatic,
              "Orders in 0..max_order each, chosen by the Bayesian information criterion."),
        field("max_order", &O::max_order, Between{0.0, 20.0, true, true},
              "With automatic: the largest AR and MA order tried."),
    };
  }
  /// The orders a command-line word gives: none for "none", automatic for "auto", p and q for
  /// "P,Q". Throws InvalidArgument naming the word otherwise.
  static std::optional<NoiseModelOrders> from_flag(std::string_view word);
  void validate() const { validate_fields(*this); }
};

struct RefinedIvOptions {
  /// Upper bound on the iterations of (29)/(30). >= 1.
  int max_iterations = 100;
  /// Stop when the largest relative change of a block of beta (each submodel's a and b,
  /// decision 0020) is below tolerance. > 0 and < 1. The rounding
  /// floor is about 1e-15 (additive) to 5e-14 (8-pole unfactored).
  double tolerance = 1e-10;
  /// Starting model. Any model is accepted: if its submodel orders differ from the requested
  /// ones it is converted to one transfer function and regrouped. Without it the start is
  /// found from the data (initialization.h).
  std::optional<AdditiveModel> initial_model;
  /// How the start is found from the data when initial_model is none.
  StartMethod start = StartMethod::automatic;
  /// Records longer than this find the start on a piece of themselves, their first
  /// max(start_screening_samples, N / 32) samples (InitializationOptions::screening_samples);
  /// 0: on the whole record.
  int start_screening_samples = 10000;
  /// Interpolation of the measured output between samples before filtering.
  Hold output_interpolation = Hold::first_order_hold;
  /// Known input delay in whole samples (>= 0); the model's input_delay [s] is set to
  /// (input_delay_samples + input_delay_fraction) * h.
  int input_delay_samples = 0;
  /// Known fraction of a sample added to input_delay_samples, in [0, 1): the filters see the input
  /// delayed exactly (held as the record's input_hold says, SampledFilter).
  double input_delay_fraction = 0.0;
  /// Several records (identify on a list): whole samples by which each record's input lags
  /// more than input_delay_samples says (an acquisition started late), one entry per record,
  /// each >= 0; empty: none. The model's delay stays input_delay_samples.
  std::vector<int> record_delay_samples;
  /// The delay was estimated from these data (IdentificationOptions::delay_range): the output
  /// sensitivity to it joins the covariance, whose parameter block then accounts for it, and
  /// EstimationResult::delay_standard_error reports its standard error.
  bool delay_estimated = false;
  /// Keep one IterationRecord per iteration in the result.
  bool record_history = false;
  /// Step control: a step of (29) after which the equations are singular or non-finite is
  /// halved toward the last accepted iterate (at most max_step_halvings times per step).
  /// Accepted steps are the plain iteration, so the fixed points are unchanged; halvings are
  /// counted in EstimationResult::step_halvings. (Unstable denominators are reflected, and
  /// in closed loop an iterate the controller does not stabilise keeps the last S_uo r,
  /// counted in sensitivity_fallbacks; halving those steps was measured to reach the true
  /// start's stationary point less often.)
  bool step_control = true;
  /// Largest number of halvings of one step. >= 0.
  int max_step_halvings = 8;
  /// Noise assumption for the covariance.
  NoiseAssumption noise = NoiseAssumption::coloured;
  /// Largest AR order tried for the coloured-noise covariance (chosen by AIC). >= 1.
  int noise_model_max_order = 20;
  /// The ARMA noise model estimated with the plant (RIVC open loop, CLRIVC closed loop; Young
  /// and Garnier): the prefilters of the iteration are D/(C A) instead of 1/A, the covariance
  /// is that of the prefiltered instrument with the innovations' variance (`noise` and
  /// noise_model_max_order then do not apply), and EstimationResult::noise_model holds it.
  /// None: the simplified estimators (SRIVC, CLSRIVC), bit for bit.
  std::optional<NoiseModelOrders> noise_model;
  /// Compute covariance, standard errors and modal standard errors (skip to save time).
  bool compute_covariance = true;
  /// State at the first sample. `estimate` adds the free response of every submodel
  /// (n_i + l_i coefficients each) to the regressor and the instrument; the reported
  /// covariance is the parameter block of the joint one. Default `zero`: decision 0010.
  InitialConditions initial_conditions = InitialConditions::zero;
  /// Threads that filter one record's submodels in parallel during the passes (decision 0068).
  /// 0: automatic, the idle cores (idle_thread_count) for a record of at least 100 000
  /// samples, one inside a parallel loop (studies, scans) and for shorter records. Never more
  /// than the submodels. The estimate does not depend on it, to the bit. >= 0.
  int threads = 0;

  static constexpr std::string_view type_name = "RefinedIvOptions";
  static constexpr auto fields() {
    using O = RefinedIvOptions;
    return std::tuple{
        field("max_iterations", &O::max_iterations, AtLeast{1},
              "Upper bound on the iterations of (29)/(30)."),
        field("tolerance", &O::tolerance, Between{0.0, 1.0},
              "Stop when the relative parameter change falls below this."),
        field("initial_model", &O::initial_model,
              "Starting AdditiveModel, or none: found from the data.")
            .with_flag("initial"),
        field("start", &O::start, "How the start is found from the data without initial_model."),
        field("start_screening_samples", &O::start_screening_samples, AtLeast{0},
              "Longer records find the start on their first max(this, N/32) samples; 0: the "
              "whole record.")
            .with_flag("start-screening"),
        field("output_interpolation", &O::output_interpolation,
              "How the measured output is continued between samples before filtering.")
            .with_flag("interpolation"),
        field("input_delay_samples", &O::input_delay_samples, AtLeast{0},
              "Known input delay [whole samples]."),
        field("input_delay_fraction", &O::input_delay_fraction, Between{0.0, 1.0, true, false},
              "Known fraction of a sample added to input_delay_samples, in [0, 1)."),
        field("record_delay_samples", &O::record_delay_samples, Each{AtLeast{0}},
              "Per record, whole samples added to input_delay_samples (several records); empty: "
              "none."),
        field("delay_estimated", &O::delay_estimated,
              "The delay was estimated: its sensitivity joins the covariance."),
        field("record_history", &O::record_history, "Keep one IterationRecord per iteration.")
            .with_flag("history"),
        field("step_control", &O::step_control,
              "Halve steps after which the equations are singular or non-finite."),
        field("max_step_halvings", &O::max_step_halvings, AtLeast{0},
              "Largest number of halvings of one step."),
        field("noise", &O::noise, "Noise assumption of the covariance."),
        field("noise_model_max_order", &O::noise_model_max_order, AtLeast{1},
              "Largest AR order of the coloured-noise covariance (chosen by AIC)."),
        field("noise_model", &O::noise_model,
              "NoiseModelOrders of the ARMA noise model estimated with the plant (RIVC), or "
              "none (SRIVC)."),
        field("compute_covariance", &O::compute_covariance,
              "Compute covariance, standard errors and modal standard errors."),
        field("initial_conditions", &O::initial_conditions,
              "State at the first sample: zero (at rest) or estimate (nuisance parameters)."),
        field("threads", &O::threads, AtLeast{0},
              "Threads that filter one record's submodels in parallel; 0: the idle cores for a "
              "record of at least 100000 samples, one inside studies and scans. Same bits "
              "whatever the count."),
    };
  }
  /// Throws InvalidArgument naming the first bad field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

}  // namespace ctid
