#include "ctid/io/result_json.h"

#include <cmath>
#include <numbers>
#include <utility>
#include <variant>

#include "ctid/core/error.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"

namespace ctid::io {
namespace {

// JSON has no NaN or infinity; an unknown value is written as null.
nlohmann::json number(double x) {
  if (!std::isfinite(x)) return nullptr;
  return x;
}

nlohmann::json vector(const Eigen::VectorXd& v) {
  nlohmann::json array = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) array.push_back(number(v(i)));
  return array;
}

nlohmann::json matrix(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    rows.push_back(vector(m.row(i).transpose()));
  }
  return rows;
}

constexpr double kTwoPi = 2.0 * std::numbers::pi;

nlohmann::json modal_json(const ModalEstimate& mode) {
  const ModalParameters& v = mode.value;
  const ModalParameters& se = mode.standard_error;
  return {{"submodel", mode.submodel},
          {"natural_frequency", number(v.natural_frequency)},
          {"natural_frequency_standard_error", number(se.natural_frequency)},
          {"natural_frequency_hz", number(v.natural_frequency / kTwoPi)},
          {"natural_frequency_hz_standard_error", number(se.natural_frequency / kTwoPi)},
          {"damping_ratio", number(v.damping_ratio)},
          {"damping_ratio_standard_error", number(se.damping_ratio)},
          {"gain", number(v.gain)},
          {"gain_standard_error", number(se.gain)}};
}

nlohmann::json checks_json(const DataChecks& c) {
  return {{"excitation_order", c.excitation_order},
          {"excitation_order_required", c.excitation_order_required},
          {"persistently_exciting", c.persistently_exciting},
          {"largest_pole_frequency", number(c.largest_pole_frequency)},
          {"nyquist_frequency", number(c.nyquist_frequency)},
          {"sampling_rate_ok", c.sampling_rate_ok},
          {"warnings", c.warnings}};
}

Eigen::MatrixXd covariance_field(const nlohmann::json& value, const std::string& source,
                                 Eigen::Index size) {
  const std::string where = source + ": covariance: ";
  require(value.is_array(), where, "expected an array of rows");
  if (value.empty()) return {};
  require(static_cast<Eigen::Index>(value.size()) == size, where, "has ", value.size(),
          " rows but the model has ", size, " parameters");
  Eigen::MatrixXd c(size, size);
  for (Eigen::Index i = 0; i < size; ++i) {
    const nlohmann::json& row = value[static_cast<size_t>(i)];
    require(row.is_array() && static_cast<Eigen::Index>(row.size()) == size, where, "row ", i,
            " must be an array of ", size, " numbers");
    for (Eigen::Index j = 0; j < size; ++j) {
      const nlohmann::json& x = row[static_cast<size_t>(j)];
      // A covariance with unknown entries is as good as none.
      if (x.is_null()) return {};
      require(x.is_number(), where, "row ", i, " entry ", j, " is not a number");
      c(i, j) = x.get<double>();
    }
  }
  return c;
}

}  // namespace

std::vector<std::string> parameter_names(const AdditiveModel& model) {
  std::vector<std::string> names;
  const std::vector<SubmodelOrder> orders = model.orders();
  for (size_t i = 0; i < orders.size(); ++i) {
    const std::string prefix = "theta" + std::to_string(i + 1) + ".";
    for (int k = 1; k <= orders[i].n; ++k) names.push_back(prefix + "a" + std::to_string(k));
    for (int k = 0; k <= orders[i].m; ++k) names.push_back(prefix + "b" + std::to_string(k));
  }
  return names;
}

Termination termination_from_string(const std::string& name) {
  if (auto t = enum_from_name<Termination>(name)) return *t;
  throw InvalidArgument("unknown termination '" + name + "' (expected " +
                        enum_names<Termination>() + ")");
}

nlohmann::json to_json(const EstimationResult& result) {
  nlohmann::json modes = nlohmann::json::array();
  for (const ModalEstimate& mode : result.modes) modes.push_back(modal_json(mode));
  nlohmann::json history = nlohmann::json::array();
  for (const IterationRecord& record : result.history) {
    history.push_back({{"iteration", record.iteration},
                       {"parameters", vector(record.parameters)},
                       {"relative_change", number(record.relative_change)},
                       {"off_diagonal_norm", number(record.off_diagonal_norm)}});
  }
  nlohmann::json value = {{"type", kEstimationResultType},
                          {"model", to_json(result.model)},
                          {"transfer_function", to_json(result.transfer_function)},
                          {"additive_view", result.additive_view ? to_json(*result.additive_view)
                                                                 : nlohmann::json(nullptr)},
                          {"parameter_names", parameter_names(result.model)},
                          {"parameters", vector(result.parameters)},
                          {"standard_errors", vector(result.standard_errors)},
                          {"covariance", matrix(result.covariance)},
                          {"modes", std::move(modes)},
                          {"termination", to_string(result.termination)},
                          {"converged", result.converged()},
                          {"message", result.message},
                          {"iterations", result.iterations},
                          {"relative_change", number(result.relative_change)},
                          {"off_diagonal_norm", number(result.off_diagonal_norm)},
                          {"unstable_reflections", result.unstable_reflections},
                          {"sensitivity_fallbacks", result.sensitivity_fallbacks},
                          {"input_delay_samples", result.input_delay},
                          {"input_delay", number(result.model.input_delay())},
                          {"noise_variance", number(result.noise_variance)},
                          {"mean_squared_error", number(result.mean_squared_error)},
                          {"fit_percent", number(result.fit_percent)},
                          {"data_checks", checks_json(result.checks)},
                          {"history", std::move(history)}};
  return value;
}

AdditiveModel as_additive_model(const TransferFunction& model) {
  require(model.is_proper(), "the transfer function ", model.to_string(),
          " is improper (numerator degree above denominator degree)");
  const Eigen::VectorXd& den = model.denominator().coefficients();
  int integrators = 0;
  while (integrators < den.size() && den(integrators) == 0.0) ++integrators;
  const double scale = den(integrators);
  Polynomial a(Eigen::VectorXd(den.tail(den.size() - integrators) / scale));
  Polynomial b(Eigen::VectorXd(model.numerator().coefficients() / scale));
  std::vector<Submodel> submodels{Submodel{std::move(a), std::move(b), integrators}};
  return AdditiveModel(std::move(submodels), model.input_delay());
}

FittedModel fitted_model_from_json(const nlohmann::json& value, const std::string& source) {
  require(value.is_object(), source, ": expected a JSON object");
  const auto type = value.find("type");
  if (type != value.end() && type->is_string() &&
      type->get<std::string>() == kEstimationResultType) {
    const auto model = value.find("model");
    require(model != value.end(), source, ": model: required field is missing");
    FittedModel fitted{additive_model_from_json(*model, source + ": model"), {}};
    const auto covariance = value.find("covariance");
    if (covariance != value.end()) {
      fitted.covariance = covariance_field(*covariance, source, fitted.model.parameter_count());
    }
    return fitted;
  }
  const ContinuousModel model = continuous_model_from_json(value, source);
  if (const auto* additive = std::get_if<AdditiveModel>(&model)) return {*additive, {}};
  return {as_additive_model(std::get<TransferFunction>(model)), {}};
}

FittedModel read_fitted_model(const std::filesystem::path& path) {
  return fitted_model_from_json(read_json(path), path.string());
}

}  // namespace ctid::io
