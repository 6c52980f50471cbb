// Python bindings of the estimation layer: the refined IV estimators (SRIVC, CLSRIVC, additive
// open and closed loop), delay scans, automatic initialisation, covariance, validation, and the
// delayed-feedback step-1 regressions and solvers. Options are keyword arguments.
#include "common.h"
#include "ctid/estimation/additive_srivc.h"
#include "ctid/estimation/clsrivc.h"
#include "ctid/estimation/covariance.h"
#include "ctid/estimation/delay_scan.h"
#include "ctid/estimation/estimation_result.h"
#include "ctid/estimation/feedback_least_squares.h"
#include "ctid/estimation/feedback_refinement.h"
#include "ctid/estimation/feedback_regressors.h"
#include "ctid/estimation/feedback_separation.h"
#include "ctid/estimation/feedback_validation.h"
#include "ctid/estimation/initialization.h"
#include "ctid/estimation/mode_relocation.h"
#include "ctid/estimation/refined_iv_options.h"
#include "ctid/estimation/srivc.h"
#include "ctid/estimation/validation.h"

namespace ctid::python {

namespace {

RefinedIvOptions refined(const char* name, const std::optional<RefinedIvOptions>& options,
                         const py::kwargs& kwargs) {
  return options_from<RefinedIvOptions>(name, options, kwargs);
}

void bind_results(py::module_& m) {
  py::enum_<Termination>(m, "Termination", "Why a refined IV iteration stopped.")
      .value("converged", Termination::converged, "Relative change below the tolerance.")
      .value("iteration_limit", Termination::iteration_limit, "max_iterations reached.")
      .value("singular_equations", Termination::singular_equations, "Singular equations.")
      .value("non_finite", Termination::non_finite, "NaN/Inf appeared.")
      .value("closed_loop_unstable", Termination::closed_loop_unstable,
             "The controller does not stabilise the initial model.");
  py::class_<ModalEstimate>(m, "ModalEstimate", "A mode's parameters with standard errors.")
      .def_readonly("submodel", &ModalEstimate::submodel, "Index in the additive view.")
      .def_readonly("value", &ModalEstimate::value, "ModalParameters.")
      .def_readonly("standard_error", &ModalEstimate::standard_error,
                    "Delta-method standard errors (ModalParameters).");
  py::class_<IterationRecord>(m, "IterationRecord", "One iteration of eq. (29).")
      .def_readonly("iteration", &IterationRecord::iteration, "Index.")
      .def_readonly("parameters", &IterationRecord::parameters, "beta after it.")
      .def_readonly("relative_change", &IterationRecord::relative_change, "Relative change.")
      .def_readonly("off_diagonal_norm", &IterationRecord::off_diagonal_norm, "Lemma 4.4.");
  py::class_<DataChecks>(m, "DataChecks", "Checks of Assumptions 1 and 4 on the data.")
      .def_readonly("excitation_order", &DataChecks::excitation_order, "PE order seen.")
      .def_readonly("excitation_order_required", &DataChecks::excitation_order_required,
                    "PE order needed.")
      .def_readonly("persistently_exciting", &DataChecks::persistently_exciting, "Met?")
      .def_readonly("largest_pole_frequency", &DataChecks::largest_pole_frequency,
                    "Largest |Im pole| [rad/s].")
      .def_readonly("nyquist_frequency", &DataChecks::nyquist_frequency, "pi/h [rad/s].")
      .def_readonly("sampling_rate_ok", &DataChecks::sampling_rate_ok, "Assumption 4 met?")
      .def_readonly("warnings", &DataChecks::warnings, "One sentence per failed check.");
  py::class_<EstimationResult>(m, "EstimationResult",
                               "Outcome of a refined IV estimator: model, parameters, "
                               "covariance, termination, diagnostics.")
      .def_readonly("model", &EstimationResult::model, "AdditiveModel (estimated structure).")
      .def_readonly("transfer_function", &EstimationResult::transfer_function,
                    "The unfactored view.")
      .def_readonly("additive_view", &EstimationResult::additive_view,
                    "Partial-fraction view or None.")
      .def_readonly("parameters", &EstimationResult::parameters, "beta.")
      .def_readonly("covariance", &EstimationResult::covariance, "Covariance of beta.")
      .def_readonly("standard_errors", &EstimationResult::standard_errors, "sqrt(diag).")
      .def_readonly("modes", &EstimationResult::modes, "ModalEstimate per mode.")
      .def_readonly("termination", &EstimationResult::termination, "Termination reason.")
      .def_readonly("message", &EstimationResult::message, "One sentence.")
      .def_readonly("iterations", &EstimationResult::iterations, "Iterations run.")
      .def_readonly("relative_change", &EstimationResult::relative_change, "Last change.")
      .def_readonly("off_diagonal_norm", &EstimationResult::off_diagonal_norm, "Lemma 4.4.")
      .def_readonly("unstable_reflections", &EstimationResult::unstable_reflections,
                    "Reflected denominators.")
      .def_readonly("sensitivity_fallbacks", &EstimationResult::sensitivity_fallbacks,
                    "Closed loop S_uo fallbacks.")
      .def_readonly("input_delay", &EstimationResult::input_delay, "Delay [samples].")
      .def_readonly("noise_variance", &EstimationResult::noise_variance, "sigma^2 estimate.")
      .def_readonly("mean_squared_error", &EstimationResult::mean_squared_error,
                    "Output-error MSE.")
      .def_readonly("fit_percent", &EstimationResult::fit_percent, "NRMSE fit %.")
      .def_readonly("checks", &EstimationResult::checks, "DataChecks.")
      .def_readonly("history", &EstimationResult::history, "IterationRecord list.")
      .def("converged", &EstimationResult::converged, "termination == converged.")
      .def("__repr__", [](const EstimationResult& r) {
        return "EstimationResult(" + to_string(r.termination) +
               ", iterations=" + std::to_string(r.iterations) +
               ", fit_percent=" + std::to_string(r.fit_percent) + ")";
      });
}

void bind_refined_iv(py::module_& m) {
  py::enum_<NoiseAssumption>(m, "NoiseAssumption", "Noise model of the covariance.")
      .value("white", NoiseAssumption::white, "sigma^2 R^-1.")
      .value("coloured", NoiseAssumption::coloured, "Sandwich with an AR noise model.");
  py::enum_<Interpolation>(m, "Interpolation", "Interpolation of a signal between samples.")
      .value("zero_order_hold", Interpolation::zero_order_hold, "Held.")
      .value("first_order_hold", Interpolation::first_order_hold, "Linear.");
  OptionsClass<RefinedIvOptions>(m, "RefinedIvOptions",
                                 "Options of srivc, clsrivc, additive_srivc, additive_clsrivc.")
      .field("max_iterations", &RefinedIvOptions::max_iterations, "Iteration limit (>= 1).")
      .field("tolerance", &RefinedIvOptions::tolerance, "Relative parameter change to stop.")
      .field("initial_model", &RefinedIvOptions::initial_model,
             "Starting AdditiveModel or None (automatic).")
      .field("output_interpolation", &RefinedIvOptions::output_interpolation,
             "Interpolation of the output.")
      .field("input_delay", &RefinedIvOptions::input_delay, "Known delay [samples].")
      .field("record_history", &RefinedIvOptions::record_history, "Keep per-iteration history.")
      .field("noise", &RefinedIvOptions::noise, "NoiseAssumption for the covariance.")
      .field("noise_model_max_order", &RefinedIvOptions::noise_model_max_order,
             "Largest AR order of the noise model.")
      .field("compute_covariance", &RefinedIvOptions::compute_covariance,
             "Compute covariance and standard errors.")
      .finish();

  m.def(
      "srivc",
      [](const SampledData& data, const SubmodelOrder& order,
         const std::optional<RefinedIvOptions>& options, const py::kwargs& kwargs) {
        const auto o = refined("srivc", options, kwargs);
        py::gil_scoped_release release;
        return srivc(data, order, o);
      },
      py::arg("data"), py::arg("order"), py::arg("options") = py::none(),
      "SRIVC: one unfactored model B/(p^l A) from open-loop data.");
  m.def(
      "clsrivc",
      [](const SampledData& data, const DiscreteTransferFunction& controller,
         const SubmodelOrder& order, const std::optional<RefinedIvOptions>& options,
         const py::kwargs& kwargs) {
        const auto o = refined("clsrivc", options, kwargs);
        py::gil_scoped_release release;
        return clsrivc(data, controller, order, o);
      },
      py::arg("data"), py::arg("controller"), py::arg("order"), py::arg("options") = py::none(),
      "CLSRIVC: one unfactored model from closed-loop data with a known controller.");
  m.def(
      "additive_srivc",
      [](const SampledData& data, const std::vector<SubmodelOrder>& orders,
         const std::optional<RefinedIvOptions>& options, const py::kwargs& kwargs) {
        const auto o = refined("additive_srivc", options, kwargs);
        py::gil_scoped_release release;
        return additive_srivc(data, orders, o);
      },
      py::arg("data"), py::arg("orders"), py::arg("options") = py::none(),
      "Additive open-loop refined IV (eq. 29), submodels listed slowest first.");
  m.def(
      "additive_clsrivc",
      [](const SampledData& data, const DiscreteTransferFunction& controller,
         const std::vector<SubmodelOrder>& orders, const std::optional<RefinedIvOptions>& options,
         const py::kwargs& kwargs) {
        const auto o = refined("additive_clsrivc", options, kwargs);
        py::gil_scoped_release release;
        return additive_clsrivc(data, controller, orders, o);
      },
      py::arg("data"), py::arg("controller"), py::arg("orders"), py::arg("options") = py::none(),
      "Additive closed-loop refined IV (eq. 29 with instrument (20)).");

  py::enum_<RelocationCriterion>(m, "RelocationCriterion", "How relocated estimates compare.")
      .value("projected_output_error", RelocationCriterion::projected_output_error,
             "Output error of the estimate's poles (numerators re-fitted).")
      .value("output_error", RelocationCriterion::output_error, "The estimate's output error.");
  OptionsClass<ModeRelocationOptions>(m, "ModeRelocationOptions",
                                      "Options of additive_srivc_relocated.")
      .field("max_relocations", &ModeRelocationOptions::max_relocations, "Moves kept at most.")
      .field("peaks_per_round", &ModeRelocationOptions::peaks_per_round,
             "Residual peaks examined per round.")
      .field("min_peak_to_floor", &ModeRelocationOptions::min_peak_to_floor,
             "Peak over local floor that counts.")
      .field("min_input_level", &ModeRelocationOptions::min_input_level,
             "Excited band: input level relative to its largest.")
      .field("floor_half_width", &ModeRelocationOptions::floor_half_width,
             "Half-width of the floor window [lines].")
      .field("zero_padding", &ModeRelocationOptions::zero_padding, "DFT length / record length.")
      .field("search_half_width", &ModeRelocationOptions::search_half_width,
             "Peak search half-width [lines].")
      .field("search_points", &ModeRelocationOptions::search_points, "Frequencies searched.")
      .field("damping_ratios", &ModeRelocationOptions::damping_ratios, "Damping ratios tried.")
      .field("trials_per_round", &ModeRelocationOptions::trials_per_round,
             "Starts re-run per round.")
      .field("criterion", &ModeRelocationOptions::criterion, "RelocationCriterion.")
      .field("min_relative_decrease", &ModeRelocationOptions::min_relative_decrease,
             "Relative decrease that keeps a move.")
      .finish();
  py::class_<RelocationTrial>(m, "RelocationTrial", "One relocated start re-run.")
      .def_readonly("round", &RelocationTrial::round, "Round (0 first).")
      .def_readonly("submodel", &RelocationTrial::submodel, "Submodel moved.")
      .def_readonly("moved_from", &RelocationTrial::moved_from, "Its w_n before [rad/s].")
      .def_readonly("peak_frequency", &RelocationTrial::peak_frequency, "Residual peak [rad/s].")
      .def_readonly("peak_to_floor", &RelocationTrial::peak_to_floor, "Peak over floor.")
      .def_readonly("start_frequency", &RelocationTrial::start_frequency, "Start w_n [rad/s].")
      .def_readonly("start_damping", &RelocationTrial::start_damping, "Start damping ratio.")
      .def_readonly("start_mean_squared_error", &RelocationTrial::start_mean_squared_error,
                    "LS output error of the start.")
      .def_readonly("mean_squared_error", &RelocationTrial::mean_squared_error,
                    "Output error after the iteration.")
      .def_readonly("projected_mean_squared_error", &RelocationTrial::projected_mean_squared_error,
                    "The same, numerators re-fitted.")
      .def_readonly("score", &RelocationTrial::score, "The criterion's value for this trial.")
      .def_readonly("termination", &RelocationTrial::termination, "Termination.")
      .def_readonly("accepted", &RelocationTrial::accepted, "Kept.");
  py::class_<ModeRelocationResult>(m, "ModeRelocationResult", "Outcome of mode relocation.")
      .def_readonly("estimate", &ModeRelocationResult::estimate, "Final EstimationResult.")
      .def_readonly("initial_mean_squared_error", &ModeRelocationResult::initial_mean_squared_error,
                    "Plain estimate's MSE.")
      .def_readonly("initial_projected_mean_squared_error",
                    &ModeRelocationResult::initial_projected_mean_squared_error,
                    "Plain estimate's MSE, numerators re-fitted.")
      .def_readonly("projected_mean_squared_error",
                    &ModeRelocationResult::projected_mean_squared_error,
                    "Final estimate's MSE, numerators re-fitted.")
      .def_readonly("initial_score", &ModeRelocationResult::initial_score,
                    "The criterion's value for the plain estimate.")
      .def_readonly("score", &ModeRelocationResult::score,
                    "The criterion's value for the kept one (never larger).")
      .def_readonly("rounds", &ModeRelocationResult::rounds, "Rounds that looked for peaks.")
      .def_readonly("relocations", &ModeRelocationResult::relocations, "Moves kept.")
      .def_readonly("trials", &ModeRelocationResult::trials, "Every re-run, in order.")
      .def_readonly("message", &ModeRelocationResult::message, "One sentence.");
  m.def(
      "additive_srivc_relocated",
      [](const SampledData& data, const std::vector<SubmodelOrder>& orders,
         const std::optional<RefinedIvOptions>& options,
         const std::optional<ModeRelocationOptions>& relocation, const py::kwargs& kwargs) {
        const auto o = refined("additive_srivc_relocated", options, kwargs);
        const ModeRelocationOptions r = relocation.value_or(ModeRelocationOptions{});
        py::gil_scoped_release release;
        return additive_srivc_relocated(data, orders, o, r);
      },
      py::arg("data"), py::arg("orders"), py::arg("options") = py::none(),
      py::arg("relocation") = py::none(),
      "additive_srivc, then moves of second-order submodels to the residual's spectral peaks, "
      "each kept only if the output error falls (a global restart).");

  py::class_<DelayScanResult>(m, "DelayScanResult", "Outcome of a delay scan.")
      .def_readonly("best", &DelayScanResult::best, "EstimationResult at the best delay.")
      .def_readonly("delays", &DelayScanResult::delays, "Delays tried [samples].")
      .def_readonly("mean_squared_errors", &DelayScanResult::mean_squared_errors,
                    "Output-error MSE per delay (inf where it failed).")
      .def_readonly("terminations", &DelayScanResult::terminations, "Per delay.");
  m.def(
      "srivc_delay_scan",
      [](const SampledData& data, const SubmodelOrder& order, int min_delay, int max_delay,
         const std::optional<RefinedIvOptions>& options, const py::kwargs& kwargs) {
        const auto o = refined("srivc_delay_scan", options, kwargs);
        py::gil_scoped_release release;
        return srivc_delay_scan(data, order, min_delay, max_delay, o);
      },
      py::arg("data"), py::arg("order"), py::arg("min_delay"), py::arg("max_delay"),
      py::arg("options") = py::none(), "srivc for every delay in a range; best fit kept.");
  m.def(
      "additive_srivc_delay_scan",
      [](const SampledData& data, const std::vector<SubmodelOrder>& orders, int min_delay,
         int max_delay, const std::optional<RefinedIvOptions>& options, const py::kwargs& kwargs) {
        const auto o = refined("additive_srivc_delay_scan", options, kwargs);
        py::gil_scoped_release release;
        return additive_srivc_delay_scan(data, orders, min_delay, max_delay, o);
      },
      py::arg("data"), py::arg("orders"), py::arg("min_delay"), py::arg("max_delay"),
      py::arg("options") = py::none(), "additive_srivc for every delay in a range.");
}

void bind_initialization(py::module_& m) {
  OptionsClass<InitializationOptions>(m, "InitializationOptions",
                                      "Options of the automatic initialisation.")
      .field("filter_bandwidths", &InitializationOptions::filter_bandwidths,
             "SVF bandwidths [rad/s]; empty: automatic grid.")
      .field("refinement_iterations", &InitializationOptions::refinement_iterations,
             "SRIVC iterations per start.")
      .field("input_delay", &InitializationOptions::input_delay, "Delay [samples].")
      .finish();
  m.def("lssvf", &lssvf, py::arg("data"), py::arg("order"), py::arg("bandwidth"),
        py::arg("input_delay") = 0, "Least-squares state-variable-filter estimate.");
  m.def("unfactored_order", &unfactored_order, py::arg("orders"),
        "Orders of the unfactored equivalent of an additive structure.");
  m.def(
      "initial_transfer_function",
      [](const SampledData& data, const SubmodelOrder& order,
         const std::optional<InitializationOptions>& options, const py::kwargs& kwargs) {
        return initial_transfer_function(
            data, order,
            options_from<InitializationOptions>("initial_transfer_function", options, kwargs));
      },
      py::arg("data"), py::arg("order"), py::arg("options") = py::none(),
      "Best unfactored start over the bandwidth grid.");
  m.def("group_into_submodels", &group_into_submodels, py::arg("g"), py::arg("orders"),
        py::arg("data"), py::arg("input_delay") = 0,
        "Poles of g grouped into submodels; numerators fitted by least squares.");
  m.def(
      "initial_additive_model",
      [](const SampledData& data, const std::vector<SubmodelOrder>& orders,
         const std::optional<InitializationOptions>& options, const py::kwargs& kwargs) {
        return initial_additive_model(
            data, orders,
            options_from<InitializationOptions>("initial_additive_model", options, kwargs));
      },
      py::arg("data"), py::arg("orders"), py::arg("options") = py::none(),
      "initial_transfer_function + group_into_submodels.");
}

void bind_covariance_and_validation(py::module_& m) {
  m.def("instrumental_variable_covariance", &instrumental_variable_covariance, py::arg("psi"),
        py::arg("residual"), py::arg("parameter_count"), py::arg("noise"),
        py::arg("max_ar_order") = 20, "Asymptotic covariance (Theorem 3.2).");
  py::class_<AutoregressiveModel>(m, "AutoregressiveModel", "AR model [1, a1, ..., ak].")
      .def_readonly("coefficients", &AutoregressiveModel::coefficients, "[1, a1, ...].")
      .def_readonly("innovation_variance", &AutoregressiveModel::innovation_variance,
                    "Variance of e.");
  m.def("fit_autoregressive", &fit_autoregressive, py::arg("x"), py::arg("max_order"),
        "Yule-Walker AR fit, order by AIC.");
  m.def("modal_estimates", &modal_estimates, py::arg("model"), py::arg("covariance"),
        py::arg("unfactored") = false, "Modal parameters with delta-method standard errors.");

  m.def("model_output", &model_output, py::arg("model"), py::arg("input"), py::arg("sample_time"),
        "Exact ZOH response of the model (from rest).");
  m.def("fit_percent", &fit_percent, py::arg("measured"), py::arg("modelled"),
        "100 (1 - ||y - y_model|| / ||y - mean y||).");
  py::class_<ValidationReport>(m, "ValidationReport", "Residual statistics of a model.")
      .def_readonly("fit_percent", &ValidationReport::fit_percent, "Fit %.")
      .def_readonly("mean_squared_error", &ValidationReport::mean_squared_error, "MSE.")
      .def_readonly("residual_mean", &ValidationReport::residual_mean, "Mean residual.")
      .def_readonly("residual_std", &ValidationReport::residual_std, "Residual std.")
      .def_readonly("max_lag", &ValidationReport::max_lag, "Lags used.")
      .def_readonly("residual_autocorrelation", &ValidationReport::residual_autocorrelation,
                    "Normalised residual autocorrelation at lags 1..max_lag.")
      .def_readonly("cross_correlation", &ValidationReport::cross_correlation,
                    "Normalised residual-input cross-correlation at lags -max_lag..max_lag.")
      .def_readonly("max_residual_autocorrelation", &ValidationReport::max_residual_autocorrelation,
                    "Largest |autocorrelation| at lags 1..max_lag.")
      .def_readonly("max_cross_correlation", &ValidationReport::max_cross_correlation,
                    "Largest |cross-correlation| at lags -max_lag..max_lag.")
      .def_readonly("whiteness_bound", &ValidationReport::whiteness_bound, "2.58/sqrt(N).")
      .def_property_readonly("residual_white", &ValidationReport::residual_white,
                             "Autocorrelation within the 99 % band.")
      .def_property_readonly("residual_uncorrelated_with_input",
                             &ValidationReport::residual_uncorrelated_with_input,
                             "Cross-correlation within the 99 % band.");
  m.def("validate_model", &validate_model, py::arg("model"), py::arg("data"),
        py::arg("max_lag") = 20, "Fit and residual statistics of a model on data.");
  m.def("persistent_excitation_order", &persistent_excitation_order, py::arg("x"),
        py::arg("max_order"), py::arg("tolerance") = 1e-9, "Order of PE seen in the record.");
  m.def("largest_pole_frequency", &largest_pole_frequency, py::arg("model"),
        "Largest |Im pole| [rad/s].");
}

void bind_feedback(py::module_& m) {
  py::enum_<RegressorFilter>(m, "RegressorFilter", "Filter of the step-1 regressors.")
      .value("integrator_chain", RegressorFilter::kIntegratorChain, "1/s^q (the paper).")
      .value("linear_integral_filter", RegressorFilter::kLinearIntegralFilter, "1/(s+a)^q.");
  OptionsClass<FeedbackRegressorOptions>(m, "FeedbackRegressorOptions",
                                         "Options of build_feedback_regression.")
      .field("filter", &FeedbackRegressorOptions::filter, "RegressorFilter.")
      .field("filter_pole", &FeedbackRegressorOptions::filter_pole, "a of 1/(s+a)^q.")
      .field("initial_condition_terms", &FeedbackRegressorOptions::initial_condition_terms,
             "Append nuisance columns for initial conditions.")
      .field("first_equation", &FeedbackRegressorOptions::first_equation,
             "First equation k; -1: ceil(Delta/delta).")
      .finish();
  py::class_<FeedbackRegression>(m, "FeedbackRegression", "target = regressor [theta; nuisance].")
      .def_readonly("regressor", &FeedbackRegression::regressor, "C.")
      .def_readonly("target", &FeedbackRegression::target, "y.")
      .def_readonly("sample_index", &FeedbackRegression::sample_index, "k of each row.")
      .def_readonly("forward_order", &FeedbackRegression::forward_order, "n.")
      .def_readonly("feedback_order", &FeedbackRegression::feedback_order, "m.")
      .def_readonly("theta_size", &FeedbackRegression::theta_size, "3(n+m) - 1.")
      .def_readonly("nuisance_size", &FeedbackRegression::nuisance_size, "Nuisance columns.")
      .def_readonly("delay", &FeedbackRegression::delay, "Delta [s].")
      .def_readonly("sample_time", &FeedbackRegression::sample_time, "delta [s].");
  m.def(
      "build_feedback_regression",
      [](const SampledData& data, int forward_order, int feedback_order, double delay,
         const std::optional<FeedbackRegressorOptions>& options, const py::kwargs& kwargs) {
        return build_feedback_regression(
            data, forward_order, feedback_order, delay,
            options_from<FeedbackRegressorOptions>("build_feedback_regression", options, kwargs));
      },
      py::arg("data"), py::arg("forward_order"), py::arg("feedback_order"), py::arg("delay"),
      py::arg("options") = py::none(), "Step-1 regression of the delayed-feedback loop.");

  py::class_<ClosedLoopEstimate>(m, "ClosedLoopEstimate", "alpha, beta, gamma and diagnostics.")
      .def_readonly("alpha", &ClosedLoopEstimate::alpha, "alpha.")
      .def_readonly("beta", &ClosedLoopEstimate::beta, "beta (monic).")
      .def_readonly("gamma", &ClosedLoopEstimate::gamma, "gamma.")
      .def_readonly("theta", &ClosedLoopEstimate::theta, "The paper's theta.")
      .def_readonly("nuisance", &ClosedLoopEstimate::nuisance, "Nuisance coefficients.")
      .def_readonly("residual_rms", &ClosedLoopEstimate::residual_rms, "Residual rms.")
      .def_readonly("condition_number", &ClosedLoopEstimate::condition_number, "cond(C).")
      .def_readonly("ridge", &ClosedLoopEstimate::ridge, "Ridge weight used.")
      .def_readonly("equations", &ClosedLoopEstimate::equations, "Rows used.")
      .def_readonly("theta_history", &ClosedLoopEstimate::theta_history, "RLS trajectory.");
  m.def("closed_loop_polynomials", &closed_loop_polynomials, py::arg("theta"), py::arg("q"),
        "Split theta into alpha, beta, gamma.");
  m.def("closed_loop_theta", &closed_loop_theta, py::arg("alpha"), py::arg("beta"),
        py::arg("gamma"), "theta of known polynomials.");
  py::enum_<LeastSquaresSolver>(m, "LeastSquaresSolver", "Batch solver.")
      .value("qr", LeastSquaresSolver::kQr, "Column-pivoted QR.")
      .value("svd", LeastSquaresSolver::kSvd, "SVD.");
  py::enum_<Regularisation>(m, "Regularisation", "Ridge choice.")
      .value("none", Regularisation::kNone, "Plain least squares.")
      .value("fixed", Regularisation::kFixed, "Fixed ridge weight.")
      .value("gcv", Regularisation::kGcv, "Weight by generalised cross-validation.");
  OptionsClass<BatchLeastSquaresOptions>(m, "BatchLeastSquaresOptions",
                                         "Options of estimate_closed_loop_batch.")
      .field("solver", &BatchLeastSquaresOptions::solver, "LeastSquaresSolver.")
      .field("regularisation", &BatchLeastSquaresOptions::regularisation, "Regularisation.")
      .field("ridge", &BatchLeastSquaresOptions::ridge, "Fixed relative ridge weight.")
      .field("gcv_min", &BatchLeastSquaresOptions::gcv_min, "GCV grid lower end.")
      .field("gcv_max", &BatchLeastSquaresOptions::gcv_max, "GCV grid upper end.")
      .field("gcv_points", &BatchLeastSquaresOptions::gcv_points, "GCV grid size.")
      .field("rank_tolerance", &BatchLeastSquaresOptions::rank_tolerance, "Rank threshold.")
      .finish();
  m.def(
      "estimate_closed_loop_batch",
      [](const FeedbackRegression& regression,
         const std::optional<BatchLeastSquaresOptions>& options, const py::kwargs& kwargs) {
        return estimate_closed_loop_batch(
            regression,
            options_from<BatchLeastSquaresOptions>("estimate_closed_loop_batch", options, kwargs));
      },
      py::arg("regression"), py::arg("options") = py::none(), "Batch least squares of step 1.");
  OptionsClass<RecursiveLeastSquaresOptions>(m, "RecursiveLeastSquaresOptions",
                                             "Options of estimate_closed_loop_recursive.")
      .field("forgetting", &RecursiveLeastSquaresOptions::forgetting, "lambda in (0, 1].")
      .field("initial_theta", &RecursiveLeastSquaresOptions::initial_theta, "theta(0) or None.")
      .field("initial_covariance", &RecursiveLeastSquaresOptions::initial_covariance,
             "P(0) = value * I.")
      .field("initial_covariance_matrix", &RecursiveLeastSquaresOptions::initial_covariance_matrix,
             "P(0) in full or None.")
      .field("keep_history", &RecursiveLeastSquaresOptions::keep_history, "Keep theta(k).")
      .finish();
  m.def(
      "estimate_closed_loop_recursive",
      [](const FeedbackRegression& regression,
         const std::optional<RecursiveLeastSquaresOptions>& options, const py::kwargs& kwargs) {
        return estimate_closed_loop_recursive(
            regression, options_from<RecursiveLeastSquaresOptions>("estimate_closed_loop_recursive",
                                                                   options, kwargs));
      },
      py::arg("regression"), py::arg("options") = py::none(), "Recursive least squares (13).");
  py::class_<RecursiveLeastSquares>(m, "RecursiveLeastSquares", "RLS of eq. (13).")
      .def(py::init<Eigen::VectorXd, Eigen::MatrixXd, double>(), py::arg("theta0"), py::arg("p0"),
           py::arg("forgetting"), "From theta(0), P(0) and lambda.")
      .def("update", &RecursiveLeastSquares::update, py::arg("c"), py::arg("y"), "One update.")
      .def_property_readonly("theta", &RecursiveLeastSquares::theta, "Current theta.")
      .def_property_readonly("covariance", &RecursiveLeastSquares::covariance, "Current P.");
  py::class_<SeparationCandidateReport>(m, "SeparationCandidateReport",
                                        "One separation candidate of identify_delayed_feedback.")
      .def_readonly("source", &SeparationCandidateReport::source,
                    "'gcd', 'kronecker: <start>' or 'structured step 1'.")
      .def_readonly("start", &SeparationCandidateReport::start, "DelayedFeedbackLoop start.")
      .def_readonly("kronecker_cost", &SeparationCandidateReport::kronecker_cost, "J of the start.")
      .def_readonly("start_rms", &SeparationCandidateReport::start_rms,
                    "Output-error rms of the start (inf: unstable).")
      .def_readonly("refined_rms", &SeparationCandidateReport::refined_rms,
                    "Output-error rms after refinement.");
  py::class_<FeedbackIdentificationResult>(m, "FeedbackIdentificationResult",
                                           "F, H and diagnostics of identify_delayed_feedback.")
      .def_readonly("loop", &FeedbackIdentificationResult::loop,
                    "DelayedFeedbackLoop (F, H, delay).")
      .def_readonly("step1", &FeedbackIdentificationResult::step1, "ClosedLoopEstimate (W).")
      .def_readonly("step1_output_rms", &FeedbackIdentificationResult::step1_output_rms,
                    "Output-error rms of the step-1 W (inf: unstable).")
      .def_readonly("candidates", &FeedbackIdentificationResult::candidates,
                    "SeparationCandidateReport list.")
      .def_readonly("best_candidate", &FeedbackIdentificationResult::best_candidate,
                    "Index of the chosen candidate (-1: none).")
      .def_readonly("output_rms", &FeedbackIdentificationResult::output_rms,
                    "Output-error rms of the returned loop.")
      .def_readonly("message", &FeedbackIdentificationResult::message, "Summary.")
      .def_property_readonly(
          "cramer_rao_standard_deviations",
          [](const FeedbackIdentificationResult& r) { return r.cramer_rao.standard_deviations; },
          "Cramer-Rao standard deviations of [a_F | b_F | a_H | b_H] at the estimate.");
  const FeedbackIdentificationOptions default_identification;
  m.def(
      "identify_delayed_feedback",
      [](const SampledData& data, int forward_order, int feedback_order, double delay,
         InputHold hold, double filter_pole, const std::vector<double>& iv_filter_poles) {
        FeedbackIdentificationOptions options;
        options.output_error.hold = hold;
        options.regressors.filter_pole = filter_pole;
        options.iv_filter_poles = iv_filter_poles;
        options.validate();
        py::gil_scoped_release release;
        return identify_delayed_feedback(data, forward_order, feedback_order, delay, options);
      },
      py::arg("data"), py::arg("forward_order"), py::arg("feedback_order"), py::arg("delay"),
      py::arg("hold") = InputHold::kFirstOrder, py::arg("filter_pole") = 1.0,
      py::arg("iv_filter_poles") = default_identification.iv_filter_poles,
      "F and H of a loop with a delayed feedback: step 1, separation candidates (GCD, min J, "
      "structured step 1, a bias-corrected IV start per pole in iv_filter_poles), output-error "
      "refinement from each; the smallest output error wins.");

  OptionsClass<StructuredIvOptions>(m, "StructuredIvOptions",
                                    "Options of estimate_structured_step1_iv.")
      .field("iterations", &StructuredIvOptions::iterations, "IV iterations.")
      .field("max_iterations", &StructuredIvOptions::max_iterations,
             "Levenberg-Marquardt steps per iteration.")
      .field("tolerance", &StructuredIvOptions::tolerance, "|d rho| / max(1, |rho|) to stop.")
      .field("hold", &StructuredIvOptions::hold, "InputHold of the simulated instruments.")
      .field("bias_correction", &StructuredIvOptions::bias_correction,
             "Subtract the estimator's error on the model's own simulated output.")
      .field("substeps", &StructuredIvOptions::substeps, "RK4 steps per sample.")
      .finish();
  py::class_<StructuredIvResult>(m, "StructuredIvResult", "Outcome of the structured IV.")
      .def_readonly("loop", &StructuredIvResult::loop, "DelayedFeedbackLoop.")
      .def_readonly("output_rms", &StructuredIvResult::output_rms, "Output-error rms.")
      .def_readonly("output_rms_history", &StructuredIvResult::output_rms_history,
                    "Start, then each iterate (inf: unstable).")
      .def_readonly("iterations", &StructuredIvResult::iterations, "Iterations run.")
      .def_readonly("converged", &StructuredIvResult::converged, "Tolerance reached.")
      .def_readonly("message", &StructuredIvResult::message, "Summary.");
  m.def(
      "estimate_structured_step1_iv",
      [](const SampledData& data, const DelayedFeedbackLoop& start,
         const FeedbackRegressorOptions& regressors,
         const std::optional<StructuredIvOptions>& options, const py::kwargs& kwargs) {
        const auto o =
            options_from<StructuredIvOptions>("estimate_structured_step1_iv", options, kwargs);
        py::gil_scoped_release release;
        return estimate_structured_step1_iv(data, start, regressors, o);
      },
      py::arg("data"), py::arg("start"), py::arg("regressors"), py::arg("options") = py::none(),
      "Bias-corrected instrumental variables in F and H's 2(n+m) unknowns, from a start loop: "
      "instruments from the loop's simulated output; the best iterate by output error.");
}

// Step 2 (separation), refinement, quality and validation of the delayed-feedback methods
// (De Iuliis et al., eqs. 19-24, and docs/algorithms/feedback-delay.md).
void bind_feedback_separation(py::module_& m) {
  py::class_<KroneckerCandidate>(m, "KroneckerCandidate", "One refined start of min J.")
      .def_readonly("start", &KroneckerCandidate::start, "'gcd' or 'roots split k'.")
      .def_readonly("forward", &KroneckerCandidate::forward, "F of this start.")
      .def_readonly("feedback", &KroneckerCandidate::feedback, "H of this start.")
      .def_readonly("cost", &KroneckerCandidate::cost, "J after Levenberg-Marquardt.");
  py::class_<KroneckerSeparationResult>(m, "KroneckerSeparationResult",
                                        "F and H from min J (eqs. 19-21).")
      .def_readonly("forward", &KroneckerSeparationResult::forward, "F(s).")
      .def_readonly("feedback", &KroneckerSeparationResult::feedback, "H(s).")
      .def_readonly("cost", &KroneckerSeparationResult::cost, "J at the returned F, H.")
      .def_readonly("starts", &KroneckerSeparationResult::starts, "Starts refined.")
      .def_readonly("best_start", &KroneckerSeparationResult::best_start, "Winning start.")
      .def_readonly("converged", &KroneckerSeparationResult::converged,
                    "Ceres converged for the best start.")
      .def_readonly("message", &KroneckerSeparationResult::message, "Summary.")
      .def_readonly("candidates", &KroneckerSeparationResult::candidates,
                    "Every refined start (KroneckerCandidate list).");
  m.def(
      "separate_kronecker",
      [](const Polynomial& alpha, const Polynomial& beta, const Polynomial& gamma,
         int forward_order, int feedback_order, bool multi_start, int max_iterations) {
        KroneckerSeparationOptions options;
        options.multi_start = multi_start;
        options.max_iterations = max_iterations;
        py::gil_scoped_release release;
        return separate_kronecker(alpha, beta, gamma, forward_order, feedback_order, options);
      },
      py::arg("alpha"), py::arg("beta"), py::arg("gamma"), py::arg("forward_order"),
      py::arg("feedback_order"), py::kw_only(), py::arg("multi_start") = true,
      py::arg("max_iterations") = 200,
      "Separate F and H from alpha, beta, gamma (ascending) by min J with Levenberg-Marquardt "
      "from the GCD estimate and every split of the roots of beta.");
  py::class_<GcdSeparationResult>(m, "GcdSeparationResult",
                                  "F and H from the approximate GCD (eqs. 22-24).")
      .def_readonly("forward", &GcdSeparationResult::forward, "F(s).")
      .def_readonly("feedback", &GcdSeparationResult::feedback, "H(s).")
      .def_readonly("forward_singular_values", &GcdSeparationResult::forward_singular_values,
                    "Singular values of the observability matrix of alpha/beta.")
      .def_readonly("feedback_singular_values", &GcdSeparationResult::feedback_singular_values,
                    "Singular values of the observability matrix of gamma/alpha.")
      .def_readonly("forward_gap", &GcdSeparationResult::forward_gap, "sigma_n / sigma_{n+1}.")
      .def_readonly("feedback_gap", &GcdSeparationResult::feedback_gap, "sigma_m / sigma_{m+1}.")
      .def_readonly("cancelled_forward", &GcdSeparationResult::cancelled_forward,
                    "The cancelled part of alpha/beta (approximate D_H).")
      .def_readonly("cancelled_feedback", &GcdSeparationResult::cancelled_feedback,
                    "The cancelled part of gamma/alpha (approximate monic N_F).");
  m.def("separate_approximate_gcd", &separate_approximate_gcd, py::arg("alpha"), py::arg("beta"),
        py::arg("gamma"), py::arg("forward_order"), py::arg("feedback_order"),
        "Separate F and H by Kalman observability decomposition and SVD (approximate GCD).");
  m.def("kronecker_cost", &kronecker_cost, py::arg("alpha"), py::arg("beta"), py::arg("gamma"),
        py::arg("forward"), py::arg("feedback"), "J of eqs. (19)-(21) at F and H.");

  py::class_<SeparabilityReport>(m, "SeparabilityReport",
                                 "Covariance of [a_F | b_F | a_H | b_H]: are F, H separable?")
      .def_readonly("parameters", &SeparabilityReport::parameters, "rho.")
      .def_readonly("covariance", &SeparabilityReport::covariance, "sigma^2 (J'J)^-1.")
      .def_readonly("standard_deviations", &SeparabilityReport::standard_deviations,
                    "Square roots of the covariance diagonal.")
      .def_readonly("relative_standard_deviations",
                    &SeparabilityReport::relative_standard_deviations, "sd / max(|rho_i|, 1e-3).")
      .def_readonly("noise_variance", &SeparabilityReport::noise_variance, "sigma^2.")
      .def_readonly("condition_number", &SeparabilityReport::condition_number,
                    "Of the column-scaled sensitivity matrix.")
      .def_readonly("separable", &SeparabilityReport::separable,
                    "Every relative sd below the threshold.")
      .def_readonly("message", &SeparabilityReport::message, "Verdict in one sentence.");
  m.def("cramer_rao_bound", &cramer_rao_bound, py::arg("loop"), py::arg("input"),
        py::arg("sample_time"), py::arg("hold"), py::arg("noise_sd"),
        py::arg("relative_threshold") = 0.1, py::arg("substeps") = 4,
        "Cramer-Rao bound of rho for this loop, input and white output noise.");

  py::class_<OutputErrorResult>(m, "OutputErrorResult", "Output-error refinement of F and H.")
      .def_readonly("loop", &OutputErrorResult::loop, "DelayedFeedbackLoop (F, H, delay).")
      .def_readonly("residual_rms", &OutputErrorResult::residual_rms, "rms of y - y_hat.")
      .def_readonly("iterations", &OutputErrorResult::iterations, "Iterations.")
      .def_readonly("converged", &OutputErrorResult::converged, "Converged.")
      .def_readonly("message", &OutputErrorResult::message, "Summary.")
      .def_readonly("quality", &OutputErrorResult::quality, "SeparabilityReport at the estimate.");
  m.def(
      "refine_output_error",
      [](const SampledData& data, const DelayedFeedbackLoop& start, InputHold hold, int substeps,
         int max_iterations, bool estimate_delay) {
        OutputErrorOptions options;
        options.hold = hold;
        options.substeps = substeps;
        options.max_iterations = max_iterations;
        options.estimate_delay = estimate_delay;
        py::gil_scoped_release release;
        return refine_output_error(data, start, options);
      },
      py::arg("data"), py::arg("start"), py::kw_only(), py::arg("hold") = InputHold::kZeroOrder,
      py::arg("substeps") = 4, py::arg("max_iterations") = 200, py::arg("estimate_delay") = false,
      "Minimise the output error over F and H (and the delay) from a start.");

  py::class_<ResponseComparison>(m, "ResponseComparison",
                                 "Responses of a true and an estimated model to white noise.")
      .def_readonly("mse", &ResponseComparison::mse, "MSE of this realisation (inf: overflow).")
      .def_readonly("expected_mse", &ResponseComparison::expected_mse,
                    "Expected MSE over realisations.")
      .def_readonly("estimate_stable", &ResponseComparison::estimate_stable, "Estimate stable.")
      .def_readonly("truth", &ResponseComparison::truth, "True response.")
      .def_readonly("estimate", &ResponseComparison::estimate, "Estimated response.");
  m.def(
      "compare_white_noise_response",
      [](const TransferFunction& truth, const TransferFunction& estimate, double sample_time,
         double duration, std::uint64_t seed) {
        WhiteNoiseValidationOptions options;
        options.sample_time = sample_time;
        options.duration = duration;
        options.seed = seed;
        return compare_white_noise_response(truth, estimate, options);
      },
      py::arg("truth"), py::arg("estimate"), py::kw_only(), py::arg("sample_time") = 0.005,
      py::arg("duration") = 5.0, py::arg("seed") = 1,
      "The paper's validation: both models driven by unit-variance white noise held at "
      "sample_time for duration seconds.");
  m.def("expected_white_noise_mse", &expected_white_noise_mse, py::arg("truth"),
        py::arg("estimate"), py::arg("sample_time"), py::arg("samples"),
        "Exact expected MSE of the white-noise validation.");

  py::class_<FeedbackDelayScanResult>(m, "FeedbackDelayScanResult", "A scan over the delay.")
      .def_readonly("delays", &FeedbackDelayScanResult::delays, "Delays tried [s].")
      .def_readonly("criterion", &FeedbackDelayScanResult::criterion, "Criterion per delay.")
      .def_readonly("delay", &FeedbackDelayScanResult::delay, "The minimiser [s].")
      .def_readonly("best_criterion", &FeedbackDelayScanResult::best_criterion, "Its value.");
  py::class_<DelayIdentificationResult>(m, "DelayIdentificationResult",
                                        "F, H and the delay when the delay is unknown.")
      .def_readonly("scan", &DelayIdentificationResult::scan, "FeedbackDelayScanResult.")
      .def_readonly("identification", &DelayIdentificationResult::identification,
                    "FeedbackIdentificationResult at the returned delay.")
      .def_readonly("delay", &DelayIdentificationResult::delay, "Estimated delay [s].")
      .def_readonly("evaluations", &DelayIdentificationResult::evaluations, "Identifications run.");
  m.def(
      "identify_delayed_feedback_with_delay_scan",
      [](const SampledData& data, int forward_order, int feedback_order, double min_delay,
         double max_delay, int points, InputHold hold) {
        DelayIdentificationOptions options;
        options.scan.min_delay = min_delay;
        options.scan.max_delay = max_delay;
        options.scan.points = points;
        options.scan.hold = hold;
        options.identification.output_error.hold = hold;
        py::gil_scoped_release release;
        return identify_delayed_feedback_with_delay_scan(data, forward_order, feedback_order,
                                                         options);
      },
      py::arg("data"), py::arg("forward_order"), py::arg("feedback_order"), py::kw_only(),
      py::arg("min_delay"), py::arg("max_delay"), py::arg("points") = 41,
      py::arg("hold") = InputHold::kFirstOrder,
      "identify_delayed_feedback with the delay unknown: a scan of the refined output error "
      "over [min_delay, max_delay], then a joint refinement of F, H and the delay.");
}

}  // namespace

void bind_estimation(py::module_& m) {
  bind_results(m);
  bind_refined_iv(m);
  bind_initialization(m);
  bind_covariance_and_validation(m);
  bind_feedback(m);
  bind_feedback_separation(m);
}

}  // namespace ctid::python
