// The summary of a batch (docs/batch.md): one row per record read back from the documents a run
// left in the output folder (OUT/<name>.json, or OUT/<name>.error.json for a record that
// failed) and the records' times (timings.json), written as summary.csv and summary.json. The
// command line's `ctid batch` and the Python package's runner both write it through here.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace ctid::io {

/// The files the batch itself writes in its output folder; no record may take their names.
inline constexpr const char* kBatchSummaryCsv = "summary.csv";
inline constexpr const char* kBatchSummaryJson = "summary.json";
inline constexpr const char* kBatchTimings = "timings.json";

/// One record as the summary reads it.
struct BatchRecordFiles {
  std::string name;
  std::vector<std::string> data;  ///< the data files, as the record's fit was given them
  std::string output;             ///< OUT/<name>.json
  std::string error_output;       ///< OUT/<name>.error.json
};

/// How many records ended each way.
struct BatchCounts {
  int ok = 0;               ///< a document with a usable model
  int no_usable_model = 0;  ///< a document whose verdict is not usable
  int failed = 0;           ///< an error document, or a document that cannot be read
  int not_run = 0;          ///< neither document
};

/// Refuses (InvalidArgument) a summary.csv or summary.json in `out_dir` that exists and was not
/// written by a batch, so that a summary never replaces a user's file unasked.
void check_batch_summary_files(const std::string& out_dir);

/// The records' times in seconds from `out_dir`/timings.json (empty when missing or unreadable).
std::map<std::string, double> read_batch_timings(const std::string& out_dir);
/// Adds `seconds` (record name -> time) to `out_dir`/timings.json, keeping the other records'.
void record_batch_timings(const std::string& out_dir, const std::map<std::string, double>& seconds);

/// Writes `out_dir`/summary.csv and summary.json for `records` (in their order) and returns the
/// counts. Each row: name, data, status (ok | no_usable_model | failed | not_run), usable,
/// fit_percent, estimator (an output-only record: its method), the modes' frequency (Hz),
/// damping and their standard errors, seconds, message (the reasons of a verdict, or the error).
BatchCounts write_batch_summary(const std::string& out_dir,
                                const std::vector<BatchRecordFiles>& records);

}  // namespace ctid::io
