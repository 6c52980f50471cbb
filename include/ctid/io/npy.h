// NumPy .npy files as numeric tables, the binary input for long records (docs/formats.md,
// decision 0022). Format versions 1.0, 2.0 and 3.0; a 1-D array (one column) or a 2-D array
// of samples x columns in C order; little-endian float64, float32 or integers, read as
// doubles. The columns are named by their 0-based index, "0", "1", ..., so the CSV readers'
// column flags address them (--time-column 0 --input-column 1 --output-column 2). Errors
// name the file and what is wrong: "d.npy: the array is in Fortran order; ...".
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "ctid/io/csv.h"

namespace ctid::io {

/// A 1-D or 2-D NumPy array as doubles: one row per sample, one column per signal (a 1-D
/// array is one column).
struct NpyArray {
  /// The array's dtype as the file declares it, e.g. "<f8".
  std::string dtype;
  /// The number of axes in the file: 1 or 2.
  int dimensions = 2;
  Eigen::MatrixXd values;
};

/// Parses the bytes of a .npy file; `source` names it in error messages. Throws
/// InvalidArgument for a bad magic string, an unsupported version or dtype (big-endian,
/// complex, bool, object, structured, strings), Fortran order, more than two axes, an empty
/// array, data shorter or longer than the header's shape, and a value that is not finite
/// (naming its 0-based row and its column).
NpyArray parse_npy(std::string_view bytes, const std::string& source);
/// Reads and parses a .npy file.
NpyArray read_npy(const std::filesystem::path& path);

/// The array as a table whose columns are named "0", "1", ... (no declarations).
CsvTable npy_table(const NpyArray& array, const std::string& source);
/// parse_npy straight into a table: npy_table(parse_npy(bytes, source), source) without the
/// intermediate array (a long record is held once, not twice).
CsvTable parse_npy_table(std::string_view bytes, const std::string& source);

/// Whether `path` names a .npy file (by its extension, in any case).
bool is_npy_path(const std::filesystem::path& path);

/// The table in `path`: a .npy file by its extension (npy_table), anything else as CSV.
CsvTable read_table(const std::filesystem::path& path);

}  // namespace ctid::io
