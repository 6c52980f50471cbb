// The delayed_feedback_result document, from the result's field lists (io/fields_json.h).
#include "ctid/io/feedback_result_json.h"

#include <string>
#include <utility>

#include <Eigen/Core>

#include "ctid/core/error.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"

namespace ctid {

nlohmann::json to_json_value(const Polynomial& polynomial) {
  nlohmann::json out = nlohmann::json::array();
  for (int i = 0; i <= polynomial.degree(); ++i) out.push_back(polynomial.coefficient(i));
  return out;
}

Polynomial from_json_value(const nlohmann::json& value, std::type_identity<Polynomial>,
                           const std::string& where) {
  Eigen::VectorXd ascending;
  io::internal::value_from_json(value, ascending, where);
  try {
    return Polynomial(ascending);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(where + ": " + e.what());
  }
}

namespace {

// A transfer_function document (io/model_json.h) read field by field, so that the zero
// placeholder model of a result (an empty numerator) reads back as written.
TransferFunction transfer_function_json(const nlohmann::json& value, const std::string& where) {
  if (!value.is_object() || value.value("type", std::string()) != "transfer_function" ||
      !value.contains("numerator_ascending") || !value.contains("denominator_ascending"))
    throw InvalidArgument(where +
                          ": expected a transfer_function with numerator_ascending "
                          "and denominator_ascending");
  Polynomial numerator =
      from_json_value(value["numerator_ascending"], std::type_identity<Polynomial>{},
                      where + ".numerator_ascending");
  Polynomial denominator =
      from_json_value(value["denominator_ascending"], std::type_identity<Polynomial>{},
                      where + ".denominator_ascending");
  double input_delay = 0.0;
  if (value.contains("input_delay"))
    io::internal::value_from_json(value["input_delay"], input_delay, where + ".input_delay");
  try {
    return TransferFunction(std::move(numerator), std::move(denominator), input_delay);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(where + ": " + e.what());
  }
}

}  // namespace

nlohmann::json to_json_value(const DelayedFeedbackLoop& loop) { return io::to_json(loop); }

DelayedFeedbackLoop from_json_value(const nlohmann::json& value,
                                    std::type_identity<DelayedFeedbackLoop>,
                                    const std::string& where) {
  if (!value.is_object() || !value.contains("type") || value["type"] != "delayed_feedback_loop" ||
      !value.contains("forward") || !value.contains("feedback") || !value.contains("delay"))
    throw InvalidArgument(where +
                          ": expected a delayed_feedback_loop with forward, feedback and delay");
  double delay = 0.0;
  io::internal::value_from_json(value["delay"], delay, where + ".delay");
  return DelayedFeedbackLoop{transfer_function_json(value["forward"], where + ".forward"),
                             transfer_function_json(value["feedback"], where + ".feedback"), delay};
}

}  // namespace ctid

namespace ctid::io {

nlohmann::json to_json(const DelayedFeedbackResult& result) {
  nlohmann::json out = {{"type", kDelayedFeedbackResultType},
                        {"version", kDelayedFeedbackResultVersion}};
  out.update(fields_to_json(result));
  return out;
}

bool is_delayed_feedback_result(const nlohmann::json& value) {
  if (!value.is_object()) return false;
  const auto type = value.find("type");
  return type != value.end() && type->is_string() && *type == kDelayedFeedbackResultType;
}

DelayedFeedbackResult delayed_feedback_result_from_json(const nlohmann::json& value,
                                                        const std::string& source) {
  require(is_delayed_feedback_result(value), source, ": not a ", kDelayedFeedbackResultType,
          " document (its \"type\" must be \"", kDelayedFeedbackResultType, "\")");
  const auto version = value.find("version");
  require(version != value.end() && version->is_number_integer() &&
              version->get<int>() == kDelayedFeedbackResultVersion,
          source, ": version must be ", kDelayedFeedbackResultVersion);
  nlohmann::json fields = value;
  fields.erase("type");
  fields.erase("version");
  DelayedFeedbackResult result;
  fields_from_json(fields, result, source);
  return result;
}

DelayedFeedbackResult read_delayed_feedback_result(const std::filesystem::path& path) {
  return delayed_feedback_result_from_json(read_json(path), path.string());
}

void write_delayed_feedback_result(const std::filesystem::path& path,
                                   const DelayedFeedbackResult& result, Overwrite overwrite) {
  write_json(path, to_json(result), overwrite);
}

}  // namespace ctid::io
