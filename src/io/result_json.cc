#include "ctid/io/result_json.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <variant>

#include "ctid/core/error.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"

namespace ctid::io {
namespace {

using internal::number_or_null;

// The flat layout of a mode in the document back into a ModalEstimate's fields.
nlohmann::json modal_fields(const nlohmann::json& mode, const std::string& where) {
  require(mode.is_object(), where, ": expected an object");
  check_keys(mode, {"submodel"},
             {"natural_frequency", "natural_frequency_standard_error", "natural_frequency_hz",
              "natural_frequency_hz_standard_error", "damping_ratio",
              "damping_ratio_standard_error", "gain", "gain_standard_error"},
             where);
  nlohmann::json value = nlohmann::json::object();
  nlohmann::json error = nlohmann::json::object();
  for (const char* name : {"natural_frequency", "damping_ratio", "gain"}) {
    if (mode.contains(name)) value[name] = mode.at(name);
    const std::string se = std::string(name) + "_standard_error";
    if (mode.contains(se)) error[name] = mode.at(se);
  }
  nlohmann::json out = {{"value", value}, {"standard_error", error}};
  if (mode.contains("submodel")) out["submodel"] = mode.at("submodel");
  return out;
}

// Keys an estimation_result document holds besides the fields it writes under their own
// name: the header, values that restate the result, renamed fields and the context that
// `ctid fit` adds.
const std::vector<std::string>& estimation_extra_keys() {
  static const std::vector<std::string> keys{
      "type",      "version", "converged", "parameter_names", "input_delay", "data_checks",
      "estimator", "loop",    "data",      "controller",      "delay_scan",  "mode_relocation",
      "two_stage", "polish"};
  return keys;
}

const std::vector<std::string>& relocation_extra_keys() {
  // "criterion" is written by ctid fit beside the result, which does not hold it.
  static const std::vector<std::string> keys{"type", "version", "criterion"};
  return keys;
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
    require(row.is_array() && static_cast<Eigen::Index>(row.size()) == size, where, "[", i,
            "] must be an array of ", size, " numbers");
    for (Eigen::Index j = 0; j < size; ++j) {
      const nlohmann::json& x = row[static_cast<size_t>(j)];
      // A covariance with unknown entries is as good as none.
      if (x.is_null()) return {};
      require(x.is_number(), where, "[", i, "][", j, "] is not a number");
      c(i, j) = x.get<double>();
    }
  }
  return c;
}

}  // namespace

nlohmann::json modal_json(const ModalEstimate& mode) {
  const ModalParameters& v = mode.value;
  const ModalParameters& se = mode.standard_error;
  return {
      {"submodel", mode.submodel},
      {"natural_frequency", internal::number_or_null(v.natural_frequency)},
      {"natural_frequency_standard_error", internal::number_or_null(se.natural_frequency)},
      {"natural_frequency_hz", internal::number_or_null(v.natural_frequency / internal::kTwoPi)},
      {"natural_frequency_hz_standard_error",
       internal::number_or_null(se.natural_frequency / internal::kTwoPi)},
      {"damping_ratio", internal::number_or_null(v.damping_ratio)},
      {"damping_ratio_standard_error", internal::number_or_null(se.damping_ratio)},
      {"gain", internal::number_or_null(v.gain)},
      {"gain_standard_error", internal::number_or_null(se.gain)}};
}

std::vector<std::string> parameter_names(const AdditiveModel& model) {
  return model.parameter_names();
}

Termination termination_from_string(const std::string& name) {
  if (auto t = enum_from_name<Termination>(name)) return *t;
  throw InvalidArgument("unknown termination '" + name + "' (expected " +
                        enum_names<Termination>() + ")");
}

void check_document(const nlohmann::json& value, std::string_view type, const std::string& source) {
  require(value.is_object(), source, ": expected a JSON object");
  const auto t = value.find("type");
  require(t != value.end() && t->is_string(), source, ": \"type\" is missing; expected \"", type,
          "\"");
  require(t->get<std::string>() == type, source, ": \"type\" is \"", t->get<std::string>(),
          "\"; expected \"", type, "\"");
  const auto v = value.find("version");
  if (v == value.end()) return;
  require(v->is_number_integer() && v->get<long long>() == kResultDocumentVersion, source, ": ",
          type, " version ", v->dump(), " is not one this ctid reads (", kResultDocumentVersion,
          ")");
}

void check_keys(const nlohmann::json& value, const std::vector<std::string>& fields,
                const std::vector<std::string>& extra, const std::string& source) {
  for (const auto& item : value.items()) {
    const std::string& key = item.key();  // a named reference, which clang 14 lambdas capture
    const auto known = [&](const std::vector<std::string>& names) {
      return std::find(names.begin(), names.end(), key) != names.end();
    };
    if (known(fields) || known(extra)) continue;
    std::string all;
    for (const auto& name : fields) all += (all.empty() ? "" : ", ") + name;
    for (const auto& name : extra) all += (all.empty() ? "" : ", ") + name;
    throw InvalidArgument(source + ": unknown field '" + key + "'; the fields are " + all);
  }
}

// Written from the field list (so a new field reaches the document), with the model's delay
// in seconds as "input_delay" beside the fields' input_delay_samples, "data_checks" for the
// checks, and modes flat with frequencies in Hz beside.
nlohmann::json to_json(const EstimationResult& result) {
  nlohmann::json value = fields_to_json(result);
  value["input_delay"] = number_or_null(result.model.input_delay());
  value["data_checks"] = value.at("checks");
  value.erase("checks");
  nlohmann::json modes = nlohmann::json::array();
  for (const ModalEstimate& mode : result.modes) modes.push_back(modal_json(mode));
  value["modes"] = std::move(modes);
  value["type"] = kEstimationResultType;
  value["version"] = kResultDocumentVersion;
  value["converged"] = result.converged();
  value["parameter_names"] = parameter_names(result.model);
  return value;
}

EstimationResult estimation_result_from_json(const nlohmann::json& value,
                                             const std::string& source) {
  check_document(value, kEstimationResultType, source);
  std::vector<std::string> fields = field_names<EstimationResult>();
  fields.erase(std::find(fields.begin(), fields.end(), "checks"));
  check_keys(value, fields, estimation_extra_keys(), source);
  for (const char* key : {"model", "transfer_function"}) {
    require(value.contains(key), source, ": ", key, ": required field is missing");
  }
  EstimationResult result(
      additive_model_from_json(value.at("model"), source + ": model"),
      transfer_function_from_json(value.at("transfer_function"), source + ": transfer_function"));
  nlohmann::json rest = nlohmann::json::object();
  for (const auto& [key, element] : value.items()) {
    if (std::find(fields.begin(), fields.end(), key) != fields.end() && key != "model" &&
        key != "transfer_function" && key != "modes") {
      rest[key] = element;
    }
  }
  if (value.contains("data_checks")) rest["checks"] = value.at("data_checks");
  if (value.contains("modes")) {
    const nlohmann::json& modes = value.at("modes");
    require(modes.is_array(), source, ": modes: expected an array");
    nlohmann::json converted = nlohmann::json::array();
    for (std::size_t i = 0; i < modes.size(); ++i) {
      converted.push_back(modal_fields(modes[i], source + ": modes[" + std::to_string(i) + "]"));
    }
    rest["modes"] = std::move(converted);
  }
  fields_from_json(rest, result, source + ": " + std::string(EstimationResult::type_name));
  return result;
}

nlohmann::json relocation_summary_to_json(const ModeRelocationResult& result) {
  nlohmann::json value = fields_to_json(result);
  value.erase("estimate");
  value["type"] = kModeRelocationResultType;
  value["version"] = kResultDocumentVersion;
  return value;
}

nlohmann::json to_json(const ModeRelocationResult& result) {
  nlohmann::json value = relocation_summary_to_json(result);
  value["estimate"] = to_json(result.estimate);
  return value;
}

ModeRelocationResult mode_relocation_result_from_json(const nlohmann::json& value,
                                                      EstimationResult estimate,
                                                      const std::string& source) {
  check_document(value, kModeRelocationResultType, source);
  check_keys(value, field_names<ModeRelocationResult>(), relocation_extra_keys(), source);
  ModeRelocationResult result(std::move(estimate));
  nlohmann::json rest = value;
  for (const char* key : {"type", "version", "criterion", "estimate"}) rest.erase(key);
  fields_from_json(rest, result, source + ": " + std::string(ModeRelocationResult::type_name));
  return result;
}

ModeRelocationResult mode_relocation_result_from_json(const nlohmann::json& value,
                                                      const std::string& source) {
  check_document(value, kModeRelocationResultType, source);
  require(value.contains("estimate"), source, ": estimate: required field is missing");
  return mode_relocation_result_from_json(
      value, estimation_result_from_json(value.at("estimate"), source + ": estimate"), source);
}

nlohmann::json delay_scan_summary_to_json(const InputDelayScanResult& result) {
  nlohmann::json value = fields_to_json(result);
  value.erase("best");
  return value;
}

nlohmann::json to_json(const InputDelayScanResult& result) {
  nlohmann::json value = delay_scan_summary_to_json(result);
  value["type"] = kInputDelayScanResultType;
  value["version"] = kResultDocumentVersion;
  value["best"] = to_json(result.best);
  return value;
}

InputDelayScanResult input_delay_scan_result_from_json(const nlohmann::json& value,
                                                       const std::string& source) {
  check_document(value, kInputDelayScanResultType, source);
  check_keys(value, field_names<InputDelayScanResult>(), {"type", "version"}, source);
  require(value.contains("best"), source, ": best: required field is missing");
  InputDelayScanResult result{
      estimation_result_from_json(value.at("best"), source + ": best"), {}, {}, {}, {}, true, {}};
  nlohmann::json rest = value;
  for (const char* key : {"type", "version", "best"}) rest.erase(key);
  fields_from_json(rest, result, source + ": " + std::string(InputDelayScanResult::type_name));
  return result;
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
  // The estimate inside a relocation or delay-scan document is judged as a fit result is.
  if (type != value.end() && type->is_string() &&
      (type->get<std::string>() == kModeRelocationResultType ||
       type->get<std::string>() == kInputDelayScanResultType)) {
    check_document(value, type->get<std::string>(), source);
    const char* inner = type->get<std::string>() == kModeRelocationResultType ? "estimate" : "best";
    require(value.contains(inner), source, ": ", inner, ": required field is missing");
    return fitted_model_from_json(value.at(inner), source + ": " + inner);
  }
  if (type != value.end() && type->is_string() &&
      type->get<std::string>() == kEstimationResultType) {
    check_document(value, kEstimationResultType, source);
    const auto model = value.find("model");
    require(model != value.end(), source, ": model: required field is missing");
    FittedModel fitted{additive_model_from_json(*model, source + ": model"), {}};
    const auto covariance = value.find("covariance");
    if (covariance != value.end()) {
      fitted.covariance = covariance_field(*covariance, source, fitted.model.parameter_count());
    }
    const auto delay_error = value.find("delay_standard_error");
    if (delay_error != value.end() && delay_error->is_number()) {
      fitted.delay_standard_error = delay_error->get<double>();
      require(std::isfinite(fitted.delay_standard_error) && fitted.delay_standard_error >= 0.0,
              source, ": delay_standard_error is ", fitted.delay_standard_error,
              "; it must be finite and >= 0");
    }
    const auto noise = value.find("noise_model");
    if (noise != value.end() && !noise->is_null()) {
      fields_from_json(*noise, fitted.noise_model.emplace(), source + ": noise_model");
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

std::optional<PreprocessingRecord> fit_preprocessing(const std::filesystem::path& path) {
  const nlohmann::json document = read_json(path);
  const auto type = document.find("type");
  if (type == document.end() || *type != kEstimationResultType) return std::nullopt;
  const auto data = document.find("data");
  if (data == document.end() || !data->is_object() || !data->contains("preprocessing")) {
    return std::nullopt;
  }
  PreprocessingRecord record = PreprocessingRecord();
  fields_from_json(data->at("preprocessing"), record, path.string() + ": data.preprocessing");
  return record;
}

}  // namespace ctid::io
