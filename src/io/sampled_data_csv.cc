#include "ctid/io/sampled_data_csv.h"

#include <cmath>
#include <optional>

#include "core/internal/signal_range.h"
#include "ctid/core/error.h"
#include "ctid/io/npy.h"

namespace ctid::io {

void CsvColumns::check_relations(const std::string& path) const {
  require(!time.empty(), path, ".time is empty; it must name the time column");
  require(!input.empty(), path, ".input is empty; it must name the input column");
  require(!output.empty(), path, ".output is empty; it must name the output column");
  require(
      time != input && time != output && input != output &&
          (reference.empty() || (reference != time && reference != input && reference != output)),
      path, " names '", time, "', '", input, "', '", output, "', '", reference,
      "' must differ from each other");
}

TimeGrid uniform_time_grid(const CsvTable& table, const std::string& time_column,
                           double relative_tolerance) {
  const Eigen::VectorXd& time = table.column(time_column);
  try {
    return uniform_grid(time, relative_tolerance);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(
        ctid::internal::concat(table.source, ": column '", time_column, "': ", e.what()));
  }
}

TimedSignal timed_signal_from_table(const CsvTable& table, const std::string& time_column,
                                    const std::string& value_column, double relative_tolerance) {
  const Eigen::VectorXd& values = table.column(value_column);
  const TimeGrid grid = uniform_time_grid(table, time_column, relative_tolerance);
  return TimedSignal{grid.start_time, grid.sample_time, values};
}

std::optional<Hold> declared_input_hold(const CsvTable& table) {
  const CsvDeclaration* d = table.declaration("input_hold");
  if (d == nullptr) return std::nullopt;
  if (d->value == "zoh" || d->value == "zero_order_hold") return Hold::zero_order_hold;
  if (d->value == "foh" || d->value == "first_order_hold") return Hold::first_order_hold;
  throw InvalidArgument(ctid::internal::concat(table.source, ":", d->line, ": input_hold is '",
                                               d->value, "'; it must be zoh or foh"));
}

SampledData sampled_data_from_table(const CsvTable& table, const CsvColumns& columns) {
  columns.validate();
  table.column(columns.time);  // a missing column is named before the stamps are checked
  const Eigen::VectorXd& input = table.column(columns.input);
  const Eigen::VectorXd& output = table.column(columns.output);
  std::optional<Eigen::VectorXd> reference;
  if (!columns.reference.empty()) reference = table.column(columns.reference);
  for (const std::string* name : {&columns.input, &columns.output, &columns.reference}) {
    if (name->empty()) continue;
    ctid::internal::require_magnitude_in_range(table.column(*name),
                                               table.source + ": column '" + *name + "'");
  }
  const Hold hold = declared_input_hold(table).value_or(Hold::zero_order_hold);
  const TimeGrid grid = uniform_time_grid(table, columns.time, columns.relative_tolerance);
  return SampledData(grid.sample_time, input, output, std::move(reference), grid.start_time)
      .with_input_hold(hold);
}

SampledData read_sampled_data(const std::filesystem::path& path, const CsvColumns& columns) {
  columns.validate();
  return sampled_data_from_table(read_table(path), columns);
}

CsvTable to_csv_table(const SampledData& data, const CsvColumns& columns) {
  columns.validate();
  CsvTable table;
  if (data.input_hold() != Hold::zero_order_hold) {
    table.declarations.push_back({"input_hold", "foh", 0});
  }
  table.add_column(columns.time, data.time());
  table.add_column(columns.input, data.input());
  table.add_column(columns.output, data.output());
  if (data.has_reference() && !columns.reference.empty()) {
    table.add_column(columns.reference, data.reference());
  }
  return table;
}

void write_sampled_data(const std::filesystem::path& path, const SampledData& data,
                        const CsvColumns& columns, Overwrite overwrite) {
  write_csv(path, to_csv_table(data, columns), overwrite);
}

}  // namespace ctid::io
