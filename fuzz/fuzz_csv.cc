// libFuzzer harness of the CSV reader (io/csv.h) and of what is read from a table: a record
// (sampled_data_csv.h, default columns t, u, y) and an FRF matrix (mimo_frf_file.h). A table
// that was read must be written and read back unchanged (format_csv is the writer of every
// CSV ctid produces).
#include "ctid/io/csv.h"
#include "ctid/io/mimo_frf_file.h"
#include "ctid/io/sampled_data_csv.h"
#include "harness.h"

namespace {

bool same(const ctid::io::CsvTable& a, const ctid::io::CsvTable& b) {
  if (a.names != b.names || a.columns.size() != b.columns.size()) return false;
  for (std::size_t k = 0; k < a.columns.size(); ++k) {
    if (a.columns[k].size() != b.columns[k].size()) return false;
    // A cell that is not a number reads as NaN (an error of its column when used), and is
    // written "nan", which reads back as NaN again.
    const auto& x = a.columns[k].array();
    const auto& y = b.columns[k].array();
    if (!(x == y || (x.isNaN() && y.isNaN())).all()) return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ctid::fuzz::refuse_or_read(data, size, [](std::string_view text) {
    const ctid::io::CsvTable table = ctid::io::parse_csv(text, "fuzz.csv");
    ctid::fuzz::must_read_back([&] {
      if (!same(ctid::io::parse_csv(ctid::io::format_csv(table), "again.csv"), table)) {
        ctid::fuzz::finding("a table written by format_csv reads back different");
      }
    });
    ctid::fuzz::refuse_or_use(
        table, [](const ctid::io::CsvTable& t) { (void)ctid::io::sampled_data_from_table(t); });
    ctid::fuzz::refuse_or_use(
        table, [](const ctid::io::CsvTable& t) { (void)ctid::io::mimo_frf_from_table(t); });
  });
}
