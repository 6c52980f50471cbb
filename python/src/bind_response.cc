// Python bindings of time responses (simulation/time_response.h): step and impulse responses of
// a model or of an estimation result, with the step characteristics, their delta-method standard
// errors and the pointwise band. A result brings its own covariance and delay standard error; a
// transfer function is taken as one submodel B/(p^l A) (io/result_json.h), the parameterisation
// of an unfactored fit, so a covariance given with it is that of [a_1 ... a_n, b_0 ... b_m].
#include <optional>
#include <string>
#include <utility>

#include "common.h"
#include "ctid/identification/identification.h"
#include "ctid/io/result_json.h"
#include "ctid/simulation/time_response.h"
#include "fields.h"

namespace ctid::python {
namespace {

// The model, its covariance and the delay's standard error behind `model`: an EstimationResult,
// an AdditiveModel or a TransferFunction (with `covariance` and `delay_standard_error` when it
// is not a result).
io::FittedModel fitted_from(const py::object& model,
                            const std::optional<Eigen::MatrixXd>& covariance,
                            std::optional<double> delay_standard_error, const char* function) {
  if (py::isinstance<EstimationResult>(model)) {
    const auto& result = model.cast<const EstimationResult&>();
    io::FittedModel fitted{result.model, result.covariance, result.delay_standard_error};
    if (covariance) fitted.covariance = *covariance;
    if (delay_standard_error) fitted.delay_standard_error = *delay_standard_error;
    return fitted;
  }
  const auto additive = [&]() -> AdditiveModel {
    if (py::isinstance<AdditiveModel>(model)) return model.cast<AdditiveModel>();
    if (py::isinstance<TransferFunction>(model)) {
      return io::as_additive_model(model.cast<TransferFunction>());
    }
    throw py::type_error(std::string(function) +
                         "(): model must be an EstimationResult, AdditiveModel or "
                         "TransferFunction, not " +
                         py::str(py::type::of(model).attr("__name__")).cast<std::string>());
  };
  io::FittedModel fitted{additive(), {}};
  if (covariance) fitted.covariance = *covariance;
  if (delay_standard_error) fitted.delay_standard_error = *delay_standard_error;
  return fitted;
}

TimeResponse response_of(const char* function, ResponseKind kind, const py::object& model,
                         const std::optional<Eigen::MatrixXd>& covariance,
                         std::optional<double> delay_standard_error,
                         const std::optional<TimeResponseOptions>& options,
                         const py::kwargs& kwargs) {
  TimeResponseOptions o = options_from<TimeResponseOptions>(function, options, kwargs);
  o.kind = kind;
  if (py::isinstance<ProcessModelResult>(model)) {
    if (covariance || delay_standard_error) {
      throw py::type_error(std::string(function) +
                           "(): a ProcessModelResult carries its own covariance; give neither "
                           "covariance= nor delay_standard_error=");
    }
    return time_response(model.cast<const ProcessModelResult&>(), o);
  }
  const io::FittedModel f = fitted_from(model, covariance, delay_standard_error, function);
  return time_response(f.model, f.covariance, o, f.delay_standard_error);
}

}  // namespace

void bind_response(py::module_& m) {
  bind_enum<ResponseKind>(m, "ResponseKind", "Step or impulse (simulation/time_response.h).");
  bind_options<TimeResponseOptions>(m, "Grid, settling band and band confidence of a response.");
  bind_result<ResponseEstimate>(m, "A characteristic with its delta-method standard error.");
  bind_result<StepCharacteristics>(m, "DC gain, rise and settling time, overshoot (stepinfo).")
      .def("defined", &StepCharacteristics::defined,
           "Whether rise time, settling time and overshoot are defined.");
  bind_result<TimeResponse>(m, "A step or impulse response on a grid with its band.");
  m.attr("MAX_TIME_RESPONSE_POINTS") = kMaxTimeResponsePoints;

  const char* model_doc =
      "model: EstimationResult (its covariance and delay standard error give the standard "
      "errors and the band), ProcessModelResult (the band by the delta method in its "
      "process parameters), AdditiveModel or TransferFunction (with covariance= of its "
      "parameters, if any). Options as keywords (final_time, points, sample_time, "
      "settling_band, confidence) or options=TimeResponseOptions(...). Returns a TimeResponse.";
  for (const auto& [name, kind] : {std::pair{"step_response", ResponseKind::step},
                                   std::pair{"impulse_response", ResponseKind::impulse}}) {
    const ResponseKind k = kind;
    const char* function = name;
    m.def(
        name,
        [k, function](const py::object& model, const std::optional<Eigen::MatrixXd>& covariance,
                      std::optional<double> delay_standard_error,
                      const std::optional<TimeResponseOptions>& options, const py::kwargs& kwargs) {
          return response_of(function, k, model, covariance, delay_standard_error, options, kwargs);
        },
        py::arg("model"), py::arg("covariance") = py::none(),
        py::arg("delay_standard_error") = py::none(), py::arg("options") = py::none(),
        (std::string("The ") + enum_name(k).data() +
         " response of a model exactly on a time grid. " + model_doc)
            .c_str());
  }
  m.def(
      "step_response_at",
      [](const py::object& model, const Eigen::VectorXd& times) {
        return step_response(fitted_from(model, {}, {}, "step_response_at").model, times);
      },
      py::arg("model"), py::arg("times"),
      "Exact step response y(t) at each of `times` (any spacing; 0 before the input delay).");
  m.def(
      "impulse_response_at",
      [](const py::object& model, const Eigen::VectorXd& times) {
        return impulse_response(fitted_from(model, {}, {}, "impulse_response_at").model, times);
      },
      py::arg("model"), py::arg("times"),
      "Exact impulse response at each of `times`, without the Dirac part of a biproper model.");
  m.def(
      "step_characteristics",
      [](const py::object& model, const std::optional<Eigen::MatrixXd>& covariance,
         double settling_band, std::optional<double> delay_standard_error) {
        const io::FittedModel f =
            fitted_from(model, covariance, delay_standard_error, "step_characteristics");
        return step_characteristics(f.model, f.covariance, settling_band, f.delay_standard_error);
      },
      py::arg("model"), py::arg("covariance") = py::none(),
      py::arg("settling_band") = TimeResponseOptions{}.settling_band,
      py::arg("delay_standard_error") = py::none(),
      "StepCharacteristics of a model or result, with delta-method standard errors.");
}

}  // namespace ctid::python
