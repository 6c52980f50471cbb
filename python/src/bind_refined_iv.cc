// Python bindings of the refined IV module (González et al.): SRIVC, CLSRIVC, additive open and
// closed loop, delay scans, mode relocation, automatic initialisation, covariance. Options are
// keyword arguments.
#include "common.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/clsrivc.h"
#include "ctid/refined_iv/clsrivc_continuous.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/refined_iv/input_delay_scan.h"
#include "ctid/refined_iv/irregular_srivc.h"
#include "ctid/refined_iv/mimo_srivc.h"
#include "ctid/refined_iv/mode_relocation.h"
#include "ctid/refined_iv/recursive_srivc.h"
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
  bind_result<ModalEstimate>(m, "A mode's parameters with standard errors.");
  bind_result<IterationRecord>(m, "One iteration of eq. (29).");
  bind_result<DataChecks>(m, "Checks of Assumptions 1 and 4 on the data.");
  bind_result<EstimationResult>(m,
                                "Outcome of a refined IV estimator: model, parameters, "
                                "covariance, termination, diagnostics.")
      .def("converged", &EstimationResult::converged, "termination == converged.")
      .def("brief_report", &EstimationResult::brief_report,
           "One line: termination, iterations and, unless converged, why.");
}

void bind_refined_iv_estimators(py::module_& m) {
  bind_enum<NoiseAssumption>(m, "NoiseAssumption", "Noise model of the covariance.");
  bind_enum<StartMethod>(m, "StartMethod",
                         "How a start is found from the data (initialization.h).");
  bind_enum<InitialConditions>(m, "InitialConditions",
                               "State assumed at the first sample: zero or estimate.");
  bind_options<NoiseModelOrders>(
      m,
      "Orders of the ARMA noise model of RIVC: NoiseModelOrders(ar=P, ma=Q), "
      "NoiseModelOrders(automatic=True), or the words 'P,Q' and 'auto'.")
      .def(py::init([](const std::string& word) {
             std::optional<NoiseModelOrders> orders = NoiseModelOrders::from_flag(word);
             if (!orders) throw py::value_error("noise model 'none': give None instead");
             return *orders;
           }),
           py::arg("word"), "From 'P,Q' or 'auto'.");
  py::implicitly_convertible<std::string, NoiseModelOrders>();
  bind_options<RefinedIvOptions>(m, "Options of srivc, clsrivc, additive_srivc, additive_clsrivc.");

  bind_options<MimoRefinedIvOptions>(m, "Options of mimo_srivc.");
  bind_result<MimoEstimationResult>(
      m, "What mimo_srivc found: the model, per-output fits, the verdict and the modes.")
      .def("converged", &MimoEstimationResult::converged, "termination == converged.");
  m.def(
      "mimo_srivc",
      [](const MimoData& data, const std::vector<SubmodelOrder>& orders,
         const std::optional<MimoAdditiveModel>& initial_model,
         const std::optional<MimoRefinedIvOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<MimoRefinedIvOptions>("mimo_srivc", options, kwargs);
        py::gil_scoped_release release;
        return mimo_srivc(data, orders, o, initial_model);
      },
      py::arg("data"), py::arg("orders"), py::arg("initial_model") = py::none(),
      py::arg("options") = py::none(),
      "Open-loop refined IV with poles shared by every input-output pair of a MimoData; "
      "options are one MimoRefinedIvOptions or its fields as keywords.");

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
      "srivc_irregular",
      [](const Eigen::VectorXd& time, const Eigen::VectorXd& input, const Eigen::VectorXd& output,
         const SubmodelOrder& order, Hold input_hold,
         const std::optional<RefinedIvOptions>& options, const py::kwargs& kwargs) {
        const auto o = refined("srivc_irregular", options, kwargs);
        IrregularRecord record{time, input, output, input_hold};
        py::gil_scoped_release release;
        return srivc_irregular(record, order, o);
      },
      py::arg("time"), py::arg("input"), py::arg("output"), py::arg("order"),
      py::arg("input_hold") = Hold::zero_order_hold, py::arg("options") = py::none(),
      "SRIVC on irregular time stamps (non-decreasing; equal stamps allowed), the filters "
      "discretised on each interval for input_hold (docs/decisions/0034).");
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
      "clsrivc_continuous",
      [](const SampledData& data, const TransferFunction& controller, const SubmodelOrder& order,
         const std::optional<RefinedIvOptions>& options, const py::kwargs& kwargs) {
        const auto o = refined("clsrivc_continuous", options, kwargs);
        py::gil_scoped_release release;
        return clsrivc_continuous(data, controller, order, o);
      },
      py::arg("data"), py::arg("controller"), py::arg("order"), py::arg("options") = py::none(),
      "CLSRIVC with a continuous-time controller C(p) (an analog loop, the reference held as "
      "data.input_hold says): the closed-loop output error from r (decision 0067).");
  m.def(
      "additive_srivc",
      [](const SampledData& data, const std::vector<SubmodelOrder>& orders,
         const std::optional<RefinedIvOptions>& options, const py::kwargs& kwargs) {
        const auto o = refined("additive_srivc", options, kwargs);
        py::gil_scoped_release release;
        return additive_srivc(data, orders, o);
      },
      py::arg("data"), py::arg("orders"), py::arg("options") = py::none(),
      "Additive open-loop refined IV (eq. 29), submodels in any order.");
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
  bind_result<RelocationTrial>(m, "One relocated start re-run.");
  bind_result<ModeRelocationResult>(m, "Outcome of mode relocation.");
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

  bind_result<InputDelayScanResult>(m, "Outcome of a delay scan.");
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
  bind_options<InitializationOptions>(m, "Options of the data-driven start (LSSVF, FRF peaks).");
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
      "Best unfactored start among the candidates (LSSVF grid, FRF peaks).");
  m.def("frf_peak_start", &frf_peak_start, py::arg("data"), py::arg("order"),
        py::arg("input_delay") = 0,
        "Start from the resonance peaks of the record's FRF, or None if it has too few.");
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

// --- Recursive SRIVC (issue 17): options, the estimator class, the free function ----------
void bind_recursive_srivc(py::module_& m) {
  bind_enum<CovarianceHistory>(m, "CovarianceHistory",
                               "What RecursiveSrivcResult keeps of the covariance per sample.");
  bind_options<RecursiveSrivcOptions>(m, "Options of recursive_srivc and RecursiveSrivc.");
  bind_result<RecursiveSrivcResult>(
      m,
      "Per-sample parameters, standard errors and covariance of recursive_srivc; the final "
      "model and the stability/finiteness verdict.");
  py::class_<RecursiveSrivc>(m, "RecursiveSrivc",
                             "Recursive SRIVC of one unfactored model B/A, advanced by update().")
      .def(
          py::init([](const SubmodelOrder& order, double sample_time, const TransferFunction& start,
                      Hold input_hold, const std::optional<RecursiveSrivcOptions>& options,
                      const py::kwargs& kwargs) {
            return RecursiveSrivc(
                order, sample_time, input_hold, start,
                options_from<RecursiveSrivcOptions>("RecursiveSrivc", options, kwargs));
          }),
          py::arg("order"), py::arg("sample_time"), py::arg("start"),
          py::arg("input_hold") = Hold::zero_order_hold, py::arg("options") = py::none(),
          "From the structure, the sample time, a stable start and options (one "
          "RecursiveSrivcOptions or its fields as keywords).")
      .def("update", &RecursiveSrivc::update, py::arg("u"), py::arg("y"),
           "Advance one sample (u_k, y_k).")
      .def_property_readonly("parameters", &RecursiveSrivc::parameters,
                             "theta = [a_1 .. a_n, b_0 .. b_m].")
      .def("model", &RecursiveSrivc::model, "B/A of the current theta.")
      .def_property_readonly("covariance", &RecursiveSrivc::covariance,
                             "sigma^2 (P + P')/2, np x np.")
      .def_property_readonly("gain_matrix", &RecursiveSrivc::gain_matrix,
                             "P of the recursion (not scaled by sigma^2).")
      .def_property_readonly("noise_variance", &RecursiveSrivc::noise_variance,
                             "Weighted output-error variance sigma^2.")
      .def_property_readonly("steps", &RecursiveSrivc::steps, "Samples processed.")
      .def_property_readonly("rejected_refreshes", &RecursiveSrivc::rejected_refreshes,
                             "Refreshes refused because A was unstable.")
      .def_property_readonly("skipped_updates", &RecursiveSrivc::skipped_updates,
                             "Updates skipped (non-finite theta or P).");
  m.def(
      "recursive_srivc",
      [](const SampledData& data, const SubmodelOrder& order, const TransferFunction& start,
         const std::optional<RecursiveSrivcOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<RecursiveSrivcOptions>("recursive_srivc", options, kwargs);
        py::gil_scoped_release release;
        return recursive_srivc(data, order, start, o);
      },
      py::arg("data"), py::arg("order"), py::arg("start"), py::arg("options") = py::none(),
      "Recursive SRIVC over the record from `start` (exponential forgetting and/or a random "
      "walk); options are one RecursiveSrivcOptions or its fields as keywords.");
}
// --- end of recursive SRIVC --------------------------------------------------------------

}  // namespace

void bind_refined_iv(py::module_& m) {
  bind_results(m);
  bind_refined_iv_estimators(m);
  bind_initialization(m);
  bind_covariance(m);
  bind_recursive_srivc(m);
}

}  // namespace ctid::python
