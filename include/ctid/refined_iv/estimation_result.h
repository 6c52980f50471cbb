// What a refined instrumental-variable estimate returns (González et al., Sections 3-5): the
// model in its additive and unfactored views, beta = [theta_1; ...; theta_K] (eq. 3 order),
// why the iteration (29) stopped, the Lemma 4.4 check, the asymptotic covariance (Theorem 3.2)
// with standard errors of modal parameters, and the checks of Assumptions 1 and 4.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/transfer_function.h"
#include "ctid/estimation/arma.h"
#include "ctid/estimation/termination.h"
#include "ctid/estimation/verdict.h"

namespace ctid {

/// Natural frequency, damping ratio and modal gain of one second-order mode with their
/// delta-method standard errors (NaN where no covariance is available).
struct ModalEstimate {
  int submodel = 0;  ///< index in the model's additive view
  ModalParameters value;
  ModalParameters standard_error;

  static constexpr std::string_view type_name = "ModalEstimate";
  static constexpr auto fields() {
    using S = ModalEstimate;
    return std::tuple{
        field("submodel", &S::submodel, "Index in the model's additive view."),
        field("value", &S::value, "ModalParameters of the mode."),
        field("standard_error", &S::standard_error,
              "Delta-method standard errors (NaN where no covariance is available)."),
    };
  }
};

/// One iteration of (29), recorded when RefinedIvOptions::record_history is set.
struct IterationRecord {
  int iteration = 0;
  Eigen::VectorXd parameters;      ///< beta after this iteration
  double relative_change = 0.0;    ///< ||beta_{j+1} - beta_j|| / ||beta_j||
  double off_diagonal_norm = 0.0;  ///< Lemma 4.4: ||off-block-diagonal part|| / ||beta||

  static constexpr std::string_view type_name = "IterationRecord";
  static constexpr auto fields() {
    using S = IterationRecord;
    return std::tuple{
        field("iteration", &S::iteration, "Index of the iteration."),
        field("parameters", &S::parameters, "beta after this iteration."),
        field("relative_change", &S::relative_change, "||beta_{j+1} - beta_j|| / ||beta_j||."),
        field("off_diagonal_norm", &S::off_diagonal_norm,
              "Lemma 4.4: ||off-block-diagonal part|| / ||beta||."),
    };
  }
};

/// Checks of the paper's assumptions on the data (Assumptions 1 and 4).
struct DataChecks {
  /// Largest order (up to the required one) at which the input (open loop) or reference
  /// (closed loop) is persistently exciting.
  int excitation_order = 0;
  /// 2 n open loop, 2 n + n_c closed loop (n = total number of poles).
  int excitation_order_required = 0;
  bool persistently_exciting = true;
  /// Largest |imaginary part| of the estimated poles [rad/s] against the Nyquist
  /// frequency pi/h: Assumption 4 asks for the former to be smaller.
  double largest_pole_frequency = 0.0;
  double nyquist_frequency = 0.0;
  bool sampling_rate_ok = true;
  /// One sentence per failed check.
  std::vector<std::string> warnings;

  static constexpr std::string_view type_name = "DataChecks";
  static constexpr auto fields() {
    using S = DataChecks;
    return std::tuple{
        field("excitation_order", &S::excitation_order,
              "Largest order of persistent excitation seen (up to the required one)."),
        field("excitation_order_required", &S::excitation_order_required,
              "2 n open loop, 2 n + n_c closed loop."),
        field("persistently_exciting", &S::persistently_exciting, "Assumption 1 met."),
        field("largest_pole_frequency", &S::largest_pole_frequency,
              "Largest |imaginary part| of the estimated poles [rad/s]."),
        field("nyquist_frequency", &S::nyquist_frequency, "pi/h [rad/s]."),
        field("sampling_rate_ok", &S::sampling_rate_ok, "Assumption 4 met."),
        field("warnings", &S::warnings, "One sentence per failed check."),
    };
  }
};

/// Derives termination, message and iterations (the iteration count of (29)) from Outcome.
struct EstimationResult : Outcome {
  EstimationResult(AdditiveModel estimated, TransferFunction unfactored)
      : model(std::move(estimated)), transfer_function(std::move(unfactored)) {}

  /// The estimated parameterisation: K submodels for the additive estimators, one unfactored
  /// submodel B/(p^l A) for SRIVC/CLSRIVC. Input delay in seconds.
  AdditiveModel model;
  /// The same model as one transfer function (the unfactored view).
  TransferFunction transfer_function;
  /// Partial-fraction view of an unfactored estimate (second-order modes, an integrator
  /// submodel); equals `model` for the additive estimators; empty if it cannot be formed
  /// (e.g. repeated poles).
  std::optional<AdditiveModel> additive_view;

  Eigen::VectorXd parameters;        ///< beta, stacked theta_i (eq. 3)
  Eigen::MatrixXd covariance;        ///< of `parameters` (already divided by N); empty if unknown
  Eigen::VectorXd standard_errors;   ///< sqrt of its diagonal
  std::vector<ModalEstimate> modes;  ///< every second-order mode of `additive_view`
  /// RefinedIvOptions::initial_conditions = estimate: per submodel (in `model`), the value
  /// and first n_i + l_i - 1 derivatives at the first sample of its estimated free response
  /// (the part of its output not driven by the recorded input). Empty with `zero`.
  Eigen::VectorXd initial_conditions;

  double relative_change = 0.0;    ///< at the last iteration
  double off_diagonal_norm = 0.0;  ///< Lemma 4.4 at the last iteration (0 for K = 1)
  int unstable_reflections = 0;    ///< denominators reflected into the left half-plane
  int sensitivity_fallbacks = 0;   ///< closed loop: S_uo r reused because the loop was unstable
  int step_halvings = 0;           ///< steps of (29) halved by RefinedIvOptions::step_control

  int input_delay_samples = 0;        ///< whole samples of the input delay
  double input_delay_fraction = 0.0;  ///< and its fraction of a sample: tau = (d + f) h
  /// Standard error of the delay tau [s] when it was estimated as a continuous parameter
  /// (IdentificationOptions::delay_range); 0 when it was given or chosen from whole samples.
  double delay_standard_error = 0.0;
  double noise_variance = 0.0;      ///< sum of squared residuals / (N - parameters)
  double mean_squared_error = 0.0;  ///< sum of squared residuals / N (output error)
  double fit_percent = 0.0;         ///< 100 (1 - ||y - y_model|| / ||y - mean(y)||)
  /// The same fit of the start the iteration began from (NaN if it could not be formed).
  double start_fit_percent = std::numeric_limits<double>::quiet_NaN();
  /// Closed loop: 100 (1 - ||y - G S_uo(G) r|| / ||y - mean(y)||), the fit of the output the
  /// model gives from the reference alone through the known controller, the fit that judges a
  /// closed-loop model (decision 0028); NaN in open loop or when the controller does not
  /// stabilise the model.
  double closed_loop_fit_percent = std::numeric_limits<double>::quiet_NaN();
  /// The same fit of the start (NaN in open loop or if it could not be formed).
  double start_closed_loop_fit_percent = std::numeric_limits<double>::quiet_NaN();
  /// Reciprocal condition of the scaled instrument-regressor matrix of (29) at the last
  /// iteration (NaN if none was formed).
  double reciprocal_condition = std::numeric_limits<double>::quiet_NaN();
  /// RefinedIvOptions::noise_model: the ARMA noise model C/D of the output error y - G u at
  /// the estimate, with its standard errors and spectrum; none for SRIVC and CLSRIVC.
  std::optional<ArmaModel> noise_model;
  /// Is the model worth using (estimation/verdict.h): checked after every estimate.
  Verdict verdict;

  DataChecks checks;
  std::vector<IterationRecord> history;

  static constexpr std::string_view type_name = "EstimationResult";
  static constexpr auto fields() {
    using S = EstimationResult;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("model", &S::model, "The estimated AdditiveModel (input delay in seconds)."),
            field("transfer_function", &S::transfer_function, "The same model unfactored."),
            field("additive_view", &S::additive_view,
                  "Partial-fraction view of an unfactored estimate, or none."),
            field("parameters", &S::parameters, "beta, stacked theta_i (eq. 3)."),
            field("covariance", &S::covariance,
                  "Covariance of beta (already divided by N); empty if unknown."),
            field("standard_errors", &S::standard_errors, "sqrt of its diagonal."),
            field("modes", &S::modes, "ModalEstimate of every second-order mode."),
            field("initial_conditions", &S::initial_conditions,
                  "Per submodel, the estimated free response and its first n_i + l_i - 1 "
                  "derivatives at the first sample; empty unless estimated."),
            field("relative_change", &S::relative_change, "At the last iteration."),
            field("off_diagonal_norm", &S::off_diagonal_norm,
                  "Lemma 4.4 at the last iteration (0 for K = 1)."),
            field("unstable_reflections", &S::unstable_reflections,
                  "Denominators reflected into the left half-plane."),
            field("sensitivity_fallbacks", &S::sensitivity_fallbacks,
                  "Closed loop: S_uo r reused because the loop was unstable."),
            field("step_halvings", &S::step_halvings,
                  "Steps of (29) halved by RefinedIvOptions.step_control."),
            field("input_delay_samples", &S::input_delay_samples,
                  "Whole samples of the input delay."),
            field("input_delay_fraction", &S::input_delay_fraction,
                  "Fraction of a sample added to input_delay_samples (tau = (d + f) h)."),
            field("delay_standard_error", &S::delay_standard_error,
                  "Standard error of an estimated continuous delay [s]; 0 when given."),
            field("noise_variance", &S::noise_variance,
                  "Sum of squared residuals / (N - parameters)."),
            field("mean_squared_error", &S::mean_squared_error,
                  "Sum of squared residuals / N (output error)."),
            field("fit_percent", &S::fit_percent, "100 (1 - ||y - y_model|| / ||y - mean(y)||)."),
            field("start_fit_percent", &S::start_fit_percent,
                  "The same fit of the start (NaN if it could not be formed)."),
            field("closed_loop_fit_percent", &S::closed_loop_fit_percent,
                  "Closed loop: 100 (1 - ||y - G S_uo r|| / ||y - mean(y)||), the model's output "
                  "from r through the controller; NaN in open loop or if the loop is unstable."),
            field("start_closed_loop_fit_percent", &S::start_closed_loop_fit_percent,
                  "The same closed-loop fit of the start (NaN in open loop or if unstable)."),
            field("reciprocal_condition", &S::reciprocal_condition,
                  "Reciprocal condition of the scaled IV matrix of (29) at the last iteration."),
            field("noise_model", &S::noise_model,
                  "ArmaModel of the noise (RIVC, CLRIVC), or none (SRIVC, CLSRIVC)."),
            field("verdict", &S::verdict,
                  "Verdict: usable, reasons, advice (docs/decisions/0007-quality-verdict.md)."),
            field("checks", &S::checks, "DataChecks of Assumptions 1 and 4."),
            field("history", &S::history,
                  "IterationRecord per iteration (RefinedIvOptions.record_history)."),
        });
  }
};

}  // namespace ctid
