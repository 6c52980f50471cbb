// Measured FRF matrices from files, for fitting a modal model without time records
// (frf_fit/frf_matrix_fit.h). CSV: the table `ctid frf --input-columns ... -o X.csv` writes
// (docs/formats.md, "FRF matrix CSV"): a "frequency" column in rad/s (or "frequency_hz" in
// Hz), and for every output/input pair "<output>/<input>_real" and "<output>/<input>_imag",
// optionally "<output>/<input>_variance" and "coherence_<output>"; outputs and inputs in the
// order they first appear. Universal file format dataset 58: uff58.h. read_mimo_frf picks the
// reader by the file's extension.
#pragma once

#include <filesystem>
#include <string>

#include "ctid/frequency/mimo_frf.h"
#include "ctid/io/csv.h"
#include "ctid/io/file.h"

namespace ctid::io {

/// The FRF matrix in a CSV table (layout above). Throws InvalidArgument naming the source and
/// the column for a missing frequency column, a pair with only one of _real/_imag, an
/// output/input pair missing from the matrix, variances given for some pairs only, or
/// frequencies that are negative or do not increase.
MimoFrf mimo_frf_from_table(const CsvTable& table);
MimoFrf read_mimo_frf_csv(const std::filesystem::path& path);

/// The table `ctid frf -o X.csv` writes: frequency, frequency_hz, input_condition,
/// input_level_<input>, coherence_<output>, then per pair _real, _imag and _variance (columns
/// the FRF does not have are left out).
CsvTable mimo_frf_table(const MimoFrf& frf);

/// Whether `path` names a universal file by its extension (.uff, .unv or .uf, any case).
bool is_universal_file_path(const std::filesystem::path& path);

/// By extension: .uff, .unv or .uf as universal file dataset 58 (read_uff58), .json as the
/// "mimo_frf" document `ctid frf -o X.json` writes, anything else as CSV.
MimoFrf read_mimo_frf(const std::filesystem::path& path);

}  // namespace ctid::io
