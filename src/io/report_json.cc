#include "ctid/io/report_json.h"

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
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
       "residual_uncorrelated_with_input", "bound_99", "model_file", "data", "prediction"},
      source);
}

nlohmann::json to_json(const OmaResult& result) { return document(result, kOmaResultType); }

OmaResult oma_result_from_json(const nlohmann::json& value, const std::string& source) {
  // "setups": each setup's own document beside the merged modes (`ctid oma` on several files).
  return document_fields<OmaResult>(value, kOmaResultType, {"data", "setups"}, source);
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
  // An FRF read from a table or a universal file has no DFT lines, variances, coherences or
  // input levels: those are written as -1 (lines) and null, in the shape the reader checks.
  const auto n = static_cast<Eigen::Index>(frf.response.size());
  const auto n_y = static_cast<Eigen::Index>(frf.output_count());
  const auto n_u = static_cast<Eigen::Index>(frf.input_count());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto shaped = [&](const Eigen::MatrixXd& m, Eigen::Index cols) {
    return m.rows() == n && m.cols() == cols ? m : Eigen::MatrixXd::Constant(n, cols, nan);
  };
  const bool has_variance = static_cast<Eigen::Index>(frf.variance.size()) == n;
  std::vector<int> line_numbers = frf.lines;
  if (static_cast<Eigen::Index>(line_numbers.size()) != n) {
    line_numbers.assign(static_cast<std::size_t>(n), -1);
  }
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
    variance.push_back(
        rows(has_variance ? frf.variance[l] : Eigen::MatrixXd::Constant(n_y, n_u, nan)));
  }
  nlohmann::json condition = nlohmann::json::array();
  for (Eigen::Index l = 0; l < n; ++l) {
    condition.push_back(frf.input_condition.size() == n ? nullable(frf.input_condition(l))
                                                        : nlohmann::json(nullptr));
  }
  return {{"type", kMimoFrfType},
          {"version", 1},
          {"inputs", frf.input_names},
          {"outputs", frf.output_names},
          {"lines", line_numbers},
          {"frequencies", std::vector<double>(frf.frequencies.data(),
                                              frf.frequencies.data() + frf.frequencies.size())},
          {"response", std::move(response)},
          {"variance", std::move(variance)},
          {"coherence", rows(shaped(frf.coherence, n_y))},
          {"output_power", rows(shaped(frf.output_power, n_y))},
          {"input_level", rows(shaped(frf.input_level, n_u))},
          {"input_condition", std::move(condition)},
          {"averages", frf.averages},
          {"block_length", frf.block_length}};
}

namespace {

// The readers of the mimo_frf arrays: every level's length is checked against the FRF's lines,
// outputs and inputs, and errors name the source and the entry ("response[3][0][1]").
class MimoFrfReader {
 public:
  MimoFrfReader(const nlohmann::json& value, const std::string& source)
      : value_(value), source_(source) {}

  const nlohmann::json& field(const char* key) const {
    const auto found = value_.find(key);
    require(found != value_.end(), source_, ": ", key, ": required field is missing");
    return *found;
  }
  const nlohmann::json& array(const nlohmann::json& v, std::size_t size,
                              const std::string& where) const {
    require(v.is_array() && v.size() == size, source_, ": ", where, ": expected an array of ", size,
            " entries");
    return v;
  }
  // A number; null is the writer's unknown value, NaN.
  double number(const nlohmann::json& v, const std::string& where) const {
    if (v.is_null()) return std::numeric_limits<double>::quiet_NaN();
    require(v.is_number(), source_, ": ", where, ": expected a number or null");
    return v.get<double>();
  }
  int integer(const nlohmann::json& v, const std::string& where) const {
    require(v.is_number_integer(), source_, ": ", where, ": expected an integer");
    return v.get<int>();
  }
  std::vector<std::string> names(const char* key) const {
    const nlohmann::json& v = field(key);
    require(v.is_array() && !v.empty(), source_, ": ", key, ": expected a non-empty array");
    std::vector<std::string> out;
    for (const auto& name : v) {
      require(name.is_string(), source_, ": ", key, ": expected names (strings)");
      out.push_back(name.get<std::string>());
    }
    return out;
  }
  // A (lines x columns) matrix written as one row per line.
  Eigen::MatrixXd matrix(const char* key, std::size_t lines, std::size_t columns) const {
    const nlohmann::json& rows = array(field(key), lines, key);
    Eigen::MatrixXd out(static_cast<Eigen::Index>(lines), static_cast<Eigen::Index>(columns));
    for (std::size_t l = 0; l < lines; ++l) {
      const std::string where = ctid::internal::concat(key, "[", l, "]");
      const nlohmann::json& row = array(rows[l], columns, where);
      for (std::size_t c = 0; c < columns; ++c) {
        out(static_cast<Eigen::Index>(l), static_cast<Eigen::Index>(c)) =
            number(row[c], ctid::internal::concat(where, "[", c, "]"));
      }
    }
    return out;
  }

 private:
  const nlohmann::json& value_;
  const std::string& source_;
};

}  // namespace

MimoFrf mimo_frf_from_json(const nlohmann::json& value, const std::string& source) {
  check_document(value, kMimoFrfType, source);
  check_keys(value,
             {"inputs", "outputs", "lines", "frequencies", "response", "variance", "coherence",
              "output_power", "input_level", "input_condition", "averages", "block_length"},
             {"type", "version", "method", "data", "peaks_of", "peaks"}, source);
  const MimoFrfReader read(value, source);
  MimoFrf frf;
  frf.input_names = read.names("inputs");
  frf.output_names = read.names("outputs");
  const std::size_t n_u = frf.input_names.size();
  const std::size_t n_y = frf.output_names.size();
  const nlohmann::json& frequencies = read.field("frequencies");
  require(frequencies.is_array(), source, ": frequencies: expected an array");
  const std::size_t lines = frequencies.size();
  frf.frequencies.resize(static_cast<Eigen::Index>(lines));
  const nlohmann::json& line_numbers = read.array(read.field("lines"), lines, "lines");
  const nlohmann::json& response = read.array(read.field("response"), lines, "response");
  const Eigen::MatrixXd coherence = read.matrix("coherence", lines, n_y);
  const Eigen::MatrixXd output_power = read.matrix("output_power", lines, n_y);
  const Eigen::MatrixXd input_level = read.matrix("input_level", lines, n_u);
  const nlohmann::json& condition =
      read.array(read.field("input_condition"), lines, "input_condition");
  const nlohmann::json& variance = read.array(read.field("variance"), lines, "variance");
  for (std::size_t l = 0; l < lines; ++l) {
    const auto e = static_cast<Eigen::Index>(l);
    frf.frequencies(e) =
        read.number(frequencies[l], ctid::internal::concat("frequencies[", l, "]"));
    frf.lines.push_back(read.integer(line_numbers[l], ctid::internal::concat("lines[", l, "]")));
    Eigen::MatrixXcd h(static_cast<Eigen::Index>(n_y), static_cast<Eigen::Index>(n_u));
    Eigen::MatrixXd v(static_cast<Eigen::Index>(n_y), static_cast<Eigen::Index>(n_u));
    const std::string at = ctid::internal::concat("[", l, "]");
    const nlohmann::json& h_rows = read.array(response[l], n_y, "response" + at);
    const nlohmann::json& v_rows = read.array(variance[l], n_y, "variance" + at);
    for (std::size_t j = 0; j < n_y; ++j) {
      const std::string row = ctid::internal::concat(at, "[", j, "]");
      const nlohmann::json& h_row = read.array(h_rows[j], n_u, "response" + row);
      const nlohmann::json& v_row = read.array(v_rows[j], n_u, "variance" + row);
      for (std::size_t i = 0; i < n_u; ++i) {
        const std::string entry = ctid::internal::concat(row, "[", i, "]");
        const nlohmann::json& pair = read.array(h_row[i], 2, "response" + entry);
        const auto r = static_cast<Eigen::Index>(j);
        const auto c = static_cast<Eigen::Index>(i);
        h(r, c) = {read.number(pair[0], "response" + entry + "[0]"),
                   read.number(pair[1], "response" + entry + "[1]")};
        v(r, c) = read.number(v_row[i], "variance" + entry);
      }
    }
    frf.response.push_back(std::move(h));
    frf.variance.push_back(std::move(v));
  }
  frf.coherence = coherence;
  frf.output_power = output_power;
  frf.input_level = input_level;
  frf.input_condition.resize(static_cast<Eigen::Index>(lines));
  for (std::size_t l = 0; l < lines; ++l) {
    frf.input_condition(static_cast<Eigen::Index>(l)) =
        read.number(condition[l], ctid::internal::concat("input_condition[", l, "]"));
  }
  frf.averages = read.integer(read.field("averages"), "averages");
  frf.block_length = read.integer(read.field("block_length"), "block_length");
  return frf;
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

nlohmann::json to_json(const MimoStructureScanResult& scan) {
  return document(scan, kMimoStructureScanResultType);
}

MimoStructureScanResult mimo_structure_scan_result_from_json(const nlohmann::json& value,
                                                             const std::string& source) {
  return document_fields<MimoStructureScanResult>(value, kMimoStructureScanResultType, {"data"},
                                                  source);
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
