// The batch summary (batch_summary.h): rows read back from the records' documents.
#include "ctid/io/batch_summary.h"

#include <algorithm>
#include <filesystem>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"

namespace ctid::io {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kSummaryCsvHeader = "name,data,status,";

std::string summary_csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// A JSON value as a cell: numbers exactly as the document holds them, null empty.
std::string summary_cell(const json& value) {
  if (value.is_null()) return "";
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_number_float()) return format_round_trip(value.get<double>());
  return value.dump();
}

json summary_number(const json& object, const char* key) {
  const auto it = object.find(key);
  return it != object.end() && it->is_number() ? *it : json(nullptr);
}

std::optional<json> read_json_if_readable(const std::string& file) {
  try {
    return read_json(file);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::string join_in(const std::string& dir, const std::string& file) {
  return (fs::path(dir) / file).string();
}

struct SummaryRow {
  json fields = json::object();  // name, data, status, usable, fit_percent, estimator, seconds,
                                 // message
  json modes = json::array();    // {frequency_hz, frequency_se_hz, damping, damping_se}
};

// The kinds of document whose modes the summary reads.
enum class ModeSource { siso, mimo, output_only };

// The modes of a document: a SISO fit gives them in Hz, a MIMO one (MimoMode) in rad/s, an
// output-only one (OmaMode) in Hz with *_std standard errors.
json summary_modes(const json& document, ModeSource source) {
  json rows = json::array();
  const auto modes = document.find("modes");
  if (modes == document.end() || !modes->is_array()) return rows;
  for (const json& mode : *modes) {
    if (!mode.is_object()) continue;
    if (source == ModeSource::output_only) {
      rows.push_back({{"frequency_hz", summary_number(mode, "frequency_hz")},
                      {"frequency_se_hz", summary_number(mode, "frequency_hz_std")},
                      {"damping", summary_number(mode, "damping_ratio")},
                      {"damping_se", summary_number(mode, "damping_ratio_std")}});
      continue;
    }
    if (source == ModeSource::mimo) {
      const auto hz = [&](const char* key) {
        const json value = summary_number(mode, key);
        return value.is_null() ? value : json(value.get<double>() / (2.0 * std::numbers::pi));
      };
      rows.push_back({{"frequency_hz", hz("natural_frequency")},
                      {"frequency_se_hz", hz("natural_frequency_se")},
                      {"damping", summary_number(mode, "damping_ratio")},
                      {"damping_se", summary_number(mode, "damping_ratio_se")}});
      continue;
    }
    rows.push_back(
        {{"frequency_hz", summary_number(mode, "natural_frequency_hz")},
         {"frequency_se_hz", summary_number(mode, "natural_frequency_hz_standard_error")},
         {"damping", summary_number(mode, "damping_ratio")},
         {"damping_se", summary_number(mode, "damping_ratio_standard_error")}});
  }
  return rows;
}

// The row of a record whose fit wrote its document.
void fill_from_document(SummaryRow& row, const json& document) {
  const json& verdict = document["verdict"];
  const bool usable = verdict.is_object() && verdict.value("usable", false);
  row.fields["status"] = usable ? "ok" : "no_usable_model";
  row.fields["usable"] = usable;
  row.fields["fit_percent"] = summary_number(document, "fit_percent");
  if (document.contains("estimator")) row.fields["estimator"] = document["estimator"];
  const std::string type = document.value("type", "");
  const bool mimo = type == "mimo_estimation_result";
  if (type == "oma_result" && document.contains("method")) {
    row.fields["estimator"] = document["method"];  // ssi-cov, ssi-data, fdd, efdd
  }
  if (mimo) {
    // Several outputs: one fit per output, reported as their mean.
    row.fields["estimator"] = "mimo_srivc";
    const auto fits = document.find("fit_percent");
    if (fits != document.end() && fits->is_array() && !fits->empty()) {
      double sum = 0.0;
      bool finite = true;
      for (const json& fit : *fits) {
        finite = finite && fit.is_number();
        if (fit.is_number()) sum += fit.get<double>();
      }
      if (finite) row.fields["fit_percent"] = sum / static_cast<double>(fits->size());
    }
  }
  if (!usable && verdict.is_object()) {
    std::string reasons;
    if (verdict.contains("reasons") && verdict["reasons"].is_array()) {
      for (const json& reason : verdict["reasons"]) {
        if (reason.is_string())
          reasons += (reasons.empty() ? "" : "; ") + reason.get<std::string>();
      }
    }
    row.fields["message"] = reasons;
  }
  row.modes = summary_modes(document, mimo                   ? ModeSource::mimo
                                      : type == "oma_result" ? ModeSource::output_only
                                                             : ModeSource::siso);
}

SummaryRow summary_row(const BatchRecordFiles& record, const std::map<std::string, double>& times) {
  SummaryRow row;
  row.fields["name"] = record.name;
  std::string data;
  for (const std::string& file : record.data) data += (data.empty() ? "" : ";") + file;
  row.fields["data"] = data;
  row.fields["status"] = "failed";
  row.fields["usable"] = nullptr;
  row.fields["fit_percent"] = nullptr;
  row.fields["estimator"] = nullptr;
  const auto time = times.find(record.name);
  row.fields["seconds"] = time != times.end() ? json(time->second) : json(nullptr);
  row.fields["message"] = "";
  if (fs::exists(record.output)) {
    const std::optional<json> document = read_json_if_readable(record.output);
    if (!document || !document->is_object() || !document->contains("verdict")) {
      row.fields["message"] = record.output + " is not a ctid result document";
      return row;
    }
    fill_from_document(row, *document);
    return row;
  }
  if (fs::exists(record.error_output)) {
    const std::optional<json> error = read_json_if_readable(record.error_output);
    row.fields["message"] = error && error->is_object() && (*error)["message"].is_string()
                                ? (*error)["message"].get<std::string>()
                                : record.error_output + " cannot be read";
    return row;
  }
  row.fields["status"] = "not_run";
  return row;
}

// Whether a summary may replace `file`: missing, or a summary a batch wrote.
bool summary_is_ours_or_missing(const std::string& file, bool is_json) {
  if (!fs::exists(file)) return true;
  try {
    if (is_json) {
      const json document = read_json(file);
      return document.is_object() && document.value("type", "") == "ctid_batch_summary";
    }
    return read_text_file(file).rfind(kSummaryCsvHeader, 0) == 0;
  } catch (const std::exception&) {
    return false;
  }
}

std::string summary_csv(const std::vector<SummaryRow>& rows, std::size_t most_modes) {
  std::string csv = "name,data,status,usable,fit_percent,estimator";
  for (std::size_t k = 1; k <= most_modes; ++k) {
    const std::string mode = "mode" + std::to_string(k);
    csv += "," + mode + "_frequency_hz," + mode + "_frequency_se_hz," + mode + "_damping," + mode +
           "_damping_se";
  }
  csv += ",seconds,message\n";
  for (const SummaryRow& row : rows) {
    for (const char* key : {"name", "data", "status", "usable", "fit_percent", "estimator"}) {
      csv +=
          (std::string(key) == "name" ? "" : ",") + summary_csv_cell(summary_cell(row.fields[key]));
    }
    for (std::size_t k = 0; k < most_modes; ++k) {
      for (const char* key : {"frequency_hz", "frequency_se_hz", "damping", "damping_se"}) {
        csv +=
            "," + (k < row.modes.size() ? summary_csv_cell(summary_cell(row.modes[k][key])) : "");
      }
    }
    csv += "," + summary_csv_cell(summary_cell(row.fields["seconds"])) + "," +
           summary_csv_cell(summary_cell(row.fields["message"])) + "\n";
  }
  return csv;
}

}  // namespace

void check_batch_summary_files(const std::string& out_dir) {
  for (const char* name : {kBatchSummaryCsv, kBatchSummaryJson}) {
    const std::string file = join_in(out_dir, name);
    require(summary_is_ours_or_missing(file, std::string(name) == kBatchSummaryJson),
            file + ": file exists and is not a ctid batch summary; pass --force to replace it");
  }
}

std::map<std::string, double> read_batch_timings(const std::string& out_dir) {
  std::map<std::string, double> times;
  const std::string file = join_in(out_dir, kBatchTimings);
  if (!fs::exists(file)) return times;
  const std::optional<json> timings = read_json_if_readable(file);
  if (!timings || !timings->is_object()) return times;
  for (const auto& [name, seconds] : timings->items()) {
    if (seconds.is_number()) times[name] = seconds.get<double>();
  }
  return times;
}

void record_batch_timings(const std::string& out_dir,
                          const std::map<std::string, double>& seconds) {
  const std::string file = join_in(out_dir, kBatchTimings);
  std::optional<json> timings = fs::exists(file) ? read_json_if_readable(file) : std::nullopt;
  if (!timings || !timings->is_object()) timings = json::object();
  for (const auto& [name, time] : seconds) (*timings)[name] = time;
  write_text_file(file, json_text(*timings) + "\n", Overwrite::yes);
}

BatchCounts write_batch_summary(const std::string& out_dir,
                                const std::vector<BatchRecordFiles>& records) {
  const std::map<std::string, double> times = read_batch_timings(out_dir);
  std::vector<SummaryRow> rows;
  std::size_t most_modes = 0;
  BatchCounts counts;
  json summary_records = json::array();
  for (const BatchRecordFiles& record : records) {
    rows.push_back(summary_row(record, times));
    most_modes = std::max(most_modes, rows.back().modes.size());
    const std::string status = rows.back().fields["status"].get<std::string>();
    (status == "ok"                ? counts.ok
     : status == "no_usable_model" ? counts.no_usable_model
     : status == "failed"          ? counts.failed
                                   : counts.not_run) += 1;
    json entry = rows.back().fields;
    entry["modes"] = rows.back().modes;
    summary_records.push_back(std::move(entry));
  }
  const json summary = {{"type", "ctid_batch_summary"}, {"records", summary_records}};
  write_text_file(join_in(out_dir, kBatchSummaryCsv), summary_csv(rows, most_modes),
                  Overwrite::yes);
  write_text_file(join_in(out_dir, kBatchSummaryJson), json_text(summary) + "\n", Overwrite::yes);
  return counts;
}

}  // namespace ctid::io
