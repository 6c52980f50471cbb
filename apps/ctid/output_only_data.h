// Records with no input for `ctid oma` and `ctid track --output-only`: output columns of a CSV
// or .npy file (every column but the time column unless named), the sample time from a uniform
// time column or given, each channel preprocessed alike (core/mimo_preprocessing.h).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/mimo_preprocessing.h"
#include "ctid/io/csv.h"

namespace ctid::cli {

struct OutputOnlyRecord {
  Eigen::MatrixXd outputs;  ///< N x l
  std::vector<std::string> names;
  double sample_time = 0.0;
  double start_time = 0.0;  ///< the first time stamp (0 without a time column)
  std::optional<PreprocessingRecord> preprocessing;
  io::CsvTable table;  ///< the file as read (reference columns are found in it)
};

/// `file`'s channels `output_columns` (names or ranges A:B; empty: every column but
/// `time_column`), the sample time `sample_time` when given, else from the uniform time
/// column; preprocessed when `preprocessing` is given (its input scale ignored). A usage error
/// names what is missing or not uniform; preprocessing errors are prefixed with the file.
OutputOnlyRecord read_output_only(const std::string& file,
                                  const std::vector<std::string>& output_columns,
                                  const std::string& time_column, std::optional<double> sample_time,
                                  std::optional<PreprocessingOptions> preprocessing);

}  // namespace ctid::cli
