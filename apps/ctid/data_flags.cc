#include "data_flags.h"

#include <cmath>
#include <optional>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/io/csv.h"
#include "ctid/io/sampled_data_csv.h"

namespace ctid::cli {
namespace {

std::string column_list(const io::CsvTable& table) {
  std::string list;
  for (const std::string& name : table.names) list += (list.empty() ? "" : ", ") + name;
  return list;
}

}  // namespace

bool same_sample_time(double a, double b) { return std::abs(a - b) <= 1e-9 * std::abs(b); }

void DataFlags::add_to(CLI::App& app, const std::string& name, bool with_reference) {
  app.add_option(name, file, "CSV data file with a header row of column names")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--input-column", input_column, "Column holding the input u")
      ->capture_default_str()
      ->group("Data");
  app.add_option("--output-column", output_column, "Column holding the output y")
      ->capture_default_str()
      ->group("Data");
  if (with_reference) {
    app.add_option("--reference-column", reference_column,
                   "Column holding the reference r (closed loop only; default r)")
        ->group("Data");
  }
  app.add_option("--time-column", time_column, "Time column; its uniform step is the sample time")
      ->capture_default_str()
      ->group("Data");
  app.add_option("--sample-time,-T", sample_time,
                 "Sample time h in seconds, for data without a time column")
      ->check(CLI::PositiveNumber)
      ->group("Data");
}

SampledData DataFlags::load(const CLI::App& app, bool need_reference) const {
  const io::CsvTable table = io::read_csv(file);
  const bool reference_flag = app.get_option_no_throw("--reference-column") != nullptr &&
                              app.count("--reference-column") > 0;
  std::optional<Eigen::VectorXd> reference;
  std::string reference_name;
  if (need_reference) {
    reference_name = reference_column.empty() ? "r" : reference_column;
    if (!table.has_column(reference_name)) {
      usage_error(internal::concat("closed loop (--controller) needs the reference r, but ", file,
                                   " has no column '", reference_name, "' (columns: ",
                                   column_list(table), "); name it with --reference-column"));
    }
    reference = table.column(reference_name);
  } else if (reference_flag) {
    usage_error("--reference-column has no effect without --controller (open loop)");
  }
  const Eigen::VectorXd& u = table.column(input_column);
  const Eigen::VectorXd& y = table.column(output_column);
  const bool time_flag = app.count("--time-column") > 0;
  const bool h_flag = app.count("--sample-time") > 0;
  if (table.has_column(time_column)) {
    io::CsvColumns columns;
    columns.time = time_column;
    columns.input = input_column;
    columns.output = output_column;
    columns.reference = reference_name;
    SampledData data = io::sampled_data_from_table(table, columns);
    if (h_flag && !same_sample_time(sample_time, data.sample_time())) {
      usage_error(internal::concat("--sample-time ", format_number(sample_time),
                                   " disagrees with the time column '", time_column, "' of ", file,
                                   " (step ", format_number(data.sample_time()), " s)"));
    }
    return data;
  }
  if (time_flag) table.column(time_column);  // throws, naming the columns present
  if (!h_flag) {
    usage_error(internal::concat(file, " has no time column '", time_column,
                                 "'; give --sample-time (or --time-column)"));
  }
  try {
    return SampledData(sample_time, u, y, reference);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(file + ": " + e.what());
  }
}

}  // namespace ctid::cli
