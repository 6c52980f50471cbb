// .npy data files on the command line (decision 0022): chosen by the extension wherever a
// command reads a record, columns addressed by their 0-based index; the same numbers as a CSV
// give the same model bit for bit; a malformed file is one line naming it, exit 2.
#include <cstring>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/io/csv.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"

namespace ctid::cli::npy_input_test {
namespace {

using testing::expect_bad_input;

// The bytes np.save writes for a C-order float64 array: version 1.0, a header padded to 64
// bytes. `columns` of the table, in order, as the array's columns.
std::string npy_of(const io::CsvTable& table, const std::vector<std::string>& columns,
                   bool fortran_order = false) {
  const auto rows = static_cast<size_t>(table.rows());
  std::string header =
      "{'descr': '<f8', 'fortran_order': " + std::string(fortran_order ? "True" : "False") +
      ", 'shape': (" + std::to_string(rows) + ", " + std::to_string(columns.size()) + "), }";
  while ((10 + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::string bytes = "\x93NUMPY\x01";
  bytes += '\0';
  bytes += static_cast<char>(header.size() & 0xff);
  bytes += static_cast<char>(header.size() >> 8);
  bytes += header;
  for (size_t k = 0; k < rows; ++k) {
    for (const std::string& name : columns) {
      const double value = table.column(name)(static_cast<Eigen::Index>(k));
      char raw[sizeof value];
      std::memcpy(raw, &value, sizeof value);  // the test host is little-endian
      bytes.append(raw, sizeof raw);
    }
  }
  return bytes;
}

class NpyInput : public testing::Section61Test {
 protected:
  io::CsvTable csv() const { return io::read_csv(path("d.csv")); }
  std::string text(const std::string& name) const { return io::read_text_file(path(name)); }
};

TEST_F(NpyInput, FitAndValidateReadTheSameRecordAsTheCsv) {
  write("d.npy", npy_of(csv(), {"t", "u", "y"}));
  const auto from_csv = ctid({"fit", "d.csv", "--modes", "4", "-q", "--model-output", "c.json"});
  ASSERT_EQ(from_csv.status, 0) << from_csv.err;
  const auto from_npy =
      ctid({"fit", "d.npy", "--time-column", "0", "--input-column", "1", "--output-column", "2",
            "--modes", "4", "-q", "--model-output", "n.json"});
  ASSERT_EQ(from_npy.status, 0) << from_npy.err;
  EXPECT_EQ(text("n.json"), text("c.json"));

  const auto validated = ctid({"validate", "c.json", "d.npy", "--time-column", "0",
                               "--input-column", "1", "--output-column", "2", "-o", "v.json"});
  ASSERT_EQ(validated.status, 0) << validated.err;
  const auto reference = ctid({"validate", "c.json", "d.csv", "-o", "w.json"});
  ASSERT_EQ(reference.status, 0) << reference.err;
  EXPECT_EQ(io::read_json(path("v.json"))["fit_percent"],
            io::read_json(path("w.json"))["fit_percent"]);
}

TEST_F(NpyInput, AnArrayWithoutTimeColumnTakesTheSampleTime) {
  write("uy.npy", npy_of(csv(), {"u", "y"}));
  expect_bad_input(
      ctid({"fit", "uy.npy", "--input-column", "0", "--output-column", "1", "--modes", "4", "-q"}),
      "fit", "uy.npy has no time column 't'; give --sample-time (or --time-column)");
  const auto r = ctid({"fit", "uy.npy", "--input-column", "0", "--output-column", "1", "-T", "0.05",
                       "--modes", "4", "-q", "--model-output", "n.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_EQ(ctid({"fit", "d.csv", "--modes", "4", "-q", "--model-output", "c.json"}).status, 0);
  EXPECT_EQ(text("n.json"), text("c.json"));
}

TEST_F(NpyInput, AMissingColumnListsTheIndexNames) {
  write("d.npy", npy_of(csv(), {"t", "u", "y"}));
  expect_bad_input(ctid({"fit", "d.npy", "--modes", "4", "-q"}), "fit",
                   "d.npy: no column 'u' (columns: 0, 1, 2)");
}

TEST_F(NpyInput, MalformedFilesAreOneLineNamingTheFile) {
  write("text.npy", "t,u,y\n0,1,2\n0.05,1,2\n");
  expect_bad_input(ctid({"frf", "text.npy", "-o", "f.json"}), "frf",
                   "text.npy: not a .npy file (it does not start with the magic string "
                   "\\x93NUMPY)");
  write("f.npy", npy_of(csv(), {"t", "u", "y"}, true));
  expect_bad_input(ctid({"fit", "f.npy", "--modes", "4", "-q"}), "fit",
                   "f.npy: the array is in Fortran order (column-major); ctid reads C order");
  const std::string whole = npy_of(csv(), {"t", "u", "y"});
  write("cut.npy", whole.substr(0, whole.size() - 5));
  expect_bad_input(ctid({"validate", example("gonzalez_6_1_open_loop.json"), "cut.npy"}),
                   "validate", "cut.npy: truncated");
}

}  // namespace
}  // namespace ctid::cli::npy_input_test
