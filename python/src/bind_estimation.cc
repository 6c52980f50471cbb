// Python bindings of the shared estimation base: the Termination of every iterative method, model
// output, fit, the quality verdict and the residual tests of a model on data (validation.h).
#include "common.h"
#include "ctid/estimation/arma.h"
#include "ctid/estimation/mimo_modes.h"
#include "ctid/estimation/prediction.h"
#include "ctid/estimation/residual_correlation.h"
#include "ctid/estimation/termination.h"
#include "ctid/estimation/validation.h"
#include "ctid/estimation/verdict.h"
#include "fields.h"

namespace ctid::python {

void bind_estimation(py::module_& m) {
  bind_enum<Termination>(m, "Termination", "Why an iterative method stopped (termination.h).");
  bind_result<Verdict>(
      m, "Is an estimate worth using: usable, reasons, advice, active_constraints (verdict.h).")
      .def("summary", &Verdict::summary,
           "'no usable model: <reasons>. Try: <advice>.' (empty when usable).");
  m.def("model_output", &model_output, py::arg("model"), py::arg("input"), py::arg("sample_time"),
        py::arg("input_hold") = Hold::zero_order_hold,
        "Exact response of the model (from rest) to the input held as input_hold says.");
  m.def("fit_percent", &fit_percent, py::arg("measured"), py::arg("modelled"),
        "100 (1 - ||y - y_model|| / ||y - mean y||).");
  m.def(
      "residual_correlations",
      [](const Eigen::VectorXd& residual, const Eigen::VectorXd& input, int max_lag) {
        ResidualCorrelations r = residual_correlations(residual, input, max_lag);
        return py::make_tuple(r.autocorrelation, r.cross_correlation);
      },
      py::arg("residual"), py::arg("input"), py::arg("max_lag"),
      "(r_ee at lags 0..max_lag, r_eu at lags -max_lag..max_lag), means removed "
      "(estimation/residual_correlation.h).");
  bind_result<ArmaModel>(m, "ARMA noise model D v = C e with standard errors (arma.h).");
  m.def("fit_arma", &fit_arma, py::arg("v"), py::arg("ar_order"), py::arg("ma_order"),
        py::arg("record_starts") = std::vector<Eigen::Index>{},
        "ARMA(p, q) of v by prediction-error minimisation from the Hannan-Rissanen estimate.");
  m.def("fit_arma_by_criterion", &fit_arma_by_criterion, py::arg("v"), py::arg("max_order"),
        py::arg("record_starts") = std::vector<Eigen::Index>{},
        "ARMA orders in 0..max_order each with the smallest BIC, fitted.");
  m.def("arma_innovations", &arma_innovations, py::arg("model"), py::arg("v"),
        py::arg("record_starts") = std::vector<Eigen::Index>{}, "e = (D/C) v from rest.");
  bind_result<PredictionReport>(m,
                                "k-step-ahead prediction of a Box-Jenkins model (prediction.h).");
  m.def("predict_ahead", &predict_ahead, py::arg("model"), py::arg("noise_model"), py::arg("data"),
        py::arg("horizon"),
        "y_hat(t | t - k) = G u + (1 - H_k D/C)(y - G u): the k-step-ahead prediction with a "
        "noise model (a RIVC result's noise_model).");
  bind_enum<InitialState>(m, "InitialState", "Where validate_model's simulation starts.");
  bind_options<ValidationOptions>(m, "Options of validate_model: initial state and window.");
  bind_result<ValidationReport>(m, "Residual statistics of a model.")
      .def_property_readonly("residual_white", &ValidationReport::residual_white,
                             "Autocorrelation within the 99 % band.")
      .def_property_readonly("residual_uncorrelated_with_input",
                             &ValidationReport::residual_uncorrelated_with_input,
                             "Cross-correlation within the 99 % band.");
  m.def("validate_model",
        py::overload_cast<const AdditiveModel&, const SampledData&, int>(&validate_model),
        py::arg("model"), py::arg("data"), py::arg("max_lag") = 20,
        "Fit and residual statistics of a model on data, simulated from rest.");
  m.def("validate_model",
        py::overload_cast<const AdditiveModel&, const SampledData&, const ValidationOptions&>(
            &validate_model),
        py::arg("model"), py::arg("data"), py::arg("options"),
        "Fit and residual statistics on options' window, from rest or from the least-squares "
        "initial state; both fits are reported.");
  bind_result<MimoValidationReport>(m, "Per-output fit and residual statistics of a MIMO model.");
  m.def("validate_model",
        py::overload_cast<const MimoAdditiveModel&, const MimoData&, const ValidationOptions&>(
            &validate_model),
        py::arg("model"), py::arg("data"), py::arg("options") = ValidationOptions{},
        "Per-output fit (from rest and from the least-squares initial state) and residual "
        "statistics of a model with several inputs and outputs.");
  m.def("validation_output", &validation_output, py::arg("model"), py::arg("data"),
        py::arg("options") = ValidationOptions{},
        "The output validate_model scores, over the whole record.");
  m.def("free_responses", &free_responses, py::arg("model"), py::arg("samples"),
        py::arg("sample_time"), "Sampled free responses of the model's realisation (columns).");
  m.def("residual_report", &residual_report, py::arg("data"), py::arg("modelled"),
        py::arg("max_lag") = 20,
        "The statistics of validate_model for any simulated output `modelled` of the record.");
  m.def("persistent_excitation_order", &persistent_excitation_order, py::arg("x"),
        py::arg("max_order"), py::arg("tolerance") = 1e-9, "Order of PE seen in the record.");
  m.def("largest_pole_frequency", &largest_pole_frequency, py::arg("model"),
        "Largest |Im pole| [rad/s].");
  bind_result<MimoMode>(m, "A mode shared by every channel: w_n, zeta, shape, participation.");
  m.def("modal_assurance",
        py::overload_cast<const Eigen::VectorXcd&, const Eigen::VectorXcd&>(&modal_assurance),
        py::arg("a"), py::arg("b"), "MAC of two shapes: |a^H b|^2 / ((a^H a)(b^H b)).");
  m.def("modal_assurance",
        py::overload_cast<const std::vector<MimoMode>&, const std::vector<MimoMode>&>(
            &modal_assurance),
        py::arg("a"), py::arg("b"), "MAC matrix of two lists of modes.");
}

}  // namespace ctid::python
