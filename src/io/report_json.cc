#include "ctid/io/report_json.h"

#include <array>
#include <utility>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/model_json.h"
#include "ctid/io/result_json.h"

namespace ctid::io {
namespace {

// Fields of S from a document: its header and the keys in `extra` are checked and dropped,
// the rest is read strictly into a default S.
template <class S>
S document_fields(const nlohmann::json& value, const char* type,
                  const std::vector<std::string>& extra, const std::string& source) {
  check_document(value, type, source);
  std::vector<std::string> allowed{"type", "version"};
  allowed.insert(allowed.end(), extra.begin(), extra.end());
  check_keys(value, field_names<S>(), allowed, source);
  nlohmann::json rest = value;
  for (const auto& key : allowed) rest.erase(key);
  S object{};
  fields_from_json(rest, object, source + ": " + std::string(S::type_name));
  return object;
}

template <class S>
nlohmann::json document(const S& object, const char* type) {
  nlohmann::json value = fields_to_json(object);
  value["type"] = type;
  value["version"] = kResultDocumentVersion;
  return value;
}

}  // namespace

nlohmann::json to_json(const ValidationReport& report) {
  nlohmann::json value = document(report, kValidationReportType);
  nlohmann::json lags = nlohmann::json::array();
  for (int k = -report.max_lag; k <= report.max_lag; ++k) lags.push_back(k);
  value["autocorrelation_lags"] = {1, report.max_lag};
  value["cross_correlation_lags"] = std::move(lags);
  value["residual_white"] = report.residual_white();
  value["residual_uncorrelated_with_input"] = report.residual_uncorrelated_with_input();
  value["bound_99"] = value.at("whiteness_bound");
  return value;
}

ValidationReport validation_report_from_json(const nlohmann::json& value,
                                             const std::string& source) {
  return document_fields<ValidationReport>(
      value, kValidationReportType,
      {"autocorrelation_lags", "cross_correlation_lags", "residual_white",
       "residual_uncorrelated_with_input", "bound_99", "model_file", "data"},
      source);
}

nlohmann::json to_json(const Frf& frf) { return document(frf, kFrfType); }

Frf frf_from_json(const nlohmann::json& value, const std::string& source) {
  return document_fields<Frf>(value, kFrfType, {"method", "data", "peaks"}, source);
}

nlohmann::json to_json(const StudySummary& summary) { return document(summary, kStudySummaryType); }

StudySummary study_summary_from_json(const nlohmann::json& value, const std::string& source) {
  return document_fields<StudySummary>(value, kStudySummaryType, {}, source);
}

nlohmann::json to_json(const StructureScanResult& scan) {
  return document(scan, kStructureScanResultType);
}

StructureScanResult structure_scan_result_from_json(const nlohmann::json& value,
                                                    const std::string& source) {
  return document_fields<StructureScanResult>(value, kStructureScanResultType, {"data"}, source);
}

}  // namespace ctid::io
