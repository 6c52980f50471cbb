#include "ctid/io/npy.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/io/mimo_data_csv.h"
#include "ctid/io/sampled_data_csv.h"
#include "io/test_directory.h"

namespace ctid::io::npy_test {
namespace {

using ::testing::HasSubstr;

// The bytes np.save writes: magic, version, little-endian header length, the header dict
// padded with spaces and a newline to a multiple of 64 bytes, then the data.
std::string npy_bytes(const std::string& dict, const std::string& data, int major = 1) {
  const size_t length_bytes = major == 1 ? 2 : 4;
  std::string header = dict;
  const size_t preamble = 8 + length_bytes;
  while ((preamble + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::string bytes = "\x93NUMPY";
  bytes += static_cast<char>(major);
  bytes += '\0';
  for (size_t i = 0; i < length_bytes; ++i) {
    bytes += static_cast<char>((header.size() >> (8 * i)) & 0xff);
  }
  return bytes + header + data;
}

template <class T>
std::string raw(const std::vector<T>& values) {
  std::string bytes(values.size() * sizeof(T), '\0');
  std::memcpy(bytes.data(), values.data(), bytes.size());  // the test host is little-endian
  return bytes;
}

std::string dict(const std::string& descr, const std::string& shape, bool fortran = false) {
  return "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") +
         ", 'shape': " + shape + ", }";
}

std::string parse_error(const std::string& bytes) {
  try {
    parse_npy(bytes, "d.npy");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(Npy, ReadsTwoDimensionalFloat64InCOrder) {
  const std::vector<double> values = {0.0, 1.5, -2.0, 0.05, 2.5, 1e-300, 0.1, -3.25, 7.0};
  const NpyArray array = parse_npy(npy_bytes(dict("<f8", "(3, 3)"), raw(values)), "d.npy");
  EXPECT_EQ(array.dtype, "<f8");
  EXPECT_EQ(array.dimensions, 2);
  ASSERT_EQ(array.values.rows(), 3);
  ASSERT_EQ(array.values.cols(), 3);
  EXPECT_EQ(array.values(0, 1), 1.5);
  EXPECT_EQ(array.values(1, 2), 1e-300);
  EXPECT_EQ(array.values(2, 1), -3.25);
}

TEST(Npy, ReadsVersionTwoAndOneDimensionalArrays) {
  const NpyArray array =
      parse_npy(npy_bytes(dict("<f8", "(2,)"), raw(std::vector<double>{4.0, 5.0}), 2), "d.npy");
  EXPECT_EQ(array.dimensions, 1);
  ASSERT_EQ(array.values.rows(), 2);
  ASSERT_EQ(array.values.cols(), 1);
  EXPECT_EQ(array.values(1, 0), 5.0);
}

TEST(Npy, ReadsFloat32AndIntegersAsDoubles) {
  const NpyArray f4 =
      parse_npy(npy_bytes(dict("<f4", "(1, 2)"), raw(std::vector<float>{0.1F, -2.0F})), "d.npy");
  EXPECT_EQ(f4.values(0, 0), static_cast<double>(0.1F));
  EXPECT_EQ(f4.values(0, 1), -2.0);
  const NpyArray i8 = parse_npy(
      npy_bytes(dict("<i8", "(2, 1)"), raw(std::vector<std::int64_t>{-3, 1LL << 40})), "d.npy");
  EXPECT_EQ(i8.values(0, 0), -3.0);
  EXPECT_EQ(i8.values(1, 0), 1099511627776.0);
  const NpyArray i2 =
      parse_npy(npy_bytes(dict("<i2", "(2,)"), raw(std::vector<std::int16_t>{-7, 300})), "d.npy");
  EXPECT_EQ(i2.values(0, 0), -7.0);
  EXPECT_EQ(i2.values(1, 0), 300.0);
  const NpyArray u1 =
      parse_npy(npy_bytes(dict("|u1", "(2,)"), raw(std::vector<std::uint8_t>{255, 1})), "d.npy");
  EXPECT_EQ(u1.values(0, 0), 255.0);
  const NpyArray i4 =
      parse_npy(npy_bytes(dict("<i4", "(1,)"), raw(std::vector<std::int32_t>{-100000})), "d.npy");
  EXPECT_EQ(i4.values(0, 0), -100000.0);
}

TEST(Npy, HeaderKeysInAnyOrderAndDoubleQuotes) {
  const std::string header = "{\"shape\": (1, 2), \"fortran_order\": False, \"descr\": \"<f8\"}";
  const NpyArray array = parse_npy(npy_bytes(header, raw(std::vector<double>{1, 2})), "d.npy");
  EXPECT_EQ(array.values(0, 1), 2.0);
}

TEST(Npy, BadMagicIsNamed) {
  EXPECT_EQ(parse_error("t,u,y\n0,1,2\n"),
            "d.npy: not a .npy file (it does not start with the magic string \\x93NUMPY)");
  EXPECT_EQ(parse_error(""),
            "d.npy: not a .npy file (it does not start with the magic string \\x93NUMPY)");
}

TEST(Npy, UnsupportedVersionIsNamed) {
  std::string bytes = npy_bytes(dict("<f8", "(1,)"), raw(std::vector<double>{1}));
  bytes[6] = 9;
  EXPECT_EQ(parse_error(bytes),
            "d.npy: .npy format version 9.0 is not supported (ctid reads versions 1.0, 2.0 and "
            "3.0)");
}

TEST(Npy, UnsupportedDtypesAreNamedWithTheWayOut) {
  EXPECT_EQ(parse_error(npy_bytes(dict(">f8", "(1,)"), std::string(8, '\0'))),
            "d.npy: dtype '>f8' is not supported (big-endian); ctid reads little-endian "
            "float64, float32 and integer arrays: save a.astype('<f8')");
  EXPECT_THAT(parse_error(npy_bytes(dict("<c16", "(1,)"), std::string(16, '\0'))),
              HasSubstr("dtype '<c16' is not supported (complex)"));
  EXPECT_THAT(parse_error(npy_bytes(dict("|b1", "(1,)"), std::string(1, '\0'))),
              HasSubstr("dtype '|b1' is not supported (bool)"));
  EXPECT_THAT(parse_error(npy_bytes(dict("|O", "(1,)"), std::string(8, '\0'))),
              HasSubstr("dtype '|O' is not supported (not a numeric type)"));
  EXPECT_THAT(parse_error(npy_bytes(dict("<U3", "(1,)"), std::string(12, '\0'))),
              HasSubstr("dtype '<U3' is not supported (strings)"));
  EXPECT_THAT(parse_error(npy_bytes(dict("<f2", "(1,)"), std::string(2, '\0'))),
              HasSubstr("dtype '<f2' is not supported (only 4- and 8-byte floats)"));
  EXPECT_THAT(parse_error(npy_bytes("{'descr': [('a', '<f8')], 'fortran_order': False, "
                                    "'shape': (1,), }",
                                    std::string(8, '\0'))),
              HasSubstr("d.npy: the array has a structured dtype (named fields)"));
}

TEST(Npy, FortranOrderIsRefused) {
  EXPECT_EQ(parse_error(npy_bytes(dict("<f8", "(2, 2)", true), std::string(32, '\0'))),
            "d.npy: the array is in Fortran order (column-major); ctid reads C order: save "
            "np.ascontiguousarray(a)");
  // One axis has one layout whatever the flag says.
  EXPECT_EQ(parse_error(npy_bytes(dict("<f8", "(2,)", true), std::string(16, '\0'))), "");
}

TEST(Npy, TruncatedDataAndTrailingBytesAreNamed) {
  EXPECT_EQ(parse_error(npy_bytes(dict("<f8", "(3, 2)"), std::string(40, '\0'))),
            "d.npy: truncated .npy file (the shape 3 x 2 of <f8 needs 48 data bytes but only 40 "
            "follow the header)");
  EXPECT_EQ(parse_error(npy_bytes(dict("<f8", "(1,)"), std::string(12, '\0'))),
            "d.npy: 4 bytes follow the array's data; the file is not one .npy array");
  const std::string whole = npy_bytes(dict("<f8", "(1,)"), std::string(8, '\0'));
  EXPECT_THAT(parse_error(whole.substr(0, 30)),
              HasSubstr("d.npy: truncated .npy file (the header is 118 bytes but only 20 follow"));
  EXPECT_THAT(parse_error(whole.substr(0, 9)), HasSubstr("d.npy: truncated .npy file (9 bytes"));
}

TEST(Npy, MalformedHeaderShapesAreNamed) {
  EXPECT_THAT(parse_error(npy_bytes("{'descr': '<f8', 'shape': (1,), }", std::string(8, '\0'))),
              HasSubstr("d.npy: malformed .npy header (no 'fortran_order')"));
  EXPECT_THAT(parse_error(npy_bytes("not a dict", "")),
              HasSubstr("d.npy: malformed .npy header (expected '{' opening the header dict)"));
  EXPECT_EQ(parse_error(npy_bytes(dict("<f8", "(1, 1, 1)"), std::string(8, '\0'))),
            "d.npy: the array has 3 axes; ctid reads a 1-D array (one signal) or a 2-D array of "
            "samples x columns");
  EXPECT_EQ(parse_error(npy_bytes(dict("<f8", "()"), std::string(8, '\0'))),
            "d.npy: the array has 0 axes; ctid reads a 1-D array (one signal) or a 2-D array of "
            "samples x columns");
  EXPECT_EQ(parse_error(npy_bytes(dict("<f8", "(0, 3)"), "")),
            "d.npy: the array is empty (shape 0 x 3); it needs at least one sample and one column");
}

TEST(Npy, NonFiniteValueNamesRowAndColumn) {
  const std::vector<double> values = {0.0, 1.0, 0.1, std::numeric_limits<double>::quiet_NaN()};
  EXPECT_EQ(parse_error(npy_bytes(dict("<f8", "(2, 2)"), raw(values))),
            "d.npy: row 1 (0-based), column '1': value nan is not finite; every value must be a "
            "finite number");
}

TEST(Npy, DirectTableEqualsTheArraysTableAndRefusesAlike) {
  for (const auto& [descr, bytes] :
       {std::pair{std::string("<f8"), raw(std::vector<double>{0.0, 1.5, -2.0, 0.05, 2.5, 7.0})},
        std::pair{std::string("<i2"), raw(std::vector<std::int16_t>{1, -2, 3, -4, 5, -6})}}) {
    const std::string file = npy_bytes(dict(descr, "(3, 2)"), bytes);
    const CsvTable direct = parse_npy_table(file, "d.npy");
    const CsvTable table = npy_table(parse_npy(file, "d.npy"), "d.npy");
    EXPECT_EQ(direct.names, table.names) << descr;
    ASSERT_EQ(direct.columns.size(), 2U) << descr;
    EXPECT_EQ(direct.columns, table.columns) << descr;
    EXPECT_EQ(direct.source, "d.npy");
  }
  const std::vector<double> values = {0.0, 1.0, 0.1, std::numeric_limits<double>::infinity()};
  const std::string bad = npy_bytes(dict("<f8", "(2, 2)"), raw(values));
  try {
    parse_npy_table(bad, "d.npy");
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()), parse_error(bad));
  }
}

TEST(Npy, TableColumnsAreNamedByIndexAndFeedTheRecordReaders) {
  testing::TestDirectory dir;
  const std::vector<double> values = {0.0, 1.0, 2.0, 0.5, 3.0, 4.0, 1.0, 5.0, 6.0};
  {
    std::ofstream out(dir / "d.NPY", std::ios::binary);
    out << npy_bytes(dict("<f8", "(3, 3)"), raw(values));
  }
  EXPECT_TRUE(is_npy_path(dir / "d.NPY"));
  EXPECT_FALSE(is_npy_path(dir / "d.csv"));
  const CsvTable table = read_table(dir / "d.NPY");
  EXPECT_EQ(table.names, (std::vector<std::string>{"0", "1", "2"}));
  EXPECT_EQ(table.source, (dir / "d.NPY").string());
  CsvColumns columns;
  columns.time = "0";
  columns.input = "1";
  columns.output = "2";
  const SampledData data = read_sampled_data(dir / "d.NPY", columns);
  EXPECT_EQ(data.sample_time(), 0.5);
  EXPECT_EQ(data.output()(2), 6.0);
  MimoCsvColumns mimo;
  mimo.time = "0";
  mimo.inputs = {"1"};
  mimo.outputs = {"2"};
  EXPECT_EQ(read_mimo_data(dir / "d.NPY", mimo).outputs()(1, 0), 4.0);
  // A missing column lists the index names.
  try {
    read_sampled_data(dir / "d.NPY");
    ADD_FAILURE() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(std::string(e.what()),
              (dir / "d.NPY").string() + ": no column 't' (columns: 0, 1, 2)");
  }
}

}  // namespace
}  // namespace ctid::io::npy_test
