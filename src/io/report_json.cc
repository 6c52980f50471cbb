#include "ctid/io/report_json.h"

#include <array>
#include <cmath>
#include <cstddef>
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

nlohmann::json to_json(const MimoFrf& frf) {
  const auto nullable = [](double x) { return std::isfinite(x) ? nlohmann::json(x) : nullptr; };
  const auto rows = [&](const Eigen::MatrixXd& m) {
    nlohmann::json out = nlohmann::json::array();
    for (Eigen::Index r = 0; r < m.rows(); ++r) {
      nlohmann::json row = nlohmann::json::array();
      for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(nullable(m(r, c)));
      out.push_back(std::move(row));
    }
    return out;
  };
  nlohmann::json response = nlohmann::json::array();
  nlohmann::json variance = nlohmann::json::array();
  for (std::size_t l = 0; l < frf.response.size(); ++l) {
    nlohmann::json h = nlohmann::json::array();
    for (Eigen::Index j = 0; j < frf.response[l].rows(); ++j) {
      nlohmann::json row = nlohmann::json::array();
      for (Eigen::Index i = 0; i < frf.response[l].cols(); ++i) {
        row.push_back(
            {nullable(frf.response[l](j, i).real()), nullable(frf.response[l](j, i).imag())});
      }
      h.push_back(std::move(row));
    }
    response.push_back(std::move(h));
    variance.push_back(rows(frf.variance[l]));
  }
  nlohmann::json condition = nlohmann::json::array();
  for (Eigen::Index l = 0; l < frf.input_condition.size(); ++l) {
    condition.push_back(nullable(frf.input_condition(l)));
  }
  return {{"type", kMimoFrfType},
          {"version", 1},
          {"inputs", frf.input_names},
          {"outputs", frf.output_names},
          {"lines", frf.lines},
          {"frequencies", std::vector<double>(frf.frequencies.data(),
                                              frf.frequencies.data() + frf.frequencies.size())},
          {"response", std::move(response)},
          {"variance", std::move(variance)},
          {"coherence", rows(frf.coherence)},
          {"output_power", rows(frf.output_power)},
          {"input_level", rows(frf.input_level)},
          {"input_condition", std::move(condition)},
          {"averages", frf.averages},
          {"block_length", frf.block_length}};
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

nlohmann::json to_json(const MimoEstimationResult& result) {
  return document(result, kMimoEstimationResultType);
}

MimoEstimationResult mimo_estimation_result_from_json(const nlohmann::json& value,
                                                      const std::string& source) {
  return document_fields<MimoEstimationResult>(value, kMimoEstimationResultType, {"data"}, source);
}

nlohmann::json to_json(const FrfMatrixFitResult& result) {
  return document(result, kFrfMatrixFitResultType);
}

FrfMatrixFitResult frf_matrix_fit_result_from_json(const nlohmann::json& value,
                                                   const std::string& source) {
  return document_fields<FrfMatrixFitResult>(value, kFrfMatrixFitResultType, {"data"}, source);
}

}  // namespace ctid::io
