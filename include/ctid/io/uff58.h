// FRF matrices in the universal file format (UFF / UNV), dataset 58, ASCII: one record per
// response/reference pair (docs/formats.md, "Universal file dataset 58", lists the subset
// exactly). Read: function type 4 (frequency response function), complex ordinates (single or
// double precision), even or uneven abscissa in Hz; the records must hold every response x
// reference pair of one FRF matrix once, on the same abscissa. Outputs are the response
// node/direction pairs and inputs the reference ones, named "<node><direction>" ("12+Z",
// "3-RX", "7" for a scalar), in the order they first appear. Other datasets in the file
// (151, 164, 2411, ...) are skipped; anything else in a dataset 58 is refused with a message
// naming the record.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "ctid/frequency/mimo_frf.h"
#include "ctid/io/file.h"

namespace ctid::io {

/// Parses the text of a universal file; `source` names it in error messages ("f.uff: dataset
/// 58 at line 12: function type 1 (time response) is not an FRF; ...").
MimoFrf parse_uff58(std::string_view text, const std::string& source);
MimoFrf read_uff58(const std::filesystem::path& path);

/// One dataset 58 per output/input pair (complex double, uneven abscissa in Hz, function type
/// 4). Names of the form "<node><direction>" give the node and direction; any other name gives
/// node = its position (outputs 1.., inputs 1001..) and direction 0 (scalar), and the names
/// are kept in ID line 1.
std::string format_uff58(const MimoFrf& frf);
void write_uff58(const std::filesystem::path& path, const MimoFrf& frf,
                 Overwrite overwrite = Overwrite::no);

}  // namespace ctid::io
