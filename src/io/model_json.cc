#include "ctid/io/model_json.h"

#include <utility>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/io/json.h"

namespace ctid::io {
namespace {

// The zero polynomial (no coefficients) is written [0.0], which the readers take back.
nlohmann::json coefficients(const Polynomial& p) {
  if (p.coefficients().size() == 0) return nlohmann::json::array({0.0});
  nlohmann::json array = nlohmann::json::array();
  for (Eigen::Index k = 0; k < p.coefficients().size(); ++k) array.push_back(p.coefficients()(k));
  return array;
}

// Runs a core constructor and prefixes its validation message with where the values came
// from, so the user learns which file and which field to fix.
template <typename Make>
auto construct(const JsonObject& object, std::string_view what, Make&& make) {
  try {
    return make();
  } catch (const InvalidArgument& e) {
    const std::string where = object.path().empty() ? std::string(what) : object.path();
    throw InvalidArgument(ctid::internal::concat(object.source(), ": ", where, ": ", e.what()));
  }
}

Polynomial polynomial_field(const JsonObject& object, std::string_view key) {
  const Eigen::VectorXd c = object.numbers(key);
  if (c.size() > kMaxModelDegree + 1) {
    object.fail(key, ctid::internal::concat("has ", c.size(),
                                            " coefficients; ctid reads polynomials of "
                                            "degree at most ",
                                            kMaxModelDegree));
  }
  try {
    return Polynomial(c);
  } catch (const InvalidArgument& e) {
    object.fail(key, e.what());
  }
}

void check_type(const JsonObject& object, std::string_view expected) {
  const std::string type = object.string("type");
  if (type != expected) {
    object.fail("type",
                ctid::internal::concat("is '", type, "' but a ", expected, " is expected here"));
  }
  object.string_or("description", "");
}

TransferFunction read_transfer_function(const JsonObject& object) {
  check_type(object, kTransferFunctionType);
  Polynomial numerator = polynomial_field(object, "numerator_ascending");
  Polynomial denominator = polynomial_field(object, "denominator_ascending");
  const double delay = object.number_or("input_delay", 0.0);
  object.finish();
  return construct(object, "transfer function", [&] {
    return TransferFunction(std::move(numerator), std::move(denominator), delay);
  });
}

AdditiveModel read_additive_model(const JsonObject& object) {
  check_type(object, kAdditiveModelType);
  std::vector<Submodel> submodels;
  for (const JsonObject& entry : object.objects("submodels")) {
    Submodel submodel;
    submodel.a = polynomial_field(entry, "denominator_ascending");
    submodel.b = polynomial_field(entry, "numerator_ascending");
    const long long integrators = entry.integer_or("integrators", 0);
    if (integrators < 0 || integrators > kMaxIntegrators) {
      entry.fail("integrators",
                 ctid::internal::concat("is ", integrators, "; it must be between 0 and ",
                                        kMaxIntegrators));
    }
    submodel.integrators = static_cast<int>(integrators);
    entry.string_or("description", "");
    entry.finish();
    submodels.push_back(std::move(submodel));
  }
  const double delay = object.number_or("input_delay", 0.0);
  object.finish();
  return construct(object, "additive model",
                   [&] { return AdditiveModel(std::move(submodels), delay); });
}

MimoAdditiveModel read_mimo_additive_model(const JsonObject& object) {
  check_type(object, kMimoAdditiveModelType);
  const long long inputs = object.integer("inputs");
  const long long outputs = object.integer("outputs");
  if (inputs < 1 || inputs > 100000) object.fail("inputs", "must be between 1 and 100000");
  if (outputs < 1 || outputs > 100000) object.fail("outputs", "must be between 1 and 100000");
  std::vector<MimoSubmodel> submodels;
  for (const JsonObject& entry : object.objects("submodels")) {
    MimoSubmodel submodel;
    submodel.a = polynomial_field(entry, "denominator_ascending");
    const std::vector<Eigen::VectorXd> rows = entry.number_rows("numerators_ascending");
    if (static_cast<long long>(rows.size()) != inputs * outputs) {
      entry.fail("numerators_ascending",
                 ctid::internal::concat("has ", rows.size(), " numerators; ", outputs,
                                        " outputs x ", inputs, " inputs need ", inputs * outputs,
                                        " (output by output, input by input)"));
    }
    // A numerator written with trailing zeros ([0.5, 0.0]) is the polynomial it denotes.
    for (const Eigen::VectorXd& row : rows) {
      if (row.size() > kMaxModelDegree + 1) {
        entry.fail(
            "numerators_ascending",
            ctid::internal::concat("has a numerator of ", row.size(),
                                   " coefficients; ctid reads polynomials of degree at most ",
                                   kMaxModelDegree));
      }
      submodel.b.push_back(Polynomial::trimmed(row));
    }
    const long long integrators = entry.integer_or("integrators", 0);
    if (integrators < 0 || integrators > kMaxIntegrators) {
      entry.fail("integrators",
                 ctid::internal::concat("is ", integrators, "; it must be between 0 and ",
                                        kMaxIntegrators));
    }
    submodel.integrators = static_cast<int>(integrators);
    entry.string_or("description", "");
    entry.finish();
    submodels.push_back(std::move(submodel));
  }
  Eigen::MatrixXd direct;
  if (object.has("direct")) {
    const std::vector<Eigen::VectorXd> rows = object.number_rows("direct");
    if (static_cast<long long>(rows.size()) != outputs) {
      object.fail("direct",
                  ctid::internal::concat("has ", rows.size(), " rows; it needs one per output (",
                                         outputs, ")"));
    }
    direct.resize(outputs, inputs);
    for (size_t j = 0; j < rows.size(); ++j) {
      if (rows[j].size() != inputs) {
        object.fail("direct",
                    ctid::internal::concat("[", j, "] has ", rows[j].size(),
                                           " entries; it needs one per input (", inputs, ")"));
      }
      direct.row(static_cast<Eigen::Index>(j)) = rows[j].transpose();
    }
  }
  Eigen::VectorXd delays;
  if (object.has("input_delays")) {
    delays = object.numbers("input_delays");
    if (delays.size() != inputs) {
      object.fail("input_delays", ctid::internal::concat("has ", delays.size(),
                                                         " entries; it needs one per input (",
                                                         inputs, ") in seconds"));
    }
  }
  object.finish();
  return construct(object, "MIMO additive model", [&] {
    return MimoAdditiveModel(static_cast<int>(inputs), static_cast<int>(outputs),
                             std::move(submodels), direct, delays);
  });
}

DiscreteTransferFunction read_discrete_transfer_function(const JsonObject& object) {
  check_type(object, kDiscreteTransferFunctionType);
  Polynomial numerator = polynomial_field(object, "numerator_ascending");
  Polynomial denominator = polynomial_field(object, "denominator_ascending");
  const double sample_time = object.number("sample_time");
  object.finish();
  return construct(object, "discrete transfer function", [&] {
    return DiscreteTransferFunction(std::move(numerator), std::move(denominator), sample_time);
  });
}

DelayedFeedbackLoop read_delayed_feedback_loop(const JsonObject& object) {
  check_type(object, kDelayedFeedbackLoopType);
  TransferFunction forward = read_transfer_function(object.object("forward"));
  TransferFunction feedback = read_transfer_function(object.object("feedback"));
  const double delay = object.number("delay");
  object.finish();
  DelayedFeedbackLoop loop{std::move(forward), std::move(feedback), delay};
  construct(object, "delayed feedback loop", [&] {
    loop.validate();
    return 0;
  });
  return loop;
}

}  // namespace

nlohmann::json to_json(const TransferFunction& model) {
  return {{"type", kTransferFunctionType},
          {"numerator_ascending", coefficients(model.numerator())},
          {"denominator_ascending", coefficients(model.denominator())},
          {"input_delay", model.input_delay()}};
}

nlohmann::json to_json(const AdditiveModel& model) {
  nlohmann::json submodels = nlohmann::json::array();
  for (const Submodel& s : model.submodels()) {
    submodels.push_back({{"denominator_ascending", coefficients(s.a)},
                         {"numerator_ascending", coefficients(s.b)},
                         {"integrators", s.integrators}});
  }
  return {{"type", kAdditiveModelType},
          {"submodels", std::move(submodels)},
          {"input_delay", model.input_delay()}};
}

nlohmann::json to_json(const DiscreteTransferFunction& model) {
  return {{"type", kDiscreteTransferFunctionType},
          {"numerator_ascending", coefficients(model.numerator())},
          {"denominator_ascending", coefficients(model.denominator())},
          {"sample_time", model.sample_time()}};
}

nlohmann::json to_json(const ContinuousModel& model) {
  return std::visit([](const auto& m) { return to_json(m); }, model);
}

nlohmann::json to_json(const DelayedFeedbackLoop& model) {
  return {{"type", kDelayedFeedbackLoopType},
          {"forward", to_json(model.forward)},
          {"feedback", to_json(model.feedback)},
          {"delay", model.delay}};
}

TransferFunction transfer_function_from_json(const nlohmann::json& value,
                                             const std::string& source) {
  return read_transfer_function(JsonObject(value, source));
}

nlohmann::json to_json(const MimoAdditiveModel& model) {
  nlohmann::json submodels = nlohmann::json::array();
  for (const MimoSubmodel& s : model.submodels()) {
    nlohmann::json numerators = nlohmann::json::array();
    for (const Polynomial& b : s.b) numerators.push_back(coefficients(b));
    nlohmann::json entry = {{"denominator_ascending", coefficients(s.a)},
                            {"numerators_ascending", numerators}};
    if (s.integrators > 0) entry["integrators"] = s.integrators;
    submodels.push_back(std::move(entry));
  }
  nlohmann::json out = {{"type", kMimoAdditiveModelType},
                        {"inputs", model.inputs()},
                        {"outputs", model.outputs()},
                        {"submodels", submodels}};
  if (model.has_direct_term()) {
    nlohmann::json rows = nlohmann::json::array();
    for (Eigen::Index j = 0; j < model.direct().rows(); ++j) {
      nlohmann::json row = nlohmann::json::array();
      for (Eigen::Index k = 0; k < model.direct().cols(); ++k) row.push_back(model.direct()(j, k));
      rows.push_back(row);
    }
    out["direct"] = rows;
  }
  if (model.has_input_delays()) {
    out["input_delays"] =
        std::vector<double>(model.input_delays().begin(), model.input_delays().end());
  }
  return out;
}

MimoAdditiveModel mimo_additive_model_from_json(const nlohmann::json& value,
                                                const std::string& source) {
  return read_mimo_additive_model(JsonObject(value, source));
}

AdditiveModel additive_model_from_json(const nlohmann::json& value, const std::string& source) {
  return read_additive_model(JsonObject(value, source));
}

DiscreteTransferFunction discrete_transfer_function_from_json(const nlohmann::json& value,
                                                              const std::string& source) {
  return read_discrete_transfer_function(JsonObject(value, source));
}

DelayedFeedbackLoop delayed_feedback_loop_from_json(const nlohmann::json& value,
                                                    const std::string& source) {
  return read_delayed_feedback_loop(JsonObject(value, source));
}

bool is_delayed_feedback_loop(const nlohmann::json& value) {
  if (!value.is_object()) return false;
  const auto type = value.find("type");
  return type != value.end() && type->is_string() && *type == kDelayedFeedbackLoopType;
}

ContinuousModel continuous_model_from_json(const nlohmann::json& value, const std::string& source) {
  const JsonObject object(value, source);
  const std::string type = object.string("type");
  if (type == kTransferFunctionType) return read_transfer_function(object);
  if (type == kAdditiveModelType) return read_additive_model(object);
  object.fail("type",
              ctid::internal::concat("is '", type, "'; a continuous-time model file needs '",
                                     kTransferFunctionType, "' or '", kAdditiveModelType, "'"));
}

ContinuousModel read_continuous_model(const std::filesystem::path& path) {
  return continuous_model_from_json(read_json(path), path.string());
}

DiscreteTransferFunction read_discrete_transfer_function(const std::filesystem::path& path) {
  return discrete_transfer_function_from_json(read_json(path), path.string());
}

ControllerModel controller_from_json(const nlohmann::json& value, const std::string& source) {
  const auto type = value.is_object() ? value.find("type") : value.end();
  const bool named = type != value.end() && type->is_string();
  if (named && *type == kTransferFunctionType) return transfer_function_from_json(value, source);
  if (named && *type == kDiscreteTransferFunctionType) {
    return discrete_transfer_function_from_json(value, source);
  }
  throw InvalidArgument(ctid::internal::concat(
      source, ": \"type\" is ", named ? "\"" + type->get<std::string>() + "\"" : "missing",
      "; a controller is a \"", kDiscreteTransferFunctionType,
      "\" (C_d(q), a digital loop) or a \"", kTransferFunctionType, "\" (C(p), an analog loop)"));
}

ControllerModel read_controller(const std::filesystem::path& path) {
  return controller_from_json(read_json(path), path.string());
}

void write_model(const std::filesystem::path& path, const ContinuousModel& model,
                 Overwrite overwrite) {
  write_json(path, to_json(model), overwrite);
}

void write_model(const std::filesystem::path& path, const DiscreteTransferFunction& model,
                 Overwrite overwrite) {
  write_json(path, to_json(model), overwrite);
}

}  // namespace ctid::io

namespace ctid {

nlohmann::json to_json_value(const TransferFunction& model) { return io::to_json(model); }
nlohmann::json to_json_value(const AdditiveModel& model) { return io::to_json(model); }
nlohmann::json to_json_value(const MimoAdditiveModel& model) { return io::to_json(model); }
nlohmann::json to_json_value(const DiscreteTransferFunction& model) { return io::to_json(model); }
TransferFunction from_json_value(const nlohmann::json& value, std::type_identity<TransferFunction>,
                                 const std::string& where) {
  return io::transfer_function_from_json(value, where);
}
AdditiveModel from_json_value(const nlohmann::json& value, std::type_identity<AdditiveModel>,
                              const std::string& where) {
  return io::additive_model_from_json(value, where);
}
MimoAdditiveModel from_json_value(const nlohmann::json& value,
                                  std::type_identity<MimoAdditiveModel>, const std::string& where) {
  return io::mimo_additive_model_from_json(value, where);
}
DiscreteTransferFunction from_json_value(const nlohmann::json& value,
                                         std::type_identity<DiscreteTransferFunction>,
                                         const std::string& where) {
  return io::discrete_transfer_function_from_json(value, where);
}

}  // namespace ctid
