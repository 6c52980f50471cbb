// The output-error polish of a refined IV estimate (issue 36, decision 0057): from the IV
// model, the continuous-time output error sum (y_k - y_model(t_k))^2 is minimised by
// Levenberg–Marquardt (Ceres) over the same coefficients beta (AdditiveModel::parameters()
// layout), the input delay as a continuous parameter, and, with a noise model, over its
// ARMA coefficients too: the criterion is then the prediction error e = (D/C)(y - y_model).
// An estimated initial state enters by variable projection (the free responses' coefficients
// are solved by least squares at every evaluation). Open loop, one SISO record.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"
#include "ctid/core/transfer_function.h"
#include "ctid/estimation/arma.h"
#include "ctid/estimation/termination.h"
#include "ctid/estimation/verdict.h"

namespace ctid {

/// What is known about one coefficient, by name: a coefficient of beta as the result names it
/// (AdditiveModel::parameter_names(): theta1.a1, theta1.b0, ...) or tau, the input delay [s]
/// (estimated by the polish).
struct CoefficientSetting {
  std::string name;
  /// Hold the parameter at this value; none: free.
  std::optional<double> fixed;
  /// Bounds of a free parameter; none: unbounded.
  std::optional<double> lower;
  std::optional<double> upper;

  static constexpr std::string_view type_name = "CoefficientSetting";
  static constexpr auto fields() {
    using S = CoefficientSetting;
    return std::tuple{
        field("name", &S::name, "theta<i>.a<k>, theta<i>.b<k> or tau."),
        field("fixed", &S::fixed, Finite{}, "Held value, or None (free)."),
        field("lower", &S::lower, Finite{}, "Lower bound, or None."),
        field("upper", &S::upper, Finite{}, "Upper bound, or None."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// Constraints on a model's coefficients (decision 0057): held values and bounds by name, and
/// a known static gain.
struct CoefficientConstraints {
  /// Held values and bounds of named coefficients (each name at most once).
  std::vector<CoefficientSetting> coefficients;
  /// The known static gain G(0) = sum_i B_i(0) / A_i(0), held to rounding: the b0 of the last
  /// submodel whose b0 is neither held nor bounded is solved from it. None: free.
  std::optional<double> dc_gain;

  bool empty() const { return coefficients.empty() && !dc_gain; }

  static constexpr std::string_view type_name = "CoefficientConstraints";
  static constexpr auto fields() {
    using C = CoefficientConstraints;
    return std::tuple{
        field("coefficients", &C::coefficients,
              "CoefficientSetting of named coefficients: held values and bounds."),
        field("dc_gain", &C::dc_gain, Finite{}, "Known static gain G(0), or None."),
    };
  }
  void validate() const { validate_fields(*this); }
};

struct OutputErrorPolishOptions {
  /// Estimate the input delay as a continuous parameter (>= 0) from the start's delay.
  bool estimate_delay = true;
  /// Estimate the initial state (the free responses' coefficients, by variable projection);
  /// false: the record starts from rest.
  bool estimate_initial_state = false;
  /// Keep every denominator stable: a start with poles in the right half-plane has them
  /// mirrored into the left first, and steps that leave the stable region are refused.
  bool keep_stable = true;
  /// Levenberg–Marquardt iterations.
  int max_iterations = 100;

  static constexpr std::string_view type_name = "OutputErrorPolishOptions";
  static constexpr auto fields() {
    using O = OutputErrorPolishOptions;
    return std::tuple{
        field("estimate_delay", &O::estimate_delay,
              "Estimate the input delay as a continuous parameter."),
        field("estimate_initial_state", &O::estimate_initial_state,
              "Estimate the initial state by variable projection."),
        field("keep_stable", &O::keep_stable,
              "Mirror unstable start poles and refuse steps that leave the stable region."),
        field("max_iterations", &O::max_iterations, AtLeast{1}, "Levenberg-Marquardt iterations."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// The polished model beside the criterion it minimised.
struct OutputErrorPolishResult : Outcome {
  explicit OutputErrorPolishResult(AdditiveModel polished)
      : model(std::move(polished)), transfer_function(model.to_transfer_function()) {}

  /// "output error", or "prediction error" with a noise model.
  std::string criterion;
  /// The polished model, in the start's structure, with the polished input delay [s].
  AdditiveModel model;
  TransferFunction transfer_function;
  /// beta in AdditiveModel::parameters() layout, then tau [s] when estimated, then the noise
  /// model's d_1..d_p, c_1..c_q.
  Eigen::VectorXd parameters;
  /// Gauss–Newton covariance sigma^2 (J^T J)^{-1} of `parameters` (sigma^2 the residual sum of
  /// squares over N - parameters); NaN when J is singular.
  Eigen::MatrixXd covariance;
  Eigen::VectorXd standard_errors;
  double delay_standard_error = 0.0;  ///< of tau [s]; 0 when the delay was held
  /// With estimate_initial_state: the coefficients of the free responses (estimation's
  /// free_responses basis, submodel by submodel); empty otherwise.
  Eigen::VectorXd initial_state;
  /// The polished noise model (with a start noise model): coefficients, innovation variance,
  /// their covariance block and the spectrum.
  std::optional<ArmaModel> noise_model;
  double start_cost = 0.0;         ///< criterion (sum of squares / N) at the start
  double cost = 0.0;               ///< and at the polished model; never above start_cost
  double start_fit_percent = 0.0;  ///< output-error fit of the start (with its initial state)
  double fit_percent = 0.0;        ///< and of the polished model
  /// keep_stable mirrored a start pole or refused a step: the stability constraint acted.
  bool stability_constraint_active = false;
  /// Parameters not free: held at a given value, or solved from the known DC gain.
  std::vector<std::string> held_parameters;
  /// Free parameters that end at one of their bounds.
  std::vector<std::string> active_bounds;
  Verdict verdict;

  static constexpr std::string_view type_name = "OutputErrorPolishResult";
  static constexpr auto fields() {
    using R = OutputErrorPolishResult;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("criterion", &R::criterion, "output error, or prediction error."),
            field("model", &R::model, "The polished model (input delay in seconds)."),
            field("transfer_function", &R::transfer_function, "The same, unfactored."),
            field("parameters", &R::parameters, "beta, then tau [s] if estimated, then D, C."),
            field("covariance", &R::covariance, "sigma^2 (J^T J)^-1 of the parameters."),
            field("standard_errors", &R::standard_errors, "sqrt of its diagonal."),
            field("delay_standard_error", &R::delay_standard_error, "Of tau [s]."),
            field("initial_state", &R::initial_state,
                  "Free-response coefficients with estimate_initial_state."),
            field("noise_model", &R::noise_model, "The polished ARMA noise model, or none."),
            field("start_cost", &R::start_cost, "Criterion / N at the start."),
            field("cost", &R::cost, "Criterion / N at the polished model."),
            field("start_fit_percent", &R::start_fit_percent, "Output-error fit of the start."),
            field("fit_percent", &R::fit_percent, "Output-error fit of the polished model."),
            field("stability_constraint_active", &R::stability_constraint_active,
                  "The stability constraint mirrored a start pole or refused a step."),
            field("held_parameters", &R::held_parameters,
                  "Held, or solved from the known DC gain."),
            field("active_bounds", &R::active_bounds, "Free parameters at a bound."),
            field("verdict", &R::verdict, "Quality verdict."),
        });
  }
};

/// Polishes `start` (e.g. a refined IV estimate) on `data` (open loop, SISO, no reference),
/// with `noise` (an ARMA model of the start's output error) the prediction error. The
/// constraints' held values, bounds and DC gain are imposed on the start first; the criterion
/// never increases from that start's. Throws InvalidArgument for bad options and constraints
/// (validate_constraints), data with a
/// reference, a non-finite start, or fewer than 10 samples per free parameter; how the
/// minimisation ended is the result's termination and verdict.
/// Throws InvalidArgument naming the first constraint that does not go with `model`: a name it
/// does not have (the message lists them), a name given twice, tau when the delay is held
/// (`delay_free` false), a held value outside its bounds or lower above upper, a known DC gain
/// with an integrator in the model (its static gain is infinite), every b0 held to a sum other
/// than the DC gain, or no b0 left free and unbounded to carry it.
void validate_constraints(const AdditiveModel& model, const CoefficientConstraints& constraints,
                          bool delay_free);

/// The coefficients a constraint holds, as (index in beta, value): the held values, and the
/// DC gain's carrier b0 when no other b0 is free (one submodel: b0 = G(0)). Coefficients a
/// constraint couples (the carrier of several free b0) are not listed. Validates first.
std::vector<std::pair<Eigen::Index, double>> held_coefficients(
    const AdditiveModel& model, const CoefficientConstraints& constraints);

/// The bounds a constraint puts on coefficients of beta that no constraint holds, as (index in
/// beta, lower, upper), a side without a bound infinite (decision 0058: the refined IV
/// iteration keeps them). The bounds of tau are the polish's own. Validates first.
std::vector<std::tuple<Eigen::Index, double, double>> bounded_coefficients(
    const AdditiveModel& model, const CoefficientConstraints& constraints);

/// Why polish_output_error would refuse to start from `start` on `data` (a record with a
/// reference, a non-finite start, fewer than 10 samples per free parameter, a start whose output
/// is not finite or, with held values, that is unstable), or none when it can start: its
/// refusals as a value, for a caller that polishes only what can be polished. Bad options and
/// constraints still throw InvalidArgument (validate_constraints).
std::optional<std::string> polish_start_refusal(
    const SampledData& data, const AdditiveModel& start,
    const std::optional<ArmaModel>& noise = std::nullopt,
    const OutputErrorPolishOptions& options = {}, const CoefficientConstraints& constraints = {});

OutputErrorPolishResult polish_output_error(const SampledData& data, const AdditiveModel& start,
                                            const std::optional<ArmaModel>& noise = std::nullopt,
                                            const OutputErrorPolishOptions& options = {},
                                            const CoefficientConstraints& constraints = {});

}  // namespace ctid
