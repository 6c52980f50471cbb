// MimoData records as CSV files with named columns (docs/formats.md): a time column checked
// for uniform sampling by the same rule as a SISO record (io::uniform_time_grid), then the
// chosen input, output and optional reference columns. Each column list entry is a column
// name or a range "A:B", every column from A to B in the file's order (both included).
// Errors name the file and the column: "d.csv: output column 'y29' not found; columns are ...".
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "ctid/core/fields.h"
#include "ctid/core/mimo_data.h"
#include "ctid/io/csv.h"
#include "ctid/io/file.h"

namespace ctid::io {

/// Which CSV columns hold which signals of a multi-input, multi-output record.
struct MimoCsvColumns {
  std::string time = "t";
  /// Input columns, in order: names or ranges "A:B" (at least one column).
  std::vector<std::string> inputs;
  /// Output columns, in order: names or ranges "A:B" (at least one column).
  std::vector<std::string> outputs;
  /// Reference columns, one per input; empty: the record has no references.
  std::vector<std::string> references;
  /// Smallest allowed distance of a time stamp from the uniform grid, relative to the step
  /// (SampledData::from_time_stamps).
  double relative_tolerance = 1e-6;

  static constexpr std::string_view type_name = "MimoCsvColumns";
  static constexpr auto fields() {
    using O = MimoCsvColumns;
    return std::tuple{
        field("time", &O::time, "Column of the time stamps."),
        field("inputs", &O::inputs, "Input columns: names or ranges A:B (file order)."),
        field("outputs", &O::outputs, "Output columns: names or ranges A:B (file order)."),
        field("references", &O::references, "Reference columns, one per input; empty: none."),
        field("relative_tolerance", &O::relative_tolerance, Between{0, 1},
              "Smallest allowed distance of a stamp from the uniform grid, relative to the step."),
    };
  }
  /// The time column is named, and there is at least one input and one output entry, none
  /// of them empty.
  void check_relations(const std::string& path) const;
  /// Throws InvalidArgument naming the field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// The column names `entries` stand for in `table`, ranges expanded in the table's order.
/// `role` ("input", "output", ...) names the list in messages. Throws InvalidArgument naming
/// the source and the entry for a column not in the table (listing those present), a range
/// whose first column comes after its last, or an empty entry.
std::vector<std::string> expand_columns(const CsvTable& table,
                                        const std::vector<std::string>& entries,
                                        std::string_view role);

/// The record; the input hold is the one the table declares (zero-order hold if none). Throws
/// InvalidArgument (naming the source) for a missing column, a column used twice (among the
/// time, inputs, outputs and references), a reference count that differs from the input
/// count, or non-uniform time stamps. Channels are named after their columns.
MimoData mimo_data_from_table(const CsvTable& table, const MimoCsvColumns& columns);
MimoData read_mimo_data(const std::filesystem::path& path, const MimoCsvColumns& columns);

/// A "# input_hold: foh" declaration for a first-order-hold input, then the time column
/// (`time_column`), the inputs, the outputs and the references (named r_<input name>), each
/// channel under its name. Read back with the same names, the record is bit-identical.
CsvTable to_csv_table(const MimoData& data, const std::string& time_column = "t");
void write_mimo_data(const std::filesystem::path& path, const MimoData& data,
                     const std::string& time_column = "t", Overwrite overwrite = Overwrite::no);

}  // namespace ctid::io
