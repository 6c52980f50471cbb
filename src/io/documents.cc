#include "ctid/io/documents.h"

#include <utility>

#include "ctid/core/error.h"
#include "ctid/io/json.h"
#include "ctid/io/report_json.h"
#include "ctid/io/result_json.h"

namespace ctid::io {

std::vector<std::string> result_document_types() {
  return {kEstimationResultType,
          kModeRelocationResultType,
          kInputDelayScanResultType,
          kValidationReportType,
          kFrfType,
          kStudySummaryType,
          std::string(kDelayedFeedbackResultType),
          kStructureScanResultType,
          kMimoEstimationResultType,
          kFrfMatrixFitResultType,
          kMimoFrfType,
          kOmaResultType,
          kMimoStructureScanResultType};
}

ResultDocument result_from_json(const nlohmann::json& value, const std::string& source) {
  require(value.is_object(), source, ": expected a JSON object");
  const auto type = value.find("type");
  std::string types;
  for (const std::string& t : result_document_types()) types += (types.empty() ? "" : ", ") + t;
  require(type != value.end() && type->is_string(), source,
          ": \"type\" is missing; a result document is one of ", types);
  const std::string name = type->get<std::string>();
  if (name == kEstimationResultType) return estimation_result_from_json(value, source);
  if (name == kModeRelocationResultType) return mode_relocation_result_from_json(value, source);
  if (name == kInputDelayScanResultType) return input_delay_scan_result_from_json(value, source);
  if (name == kValidationReportType) return validation_report_from_json(value, source);
  if (name == kFrfType) return frf_from_json(value, source);
  if (name == kStudySummaryType) return study_summary_from_json(value, source);
  if (name == kDelayedFeedbackResultType) return delayed_feedback_result_from_json(value, source);
  if (name == kStructureScanResultType) return structure_scan_result_from_json(value, source);
  if (name == kMimoEstimationResultType) return mimo_estimation_result_from_json(value, source);
  if (name == kFrfMatrixFitResultType) return frf_matrix_fit_result_from_json(value, source);
  if (name == kMimoFrfType) return mimo_frf_from_json(value, source);
  if (name == kOmaResultType) return oma_result_from_json(value, source);
  if (name == kMimoStructureScanResultType) {
    return mimo_structure_scan_result_from_json(value, source);
  }
  throw InvalidArgument(source + ": \"type\" is \"" + name +
                        "\", which is not a result document (" + types + ")");
}

ResultDocument read_result(const std::filesystem::path& path) {
  return result_from_json(read_json(path), path.string());
}

nlohmann::json to_json(const ResultDocument& result) {
  return std::visit([](const auto& r) { return to_json(r); }, result);
}

std::string_view document_type(const ResultDocument& result) {
  static const std::vector<std::string> types = result_document_types();
  return types.at(result.index());
}

void write_result(const std::filesystem::path& path, const ResultDocument& result,
                  Overwrite overwrite) {
  write_json(path, to_json(result), overwrite);
}

}  // namespace ctid::io
