// Judging a continuous-time model against sampled data, and checking data against the
// assumptions of the refined IV estimators (González et al., Assumptions 1 and 4): the
// model's exact ZOH response, fit %, persistency of excitation and the sampling-rate rule.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string_view>
#include <tuple>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/hold.h"
#include "ctid/core/mimo_data.h"
#include "ctid/core/mimo_model.h"
#include "ctid/core/sampled_data.h"

namespace ctid {

/// Exact sampled response (from rest) of the model to the input u with period h, held
/// between samples as `input_hold` says (a record's SampledData::input_hold()). The
/// model's input delay must be a whole number of samples (within 1e-9). Integrators and a
/// biproper submodel are allowed.
Eigen::VectorXd model_output(const AdditiveModel& model, const Eigen::VectorXd& input,
                             double sample_time, Hold input_hold = Hold::zero_order_hold);

/// Sampled free responses of the model's realisation (TransferFunction::to_state_space of each
/// submodel b / (s^integrators a), discretised exactly with period h): column j, row k is
/// C Phi^k e_j, the output k samples after starting from state e_j with zero input. An
/// additive model stacks its submodels' states (a static submodel has none). The response
/// from an initial state x0 is model_output(...) + free_responses(...) x0. An input delay adds
/// no states: the delayed input before the first sample is zero, as in model_output.
Eigen::MatrixXd free_responses(const AdditiveModel& model, int samples, double sample_time);

/// 100 (1 - ||y - y_model|| / ||y - mean(y)||); 100 is a perfect fit. Sizes must agree.
double fit_percent(const Eigen::VectorXd& measured, const Eigen::VectorXd& modelled);

/// Where the simulation of `ctid validate` starts: from rest, or from the initial state that
/// fits the scored window best (least squares, like MATLAB's `compare` with estimated initial
/// conditions). A record cut out of a steady-state experiment starts mid-motion; from rest
/// its first samples carry the model's transient, which a lightly damped model keeps long.
enum class InitialState { zero, estimate };

inline constexpr std::array<Enumerator<InitialState>, 2> initial_state_enumerators{{
    {InitialState::zero, "zero", "Simulate from rest."},
    {InitialState::estimate, "estimate",
     "Start from the least-squares initial state over the scored window."},
}};
constexpr std::span<const Enumerator<InitialState>> enumerators(InitialState) {
  return initial_state_enumerators;
}

/// How validate_model simulates and scores. The model is always simulated from the record's
/// first sample; the window only chooses the samples that are scored (and, with
/// InitialState::estimate, fitted by the initial state). Window bounds are times on the
/// record's own axis (start_time + k h) in seconds, inclusive; empty: the record's ends.
struct ValidationOptions {
  InitialState initial_state = InitialState::zero;
  std::optional<double> window_start;  ///< [s]; empty: the first sample
  std::optional<double> window_end;    ///< [s]; empty: the last sample
  int max_lag = 20;

  static constexpr std::string_view type_name = "ValidationOptions";
  static constexpr auto fields() {
    using O = ValidationOptions;
    return std::tuple{
        field("initial_state", &O::initial_state,
              "Simulate from rest (zero) or from the least-squares initial state (estimate)."),
        field("window_start", &O::window_start, Finite{},
              "First scored time [s] on the record's axis; None: the first sample."),
        field("window_end", &O::window_end, Finite{},
              "Last scored time [s] on the record's axis; None: the last sample."),
        field("max_lag", &O::max_lag, AtLeast{1}, "Largest correlation lag tested."),
    };
  }
  void validate() const { validate_fields(*this); }
  void check_relations(const std::string& path) const;
};

/// Residual statistics of a model on data (for `ctid validate`). Correlations are normalised
/// (means removed): r_ee(k) = sum e(t+k) e(t) / sum e(t)^2 at lags 1..max_lag, and
/// r_eu(k) = sum e(t+k) u(t) / sqrt(sum e^2 sum u^2) at lags -max_lag..max_lag; both are judged
/// against the 99 % band 2.58/sqrt(N) of a white residual independent of the input. All
/// statistics are over the scored window (N its samples); fit_percent and the residual use
/// the simulation `initial_state` names, and both fits are given beside each other.
struct ValidationReport {
  double fit_percent = 0.0;
  InitialState initial_state = InitialState::zero;  ///< the simulation the statistics use
  double fit_zero_state = 0.0;                      ///< fit % on the window, simulated from rest
  double fit_estimated_state = 0.0;  ///< fit % on the window, from the estimated state
  double window_start = 0.0;         ///< time of the first scored sample [s]
  double window_end = 0.0;           ///< time of the last scored sample [s]
  int window_samples = 0;
  int states = 0;                  ///< dimension of the initial state (free_responses columns)
  int initial_state_rank = 0;      ///< free responses numerically independent on the window
  double free_response_rms = 0.0;  ///< rms on the window of the estimated state's free response
  double mean_squared_error = 0.0;
  double residual_mean = 0.0;
  double residual_std = 0.0;
  int max_lag = 0;                           ///< lags used: min(max_lag asked, N - 1)
  Eigen::VectorXd residual_autocorrelation;  ///< r_ee(1..max_lag)
  Eigen::VectorXd cross_correlation;         ///< r_eu(-max_lag..max_lag)
  double max_residual_autocorrelation = 0.0;
  double max_cross_correlation = 0.0;
  double whiteness_bound = 0.0;  ///< 2.58/sqrt(N)
  bool residual_white() const { return max_residual_autocorrelation <= whiteness_bound; }
  bool residual_uncorrelated_with_input() const { return max_cross_correlation <= whiteness_bound; }

  static constexpr std::string_view type_name = "ValidationReport";
  static constexpr auto fields() {
    using S = ValidationReport;
    return std::tuple{
        field("fit_percent", &S::fit_percent,
              "100 (1 - ||y - y_model|| / ||y - mean(y)||) on the window, with initial_state."),
        field("initial_state", &S::initial_state, "The simulation the statistics use."),
        field("fit_zero_state", &S::fit_zero_state, "Fit % on the window from rest."),
        field("fit_estimated_state", &S::fit_estimated_state,
              "Fit % on the window from the least-squares initial state."),
        field("window_start", &S::window_start, "Time of the first scored sample [s]."),
        field("window_end", &S::window_end, "Time of the last scored sample [s]."),
        field("window_samples", &S::window_samples, "Samples scored."),
        field("states", &S::states, "Dimension of the model's initial state."),
        field("initial_state_rank", &S::initial_state_rank,
              "Free responses numerically independent on the window (the rank solved)."),
        field("free_response_rms", &S::free_response_rms,
              "Rms on the window of the estimated initial state's free response."),
        field("mean_squared_error", &S::mean_squared_error, "Mean squared residual."),
        field("residual_mean", &S::residual_mean, "Mean of the residual."),
        field("residual_std", &S::residual_std, "Standard deviation of the residual."),
        field("max_lag", &S::max_lag, "Lags used: min(max_lag asked, N - 1)."),
        field("residual_autocorrelation", &S::residual_autocorrelation,
              "Normalised residual autocorrelation r_ee at lags 1..max_lag."),
        field("cross_correlation", &S::cross_correlation,
              "Normalised residual-input cross-correlation r_eu at lags -max_lag..max_lag."),
        field("max_residual_autocorrelation", &S::max_residual_autocorrelation,
              "Largest |r_ee| at lags 1..max_lag."),
        field("max_cross_correlation", &S::max_cross_correlation,
              "Largest |r_eu| at lags -max_lag..max_lag."),
        field("whiteness_bound", &S::whiteness_bound, "The 99 % band 2.58/sqrt(N)."),
    };
  }
};
/// max_lag >= 1; 20 by default. From rest, the whole record (estimated-state fit also given).
ValidationReport validate_model(const AdditiveModel& model, const SampledData& data,
                                int max_lag = 20);
/// The model simulated from the record's first sample with the measured input (exact ZOH),
/// scored on options' window. The initial state is estimated by linear least squares of
/// y - y_rest on the free responses over the window: columns scaled to unit norm over the
/// whole record, solved by SVD with singular values below 1e-6 of the largest dropped: a
/// state direction whose free response the window barely sees (a mode that has died out
/// before the window, or nearly cancelled modes) is not fitted to the window's noise and
/// extrapolated backwards; initial_state_rank counts what was kept. A window outside the record
/// or holding fewer than 2 samples is an InvalidArgument naming the window and the record.
ValidationReport validate_model(const AdditiveModel& model, const SampledData& data,
                                const ValidationOptions& options);

/// The output validate_model scores, over the whole record: from rest, plus with
/// InitialState::estimate the free response of the state fitted on the window.
Eigen::VectorXd validation_output(const AdditiveModel& model, const SampledData& data,
                                  const ValidationOptions& options);

/// The same statistics for any model whose simulated output on `data` is `modelled` (e.g. a
/// closed loop with delayed feedback). max_lag >= 1; sizes must agree.
ValidationReport residual_report(const SampledData& data, const Eigen::VectorXd& modelled,
                                 int max_lag = 20);

/// Validation of a model with several inputs and outputs, output by output: output j's
/// simulation is sum_k G_jk u_k from the record's first sample, and with InitialState::estimate
/// plus the free response of channel (j, 1)'s realisation (every submodel's states) fitted
/// on the window as validate_model does for one channel. Correlations as in ValidationReport,
/// the cross-correlation the largest over the inputs.
struct MimoValidationReport {
  InitialState initial_state = InitialState::zero;  ///< the simulation fit_percent uses
  Eigen::VectorXd fit_percent;                      ///< per output, with initial_state
  Eigen::VectorXd fit_zero_state;                   ///< per output, from rest
  Eigen::VectorXd fit_estimated_state;              ///< per output, from the fitted state
  Eigen::VectorXd max_residual_autocorrelation;     ///< per output, largest |r_ee|
  Eigen::VectorXd max_cross_correlation;            ///< per output, largest |r_eu| over inputs
  double whiteness_bound = 0.0;                     ///< the 99 % band 2.58/sqrt(N)
  double window_start = 0.0;                        ///< time of the first scored sample [s]
  double window_end = 0.0;                          ///< time of the last scored sample [s]
  int window_samples = 0;

  static constexpr std::string_view type_name = "MimoValidationReport";
  static constexpr auto fields() {
    using S = MimoValidationReport;
    return std::tuple{
        field("initial_state", &S::initial_state, "The simulation fit_percent uses."),
        field("fit_percent", &S::fit_percent, "Per output: fit % with initial_state."),
        field("fit_zero_state", &S::fit_zero_state, "Per output: fit % from rest."),
        field("fit_estimated_state", &S::fit_estimated_state,
              "Per output: fit % from the least-squares initial state."),
        field("max_residual_autocorrelation", &S::max_residual_autocorrelation,
              "Per output: largest |r_ee| at lags 1..max_lag."),
        field("max_cross_correlation", &S::max_cross_correlation,
              "Per output: largest |r_eu| over the inputs and lags."),
        field("whiteness_bound", &S::whiteness_bound, "The 99 % band 2.58/sqrt(N)."),
        field("window_start", &S::window_start, "Time of the first scored sample [s]."),
        field("window_end", &S::window_end, "Time of the last scored sample [s]."),
        field("window_samples", &S::window_samples, "Samples scored."),
    };
  }
};

/// Throws InvalidArgument when the model's channel counts differ from the record's, or for a
/// window as validate_model(AdditiveModel) does.
MimoValidationReport validate_model(const MimoAdditiveModel& model, const MimoData& data,
                                    const ValidationOptions& options = {});

/// Largest n <= max_order for which the sample matrix sum_k phi_k phi_k' of the windows
/// phi_k = [x_k, x_{k-d}, ..., x_{k-(n-1)d}] is numerically non-singular (smallest over
/// largest eigenvalue above `tolerance`) for some lag spacing d in {1, 2, 3, 4, 6, 8, 12, 16}:
/// the order of persistency of excitation seen in the record. A constant gives 1, one
/// sinusoid 2, white noise and band-limited rich signals (multisines) max_order.
int persistent_excitation_order(const Eigen::VectorXd& x, int max_order, double tolerance = 1e-9);

/// Largest |imaginary part| of the model's poles in rad/s (0 for real poles).
double largest_pole_frequency(const AdditiveModel& model);

}  // namespace ctid
