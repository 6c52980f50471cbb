// Step and impulse responses of continuous-time models, exact at every time asked (state space
// and the matrix exponential, never a numerical integration), with the step response's
// characteristics (DC gain, 10-90 % rise time, settling time, overshoot, undershoot, peak time)
// and, given the covariance of the model's parameters, their standard errors and a pointwise
// band by the delta method (docs/time-responses.md).
#pragma once

#include <array>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/transfer_function.h"

namespace ctid {

enum class ResponseKind { step, impulse };

inline constexpr std::array<Enumerator<ResponseKind>, 2> response_kind_enumerators{{
    {ResponseKind::step, "step", "Response to a unit step applied at t = 0."},
    {ResponseKind::impulse, "impulse",
     "Response to a unit Dirac impulse at t = 0 (the Dirac part of a biproper model left out)."},
}};
constexpr std::span<const Enumerator<ResponseKind>> enumerators(ResponseKind) {
  return response_kind_enumerators;
}

/// The most points a time response is computed on; more is refused before anything is
/// allocated.
inline constexpr int kMaxTimeResponsePoints = 1'000'000;

/// The time grid t_k = k h, k = 0 ... points - 1, from 0 to final_time, and what the
/// characteristics and the band use.
struct TimeResponseOptions {
  ResponseKind kind = ResponseKind::step;
  /// Last time [s]; empty: 1.5 times the settling time of a stable model with a DC gain,
  /// otherwise the delay plus 10 time constants of the slowest pole (10 s if all are at 0).
  std::optional<double> final_time;
  /// Points of the grid, both ends included; ignored when sample_time is given.
  int points = 1000;
  /// Spacing of the grid [s]; empty: final_time / (points - 1). The grid stops at the last
  /// multiple of it not after final_time.
  std::optional<double> sample_time;
  /// Half-width of the settling band as a fraction of the final value (0.02: 2 %).
  double settling_band = 0.02;
  /// Two-sided coverage of the pointwise band lower/upper for a Gaussian estimate.
  double confidence = 0.95;

  static constexpr std::string_view type_name = "TimeResponseOptions";
  static constexpr auto fields() {
    using O = TimeResponseOptions;
    return std::tuple{
        field("kind", &O::kind, "step or impulse."),
        field("final_time", &O::final_time, Finite{GreaterThan{0}},
              "Last time [s]; None: from the model's settling time or slowest pole."),
        field("points", &O::points, Between{2, kMaxTimeResponsePoints, true, true},
              "Points of the grid 0 ... final_time (ignored when sample_time is given)."),
        field("sample_time", &O::sample_time, Finite{GreaterThan{0}},
              "Spacing of the grid [s]; None: final_time / (points - 1)."),
        field("settling_band", &O::settling_band, Between{0, 1},
              "Half-width of the settling band, a fraction of the final value (0.02: 2 %)."),
        field("confidence", &O::confidence, Between{0, 1},
              "Two-sided coverage of the pointwise band (Gaussian quantile)."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// A characteristic and its delta-method standard error; value NaN where the characteristic
/// is not defined, standard_error NaN where no covariance was given (or the value is not a
/// smooth function of the parameters there, e.g. an overshoot of 0).
struct ResponseEstimate {
  double value = std::numeric_limits<double>::quiet_NaN();
  double standard_error = std::numeric_limits<double>::quiet_NaN();

  static constexpr std::string_view type_name = "ResponseEstimate";
  static constexpr auto fields() {
    using S = ResponseEstimate;
    return std::tuple{
        field("value", &S::value, "The characteristic (NaN where it is not defined)."),
        field("standard_error", &S::standard_error,
              "Delta-method standard error (NaN without a covariance)."),
    };
  }
};

/// What the step response of a model shows (MATLAB's stepinfo). Times count from the step,
/// so settling and peak times include the input delay; percentages are of |final value|.
struct StepCharacteristics {
  /// Every pole has a negative real part (integrators and unstable poles: false).
  bool stable = false;
  /// B(0)/A(0) summed over the submodels; NaN with an integrator or an unstable pole.
  ResponseEstimate dc_gain;
  /// 10 % to 90 % of the final value, first crossings.
  ResponseEstimate rise_time;
  /// Last time the response is outside final value +- settling_band |final value|.
  ResponseEstimate settling_time;
  /// 100 (peak - final) / |final| (0 when the response never passes its final value).
  ResponseEstimate overshoot_percent;
  /// 100 (-trough) / |final| of a response that first goes the wrong way (non-minimum phase).
  ResponseEstimate undershoot_percent;
  /// Time of the peak (NaN without overshoot).
  ResponseEstimate peak_time;
  /// Why rise time, settling time and overshoot are not defined; empty when they are.
  std::string not_defined_reason;

  bool defined() const { return not_defined_reason.empty(); }

  static constexpr std::string_view type_name = "StepCharacteristics";
  static constexpr auto fields() {
    using S = StepCharacteristics;
    return std::tuple{
        field("stable", &S::stable, "Every pole has a negative real part."),
        field("dc_gain", &S::dc_gain, "B(0)/A(0); NaN with an integrator or an unstable pole."),
        field("rise_time", &S::rise_time, "10 % to 90 % of the final value [s]."),
        field("settling_time", &S::settling_time,
              "Last time outside the settling band, from the step [s]."),
        field("overshoot_percent", &S::overshoot_percent, "100 (peak - final) / |final|."),
        field("undershoot_percent", &S::undershoot_percent,
              "100 (-trough) / |final| of a response that first goes the wrong way."),
        field("peak_time", &S::peak_time, "Time of the peak, from the step [s]."),
        field("not_defined_reason", &S::not_defined_reason,
              "Why the characteristics are not defined; empty when they are."),
    };
  }
};

/// A step or impulse response on a grid with its pointwise band.
struct TimeResponse {
  ResponseKind kind = ResponseKind::step;
  Eigen::VectorXd time;    ///< t_k [s]
  Eigen::VectorXd output;  ///< y(t_k)
  /// Delta-method standard deviation of y(t_k); empty without a covariance.
  Eigen::VectorXd standard_deviation;
  Eigen::VectorXd lower;  ///< output - z standard_deviation; empty without a covariance
  Eigen::VectorXd upper;  ///< output + z standard_deviation
  double z = 0.0;         ///< the Gaussian quantile of options.confidence
  /// Impulse response of a biproper model: the weight D of the Dirac impulse at t = delay,
  /// which `output` leaves out; 0 otherwise.
  double dirac_weight = 0.0;
  /// Of the step response, whatever the kind.
  StepCharacteristics characteristics;

  static constexpr std::string_view type_name = "TimeResponse";
  static constexpr auto fields() {
    using S = TimeResponse;
    return std::tuple{
        field("kind", &S::kind, "step or impulse."),
        field("time", &S::time, "t_k [s]."),
        field("output", &S::output, "y(t_k)."),
        field("standard_deviation", &S::standard_deviation,
              "Delta-method standard deviation of y(t_k); empty without a covariance."),
        field("lower", &S::lower, "output - z standard_deviation; empty without a covariance."),
        field("upper", &S::upper, "output + z standard_deviation; empty without a covariance."),
        field("z", &S::z, "Gaussian quantile of the confidence asked."),
        field("dirac_weight", &S::dirac_weight,
              "Impulse of a biproper model: weight of the Dirac at t = delay, not in output."),
        field("characteristics", &S::characteristics, "StepCharacteristics of the model."),
    };
  }
};

/// y(t) at each of `times` (any order, any spacing; 0 before the input delay). Throws
/// InvalidArgument for an improper submodel or a non-finite time.
Eigen::VectorXd step_response(const AdditiveModel& model, const Eigen::VectorXd& times);
Eigen::VectorXd step_response(const TransferFunction& model, const Eigen::VectorXd& times);
/// The impulse response without the Dirac part D delta(t - delay) of a biproper model.
Eigen::VectorXd impulse_response(const AdditiveModel& model, const Eigen::VectorXd& times);
Eigen::VectorXd impulse_response(const TransferFunction& model, const Eigen::VectorXd& times);

/// The characteristics of the step response; with a covariance of model.parameters() (p x p,
/// or empty) their standard errors by central differences in the parameters, and with
/// delay_standard_error > 0 the delay counted as one more parameter, independent of the
/// others.
StepCharacteristics step_characteristics(const AdditiveModel& model,
                                         const Eigen::MatrixXd& covariance = {},
                                         double settling_band = 0.02,
                                         double delay_standard_error = 0.0);

/// The response of options.kind on the options' grid, its band (from `covariance` as above)
/// and the step characteristics. Throws InvalidArgument for bad options, a covariance of the
/// wrong size, or a grid of more than kMaxTimeResponsePoints points.
TimeResponse time_response(const AdditiveModel& model, const Eigen::MatrixXd& covariance = {},
                           const TimeResponseOptions& options = {},
                           double delay_standard_error = 0.0);

/// z with P(|N(0,1)| <= z) = confidence, 0 < confidence < 1.
double two_sided_normal_quantile(double confidence);

}  // namespace ctid
