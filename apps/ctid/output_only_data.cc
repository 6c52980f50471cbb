// Output-only records (output_only_data.h).
#include "output_only_data.h"

#include <cmath>
#include <utility>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/io/mimo_data_csv.h"
#include "ctid/io/npy.h"

namespace ctid::cli {

OutputOnlyRecord read_output_only(const std::string& file,
                                  const std::vector<std::string>& output_columns,
                                  const std::string& time_column, std::optional<double> sample_time,
                                  std::optional<PreprocessingOptions> preprocessing) {
  OutputOnlyRecord r;
  r.table = io::read_table(file);
  const io::CsvTable& table = r.table;
  r.start_time =
      table.has_column(time_column) && table.rows() > 0 ? table.column(time_column)(0) : 0.0;
  if (output_columns.empty()) {  // every column but the time column
    for (const std::string& name : table.names) {
      if (name != time_column) r.names.push_back(name);
    }
  } else {
    r.names = io::expand_columns(table, output_columns, "output");
  }
  r.outputs.resize(table.rows(), static_cast<Eigen::Index>(r.names.size()));
  for (std::size_t j = 0; j < r.names.size(); ++j) {
    r.outputs.col(static_cast<Eigen::Index>(j)) = table.column(r.names[j]);
  }
  if (sample_time) {
    r.sample_time = *sample_time;
  } else {
    if (!table.has_column(time_column)) {
      usage_error(internal::concat(file, " has no time column '", time_column,
                                   "'; give --sample-time (-T) or --time-column"));
    }
    const Eigen::VectorXd& t = table.column(time_column);
    require(t.size() >= 2, file, ": fewer than 2 samples");
    const double h = (t(t.size() - 1) - t(0)) / static_cast<double>(t.size() - 1);
    for (Eigen::Index k = 1; k < t.size(); ++k) {
      if (std::abs(t(k) - t(k - 1) - h) > 1e-3 * std::abs(h)) {
        usage_error(internal::concat(file, ": time column '", time_column,
                                     "' is not uniform at row ", k + 1,
                                     "; give --sample-time (-T) to override it"));
      }
    }
    r.sample_time = h;
  }
  if (preprocessing) {
    preprocessing->input_scale = 1.0;
    try {
      PreprocessedOutputs done =
          preprocess_outputs(r.outputs, r.sample_time, r.start_time, *preprocessing);
      r.outputs = std::move(done.outputs);
      r.sample_time = done.record.sample_time;
      r.start_time = done.start_time;
      r.preprocessing = std::move(done.record);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(file + ": " + e.what());
    }
  }
  return r;
}

}  // namespace ctid::cli
