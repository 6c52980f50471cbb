// Estimation results as JSON (docs/cli-estimation.md): everything in an EstimationResult of
// the refined IV estimators (González et al., Sections 3-5: model in its additive and
// unfactored views, beta, the Theorem 3.2 covariance, delta-method modal errors, why the
// iteration (29) stopped, the Lemma 4.4 norm, data checks), and reading a fitted model back,
// from a result document or a plain model document (model_json.h), for `ctid validate`.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ctid/core/additive_model.h"
#include "ctid/core/transfer_function.h"
#include "ctid/io/file.h"
#include "ctid/refined_iv/estimation_result.h"

namespace ctid::io {

/// The "type" of a result document.
inline constexpr const char* kEstimationResultType = "estimation_result";

/// Names of the stacked parameters beta = [theta_1; ...; theta_K] (eq. 3 order), one per
/// entry: "theta1.a1", ..., "theta1.b0", ... (submodels counted from 1, as in the paper).
std::vector<std::string> parameter_names(const AdditiveModel& model);

/// Termination from its to_string() name; throws InvalidArgument for another name.
Termination termination_from_string(const std::string& name);

/// The result as one JSON object with "type": "estimation_result". Its "model" field is an
/// additive_model document (model_json.h) that ctid simulate/validate read as it is; NaN
/// (unknown standard errors) is written as null. Frequencies are rad/s, with Hz beside.
nlohmann::json to_json(const EstimationResult& result);

/// A model to judge against data, with the covariance of model.parameters() when known.
struct FittedModel {
  AdditiveModel model;
  /// Empty when the document holds no covariance (a plain model file).
  Eigen::MatrixXd covariance;
};

/// One unfactored transfer function as a single additive submodel B/(p^l A) with A
/// anti-monic (l = poles at the origin). Throws InvalidArgument if the model is improper.
AdditiveModel as_additive_model(const TransferFunction& model);

/// Reads a result document (its "model" and "covariance") or a transfer_function /
/// additive_model document. Errors name `source` and the field.
FittedModel fitted_model_from_json(const nlohmann::json& value, const std::string& source);
FittedModel read_fitted_model(const std::filesystem::path& path);

}  // namespace ctid::io
