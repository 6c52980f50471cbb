// Numeric CSV tables with a header row of column names (docs/formats.md). Fields are
// separated by commas, semicolons or tabs (the one the header row uses most, decision 0031);
// in a file separated by semicolons or tabs a decimal comma is read as a decimal point.
// Names and values may be quoted ("uEst"), a delimiter may end every line, and lines end with
// LF, CRLF or CR. Blank lines and lines starting with '#' are skipped (a line
// "# key: value" is kept as a declaration). Every value of a column that is used must be a
// finite number; a column that is not used may hold anything (an empty or text cell is an
// error only when the column is asked for). Errors name the source, the line and the column:
// "data.csv:7: column 'y' (field 3): malformed number 'abc'". Written values use %.17g,
// so a table read back is bit-identical.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "ctid/io/file.h"

namespace ctid::io {

/// A comment line of the form "# key: value" (key: letters, digits and '_'), e.g.
/// "# input_hold: foh". Other comment lines are ignored.
struct CsvDeclaration {
  std::string key;
  std::string value;
  int line = 0;  ///< where it was read (0: not read from text)
};

struct CsvTable {
  /// Where the table came from (a file name), used in error messages.
  std::string source;
  std::vector<std::string> names;
  /// One vector per name, all of the same length.
  std::vector<Eigen::VectorXd> columns;
  /// Declarations from "# key: value" comment lines, in file order; written back first.
  std::vector<CsvDeclaration> declarations;
  /// Columns with a cell that is not a finite number, by name: the message for the first such
  /// cell, thrown by column() when the column is used (its values there are NaN).
  std::map<std::string, std::string, std::less<>> unreadable;

  int rows() const { return columns.empty() ? 0 : static_cast<int>(columns.front().size()); }
  bool has_column(std::string_view name) const;
  /// Throws InvalidArgument naming the source, the missing column and the columns present, or
  /// the first cell of the column that is not a finite number.
  const Eigen::VectorXd& column(std::string_view name) const;
  /// Appends a column; throws InvalidArgument for an invalid or repeated name or a length
  /// that differs from the other columns.
  void add_column(std::string name, Eigen::VectorXd values);
  /// The last declaration of `key`, if any.
  const CsvDeclaration* declaration(std::string_view key) const;
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
