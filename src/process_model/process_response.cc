// Time responses of a process model with the delta method in its parameters
// (process_response.h).
#include "ctid/process_model/process_response.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/error.h"

namespace ctid {
namespace {

constexpr double kNoError = std::numeric_limits<double>::quiet_NaN();

double process_difference_step(double value) {
  return value != 0.0 ? 1e-6 * std::abs(value) : 1e-9;
}

// The process model as one submodel B / (p^l A), A anti-monic (a process model has at most one
// integrator and no direct feedthrough), with its dead time as the input delay.
AdditiveModel process_additive_model(const ProcessStructure& structure,
                                     const Eigen::VectorXd& parameters) {
  const TransferFunction g = process_transfer_function(structure, parameters);
  const Eigen::VectorXd& den = g.denominator().coefficients();
  int integrators = 0;
  while (integrators < den.size() && den(integrators) == 0.0) ++integrators;
  const double scale = den(integrators);
  Polynomial a(Eigen::VectorXd(den.tail(den.size() - integrators) / scale));
  Polynomial b(Eigen::VectorXd(g.numerator().coefficients() / scale));
  return AdditiveModel({Submodel{std::move(a), std::move(b), integrators}}, g.input_delay());
}

Eigen::VectorXd response_on(const AdditiveModel& model, const Eigen::VectorXd& times,
                            ResponseKind kind) {
  return kind == ResponseKind::step ? step_response(model, times) : impulse_response(model, times);
}

// The characteristics' values in one vector, in the order of their standard errors below.
Eigen::VectorXd characteristic_values(const StepCharacteristics& c) {
  Eigen::VectorXd v(6);
  v << c.dc_gain.value, c.rise_time.value, c.settling_time.value, c.overshoot_percent.value,
      c.undershoot_percent.value, c.peak_time.value;
  return v;
}

void set_characteristic_errors(StepCharacteristics& c, const Eigen::VectorXd& variance) {
  ResponseEstimate* estimates[] = {&c.dc_gain,           &c.rise_time,          &c.settling_time,
                                   &c.overshoot_percent, &c.undershoot_percent, &c.peak_time};
  for (int j = 0; j < 6; ++j) {
    estimates[j]->standard_error =
        std::isfinite(estimates[j]->value) ? std::sqrt(std::max(0.0, variance(j))) : kNoError;
  }
  // A characteristic at its floor of 0 is not a smooth function of the parameters there.
  if (c.overshoot_percent.value == 0.0) c.overshoot_percent.standard_error = kNoError;
  if (c.undershoot_percent.value == 0.0) c.undershoot_percent.standard_error = kNoError;
}

}  // namespace

TimeResponse process_time_response(const ProcessModelResult& result,
                                   const TimeResponseOptions& options) {
  options.validate();
  const ProcessStructure structure = ProcessStructure::parse(result.structure);
  const auto p = static_cast<Eigen::Index>(structure.parameter_names().size());
  require(result.parameters.size() == p, "process_time_response: ", result.structure, " has ", p,
          " parameters but the result holds ", result.parameters.size());
  const bool with_covariance = result.covariance.size() > 0;
  require(!with_covariance || (result.covariance.rows() == p && result.covariance.cols() == p &&
                               result.covariance.allFinite()),
          "process_time_response: the covariance must be a finite ", p, " x ", p, " matrix");
  const AdditiveModel model = process_additive_model(structure, result.parameters);
  TimeResponse response = time_response(model, {}, options);
  if (!with_covariance) return response;

  Eigen::MatrixXd output_gradient(response.time.size(), p);
  Eigen::MatrixXd characteristic_gradient(6, p);
  for (Eigen::Index i = 0; i < p; ++i) {
    const double delta = process_difference_step(result.parameters(i));
    Eigen::VectorXd up = result.parameters;
    Eigen::VectorXd down = result.parameters;
    up(i) += delta;
    down(i) -= delta;
    const AdditiveModel model_up = process_additive_model(structure, up);
    const AdditiveModel model_down = process_additive_model(structure, down);
    output_gradient.col(i) = (response_on(model_up, response.time, response.kind) -
                              response_on(model_down, response.time, response.kind)) /
                             (2.0 * delta);
    characteristic_gradient.col(i) =
        (characteristic_values(step_characteristics(model_up, {}, options.settling_band)) -
         characteristic_values(step_characteristics(model_down, {}, options.settling_band))) /
        (2.0 * delta);
  }
  const Eigen::MatrixXd& P = result.covariance;
  response.standard_deviation =
      (output_gradient * P).cwiseProduct(output_gradient).rowwise().sum().cwiseMax(0.0).cwiseSqrt();
  response.lower = response.output - response.z * response.standard_deviation;
  response.upper = response.output + response.z * response.standard_deviation;
  const Eigen::VectorXd variance =
      (characteristic_gradient * P).cwiseProduct(characteristic_gradient).rowwise().sum();
  set_characteristic_errors(response.characteristics, variance);
  return response;
}

}  // namespace ctid
