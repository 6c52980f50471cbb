// Estimation results as JSON (docs/formats.md, docs/cli-estimation.md): everything in an
// EstimationResult of the refined IV estimators (González et al., Sections 3-5: model in its
// additive and unfactored views, beta, the Theorem 3.2 covariance, delta-method modal errors, why
// the iteration (29) stopped, the Lemma 4.4 norm, data checks), the mode relocation and delay scan
// results around it, all read back bit for bit; and reading a fitted model back, from a
// result document or a plain model document (model_json.h), for `ctid validate`.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ctid/core/additive_model.h"
#include "ctid/core/preprocessing.h"
#include "ctid/core/transfer_function.h"
#include "ctid/io/file.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/input_delay_scan.h"
#include "ctid/refined_iv/mode_relocation.h"

namespace ctid::io {

/// The "type" of a result document.
inline constexpr const char* kEstimationResultType = "estimation_result";
inline constexpr const char* kModeRelocationResultType = "mode_relocation_result";
inline constexpr const char* kInputDelayScanResultType = "input_delay_scan_result";

/// The "version" every result document of this release writes; readers accept it (and
/// documents without a "version", written before it existed) and refuse any other.
inline constexpr int kResultDocumentVersion = 1;

/// Checks that `value` is an object whose "type" is `type` and whose "version", if present,
/// is one this release reads. Throws InvalidArgument naming `source`.
void check_document(const nlohmann::json& value, std::string_view type, const std::string& source);

/// Throws InvalidArgument naming `source` and the first key of `value` that is neither a
/// field of the document's struct (`fields`) nor one of `extra` (keys written beside the
/// fields: "type", "version", derived values, context of the command that wrote it).
void check_keys(const nlohmann::json& value, const std::vector<std::string>& fields,
                const std::vector<std::string>& extra, const std::string& source);

/// A mode as the documents write it: value and standard error of ω_n (rad/s and Hz), ζ and the
/// gain, null where not finite.
nlohmann::json modal_json(const ModalEstimate& mode);

/// Names of the stacked parameters beta = [theta_1; ...; theta_K] (eq. 3 order), one per
/// entry: "theta1.a1", ..., "theta1.b0", ... (submodels counted from 1, as in the paper).
std::vector<std::string> parameter_names(const AdditiveModel& model);

/// Termination from its to_string() name; throws InvalidArgument for another name.
Termination termination_from_string(const std::string& name);

/// The result as one JSON object with "type": "estimation_result". Its "model" field is an
/// additive_model document (model_json.h) that ctid simulate/validate read as it is; NaN
/// (unknown standard errors) is written as null. Frequencies are rad/s, with Hz beside.
nlohmann::json to_json(const EstimationResult& result);

/// Reads an estimation_result document back (the inverse of to_json, bit for bit; NaN read
/// back from null). Keys that only restate the result ("converged", "parameter_names",
/// "input_delay" in seconds) and the context `ctid fit` writes beside it ("estimator",
/// "loop", "data", "controller", "delay_scan", "mode_relocation") are accepted and not read.
EstimationResult estimation_result_from_json(const nlohmann::json& value,
                                             const std::string& source);

/// A mode relocation result as a "mode_relocation_result" document: its fields, with
/// "estimate" an estimation_result document.
nlohmann::json to_json(const ModeRelocationResult& result);
/// The same without "estimate": the "mode_relocation" sub-document of a fit result, whose
/// estimate is the enclosing document.
nlohmann::json relocation_summary_to_json(const ModeRelocationResult& result);
/// Reads a mode_relocation_result document (with its "estimate").
ModeRelocationResult mode_relocation_result_from_json(const nlohmann::json& value,
                                                      const std::string& source);
/// Reads a sub-document written by relocation_summary_to_json, the estimate given.
ModeRelocationResult mode_relocation_result_from_json(const nlohmann::json& value,
                                                      EstimationResult estimate,
                                                      const std::string& source);

/// A delay scan as an "input_delay_scan_result" document: "best" an estimation_result
/// document, then delays, mean_squared_errors (null where the estimator refused the delay)
/// and terminations, one per delay.
nlohmann::json to_json(const InputDelayScanResult& result);
/// The same without "best": the "delay_scan" sub-document of a fit result.
nlohmann::json delay_scan_summary_to_json(const InputDelayScanResult& result);
InputDelayScanResult input_delay_scan_result_from_json(const nlohmann::json& value,
                                                       const std::string& source);

/// A model to judge against data, with the covariance of model.parameters() when known.
struct FittedModel {
  AdditiveModel model;
  /// Empty when the document holds no covariance (a plain model file).
  Eigen::MatrixXd covariance;
  /// Standard error of an estimated continuous input delay [s]; 0 when the delay was given,
  /// chosen from whole samples, or the document is a plain model file.
  double delay_standard_error = 0.0;
  /// The ARMA noise model of a fit with a noise model (RIVC); none otherwise.
  std::optional<ArmaModel> noise_model = std::nullopt;
};

/// One unfactored transfer function as a single additive submodel B/(p^l A) with A
/// anti-monic (l = poles at the origin). Throws InvalidArgument if the model is improper.
AdditiveModel as_additive_model(const TransferFunction& model);

/// Reads a result document (the "model" and "covariance" of an estimation_result, of the
/// "estimate" of a mode_relocation_result or of the "best" of an input_delay_scan_result)
/// or a transfer_function / additive_model document. Errors name `source` and the field.
FittedModel fitted_model_from_json(const nlohmann::json& value, const std::string& source);
FittedModel read_fitted_model(const std::filesystem::path& path);

/// What the record of a `ctid fit` result went through (its `data.preprocessing`: the trend
/// removed, the scales); nullopt for any other document (a plain model file, a result without
/// it). `ctid validate --detrend fit` removes that trend from the validation record.
std::optional<PreprocessingRecord> fit_preprocessing(const std::filesystem::path& path);

}  // namespace ctid::io
