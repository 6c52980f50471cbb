// SampledData records as CSV files with named columns (docs/formats.md): a time column
// checked for uniform sampling (SampledData::from_time_stamps), input, output and an
// optional reference. Errors name the file and the column; CsvTable errors name the line.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"
#include "ctid/io/csv.h"
#include "ctid/io/file.h"

namespace ctid::io {

/// Which CSV columns hold which signal.
struct CsvColumns {
  std::string time = "t";
  std::string input = "u";
  std::string output = "y";
  /// Empty: the record has no reference.
  std::string reference;
  /// Smallest allowed distance of a time stamp from the uniform grid, relative to the step;
  /// stamps printed to few digits are allowed more (SampledData::from_time_stamps).
  double relative_tolerance = 1e-6;

  static constexpr std::string_view type_name = "CsvColumns";
  static constexpr auto fields() {
    using O = CsvColumns;
    return std::tuple{
        field("time", &O::time, "Column of the time stamps."),
        field("input", &O::input, "Column of the input u."),
        field("output", &O::output, "Column of the output y."),
        field("reference", &O::reference, "Column of the reference r; empty: none."),
        field("relative_tolerance", &O::relative_tolerance, Between{0, 1},
              "Smallest allowed distance of a stamp from the uniform grid, relative to the step."),
    };
  }
  /// Time, input and output are named, and all names differ.
  void check_relations(const std::string& path) const;
  /// Throws InvalidArgument naming the field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// Where a uniform time column puts the samples.
using TimeGrid = UniformGrid;

/// Checks that `time_column` is uniformly sampled (ctid::uniform_grid's rule) and returns its
/// grid; errors name the table's source and the column. Every CSV reader of
/// records (SISO, MIMO, single signals) checks its time stamps here.
TimeGrid uniform_time_grid(const CsvTable& table, const std::string& time_column,
                           double relative_tolerance = 1e-6);

/// A uniformly sampled signal read from a table's time and value columns.
struct TimedSignal {
  double start_time = 0.0;
  double sample_time = 0.0;
  Eigen::VectorXd values;
};

/// Checks that `time_column` is uniformly sampled and returns it with `value_column`.
TimedSignal timed_signal_from_table(const CsvTable& table, const std::string& time_column,
                                    const std::string& value_column,
                                    double relative_tolerance = 1e-6);

/// The hold declared by a "# input_hold: zoh|foh" line, if any; throws InvalidArgument
/// naming the line for another value.
std::optional<Hold> declared_input_hold(const CsvTable& table);

/// The record, with the input hold the table declares (zero-order hold if none).
SampledData sampled_data_from_table(const CsvTable& table, const CsvColumns& columns = {});
SampledData read_sampled_data(const std::filesystem::path& path, const CsvColumns& columns = {});

/// A "# input_hold: foh" declaration for a first-order-hold input, then columns time, input,
/// output and (if the record has one and columns.reference is not
/// empty) reference, named as in `columns`.
CsvTable to_csv_table(const SampledData& data, const CsvColumns& columns = {});
void write_sampled_data(const std::filesystem::path& path, const SampledData& data,
                        const CsvColumns& columns = {}, Overwrite overwrite = Overwrite::no);

}  // namespace ctid::io
