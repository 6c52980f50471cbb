// JSON files for models (docs/formats.md): continuous TransferFunction, AdditiveModel,
// DiscreteTransferFunction (controllers C_d(q), noise filters) and DelayedFeedbackLoop (the
// loop of De Iuliis et al. 2017, Fig. 1; kept out of ContinuousModel, which fit and
// validate consume, because it is not a plain transfer function). Coefficients are stored in
// ASCENDING powers under fields named *_ascending (polynomial.h), e.g. 1 + 0.5 s is
// [1, 0.5]. Every document has a "type" field; unknown fields are rejected; errors name the
// file and the field.
#pragma once

#include <filesystem>
#include <string>
#include <type_traits>
#include <variant>

#include <nlohmann/json.hpp>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/mimo_model.h"
#include "ctid/core/transfer_function.h"
#include "ctid/io/file.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid::io {

/// The "type" values of the model formats.
/// The most integrators (poles at the origin) a submodel of a model document may have; the
/// readers refuse more, and ctid fit refuses to estimate more (it could not read them back).
inline constexpr int kMaxIntegrators = 16;
/// The highest polynomial degree a model file may hold: a continuous-time model beyond it is
/// numerically meaningless, and a file of millions of coefficients would only exhaust memory.
inline constexpr Eigen::Index kMaxModelDegree = 400;
inline constexpr const char* kTransferFunctionType = "transfer_function";
inline constexpr const char* kAdditiveModelType = "additive_model";
inline constexpr const char* kDiscreteTransferFunctionType = "discrete_transfer_function";
inline constexpr const char* kDelayedFeedbackLoopType = "delayed_feedback_loop";
inline constexpr const char* kMimoAdditiveModelType = "mimo_additive_model";

/// A continuous-time model as read from a file: unfactored or additive.
using ContinuousModel = std::variant<TransferFunction, AdditiveModel>;

nlohmann::json to_json(const TransferFunction& model);
nlohmann::json to_json(const AdditiveModel& model);
/// {"type": "mimo_additive_model", "inputs": n_u, "outputs": n_y, "submodels": [{
/// "denominator_ascending": A_i, "numerators_ascending": [R_i[0, 0], R_i[0, 1], ...] (output by
/// output, input by input)}], "direct": [[D[0, 0], ...], ...] (optional, one row per output)}.
nlohmann::json to_json(const MimoAdditiveModel& model);
nlohmann::json to_json(const DiscreteTransferFunction& model);
nlohmann::json to_json(const ContinuousModel& model);
/// {"type": "delayed_feedback_loop", "forward": F, "feedback": H, "delay": Δ}.
nlohmann::json to_json(const DelayedFeedbackLoop& model);

/// Readers of one format; `source` names the document in error messages. The model's own
/// validation (finite coefficients, non-zero leading coefficient, anti-monic A_i, ...) is
/// reported as InvalidArgument prefixed with the source and the field path.
TransferFunction transfer_function_from_json(const nlohmann::json& value,
                                             const std::string& source);
AdditiveModel additive_model_from_json(const nlohmann::json& value, const std::string& source);
MimoAdditiveModel mimo_additive_model_from_json(const nlohmann::json& value,
                                                const std::string& source);
DiscreteTransferFunction discrete_transfer_function_from_json(const nlohmann::json& value,
                                                              const std::string& source);
/// Reads a delayed_feedback_loop; F and H are transfer_function objects. The loop is
/// checked by DelayedFeedbackLoop::validate() (F, H strictly proper, Δ >= 0), its message
/// prefixed with the source.
DelayedFeedbackLoop delayed_feedback_loop_from_json(const nlohmann::json& value,
                                                    const std::string& source);
/// True when `value` is an object whose "type" is "delayed_feedback_loop".
bool is_delayed_feedback_loop(const nlohmann::json& value);
/// Dispatches on "type": transfer_function or additive_model.
ContinuousModel continuous_model_from_json(const nlohmann::json& value, const std::string& source);

ContinuousModel read_continuous_model(const std::filesystem::path& path);
DiscreteTransferFunction read_discrete_transfer_function(const std::filesystem::path& path);

/// A controller: C_d(q) of a digital loop or C(p) of an analog one (decision 0067).
using ControllerModel = std::variant<DiscreteTransferFunction, TransferFunction>;
/// Dispatches on "type": discrete_transfer_function or transfer_function; any other type is
/// refused naming both.
ControllerModel controller_from_json(const nlohmann::json& value, const std::string& source);
ControllerModel read_controller(const std::filesystem::path& path);

void write_model(const std::filesystem::path& path, const ContinuousModel& model,
                 Overwrite overwrite = Overwrite::no);
void write_model(const std::filesystem::path& path, const DiscreteTransferFunction& model,
                 Overwrite overwrite = Overwrite::no);

}  // namespace ctid::io

namespace ctid {

/// The hooks of io/fields_json.h for model types inside a field list (found by
/// argument-dependent lookup): the model documents above, read with `where` as the source.
nlohmann::json to_json_value(const TransferFunction& model);
nlohmann::json to_json_value(const AdditiveModel& model);
nlohmann::json to_json_value(const MimoAdditiveModel& model);
nlohmann::json to_json_value(const DiscreteTransferFunction& model);
TransferFunction from_json_value(const nlohmann::json& value, std::type_identity<TransferFunction>,
                                 const std::string& where);
AdditiveModel from_json_value(const nlohmann::json& value, std::type_identity<AdditiveModel>,
                              const std::string& where);
MimoAdditiveModel from_json_value(const nlohmann::json& value,
                                  std::type_identity<MimoAdditiveModel>, const std::string& where);
DiscreteTransferFunction from_json_value(const nlohmann::json& value,
                                         std::type_identity<DiscreteTransferFunction>,
                                         const std::string& where);

}  // namespace ctid
