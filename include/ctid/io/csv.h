// Numeric CSV tables with a header row of column names (docs/formats.md). Fields are
// separated by commas; blank lines and lines starting with '#' are skipped; every value
// must be a finite number. Parse errors name the source, the line and the column:
// "data.csv:7: column 'y' (field 3): malformed number 'abc'". Written values use %.17g,
// so a table read back is bit-identical.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "ctid/io/file.h"

namespace ctid::io {

struct CsvTable {
  /// Where the table came from (a file name), used in error messages.
  std::string source;
  std::vector<std::string> names;
  /// One vector per name, all of the same length.
  std::vector<Eigen::VectorXd> columns;

  int rows() const { return columns.empty() ? 0 : static_cast<int>(columns.front().size()); }
  bool has_column(std::string_view name) const;
  /// Throws InvalidArgument naming the source, the missing column and the columns present.
  const Eigen::VectorXd& column(std::string_view name) const;
  /// Appends a column; throws InvalidArgument for an invalid or repeated name or a length
  /// that differs from the other columns.
  void add_column(std::string name, Eigen::VectorXd values);
};

/// Parses CSV text; `source` names it in error messages.
CsvTable parse_csv(std::string_view text, const std::string& source);
/// Reads and parses a CSV file.
CsvTable read_csv(const std::filesystem::path& path);

/// The table as CSV text: header row, then one row per sample with %.17g values.
std::string format_csv(const CsvTable& table);
/// Writes the table (see write_text_file for the overwrite rule).
void write_csv(const std::filesystem::path& path, const CsvTable& table,
               Overwrite overwrite = Overwrite::no);

}  // namespace ctid::io
