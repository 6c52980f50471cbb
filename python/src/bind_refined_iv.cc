// Python bindings of the refined IV module (González et al.): SRIVC, CLSRIVC, additive open and
// closed loop, delay scans, mode relocation, automatic initialisation, covariance. Options are
// keyword arguments.
#include "common.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/refined_iv/input_delay_scan.h"
#include "ctid/refined_iv/mode_relocation.h"
#include "ctid/refined_iv/refined_iv_options.h"
#include "ctid/refined_iv/srivc.h"
#include "fields.h"

namespace ctid::python {

namespace {

RefinedIvOptions refined(const char* name, const std::optional<RefinedIvOptions>& options,
                         const py::kwargs& kwargs) {
  return options_from<RefinedIvOptions>(name, options, kwargs);
}

void bind_results(py::module_& m) {
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
      .def("brief_report", &EstimationResult::brief_report,
           "One line: termination, iterations and, unless converged, why.")
      .def("__repr__", [](const EstimationResult& r) {
        return "EstimationResult(" + to_string(r.termination) +
               ", iterations=" + std::to_string(r.iterations) +
               ", fit_percent=" + std::to_string(r.fit_percent) + ")";
      });
}

void bind_refined_iv_estimators(py::module_& m) {
  bind_enum<NoiseAssumption>(m, "NoiseAssumption", "Noise model of the covariance.");
  bind_options<RefinedIvOptions>(m, "Options of srivc, clsrivc, additive_srivc, additive_clsrivc.");

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

  bind_enum<RelocationCriterion>(m, "RelocationCriterion", "How relocated estimates compare.");
  bind_options<ModeRelocationOptions>(m, "Options of additive_srivc_relocated.");
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

  py::class_<InputDelayScanResult>(m, "InputDelayScanResult", "Outcome of a delay scan.")
      .def_readonly("best", &InputDelayScanResult::best, "EstimationResult at the best delay.")
      .def_readonly("delays", &InputDelayScanResult::delays, "Delays tried [samples].")
      .def_readonly("mean_squared_errors", &InputDelayScanResult::mean_squared_errors,
                    "Output-error MSE per delay (inf where it failed).")
      .def_readonly("terminations", &InputDelayScanResult::terminations, "Per delay.");
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
  bind_options<InitializationOptions>(m, "Options of the data-driven start (LSSVF + SRIVC).");
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

void bind_covariance(py::module_& m) {
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
}

}  // namespace

void bind_refined_iv(py::module_& m) {
  bind_results(m);
  bind_refined_iv_estimators(m);
  bind_initialization(m);
  bind_covariance(m);
}

}  // namespace ctid::python
