#include "ctid/io/csv.h"

#include <cmath>
#include <limits>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "io/test_directory.h"

namespace ctid::io::csv_test {
namespace {

using ::testing::HasSubstr;

// The message of the InvalidArgument that parsing `text` and using every column throws (""
// if none). A cell that is not a number is an error of its column, raised when it is used.
std::string parse_error(const std::string& text) {
  try {
    const CsvTable table = parse_csv(text, "data.csv");
    for (const std::string& name : table.names) table.column(name);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(Csv, ParsesNamedColumnsSkippingCommentsBlankLinesAndCarriageReturns) {
  const CsvTable table =
      parse_csv("# recorded 2024\r\n t , u,y\r\n0,1.5,-2\r\n\r\n1, +2e-3 ,3\r\n# end\n", "x.csv");
  ASSERT_EQ(table.names, (std::vector<std::string>{"t", "u", "y"}));
  ASSERT_EQ(table.rows(), 2);
  EXPECT_EQ(table.column("u")(0), 1.5);
  EXPECT_EQ(table.column("u")(1), 2e-3);
  EXPECT_EQ(table.column("y")(0), -2.0);
  EXPECT_TRUE(table.has_column("t"));
  EXPECT_FALSE(table.has_column("r"));
}

TEST(Csv, ByteOrderMarkIsSkipped) {
  const CsvTable table = parse_csv("\xEF\xBB\xBFt,u\n0,1\n", "bom.csv");
  EXPECT_EQ(table.names, (std::vector<std::string>{"t", "u"}));
}

// Found by fuzz_csv: a mark after comment lines became part of the name 't', and the table,
// written back (comments dropped, the mark now first), read back with another name.
TEST(Csv, ByteOrderMarkBeforeAHeaderAfterCommentsIsSkipped) {
  const CsvTable table = parse_csv("# made by a logger\n\xEF\xBB\xBFt,u\n0,1\n", "bom.csv");
  EXPECT_EQ(table.names, (std::vector<std::string>{"t", "u"}));
  EXPECT_EQ(parse_csv(format_csv(table), "again.csv").names, table.names);
}

TEST(Csv, LoneCarriageReturnsEndLinesAndLinesAreCounted) {
  const CsvTable table = parse_csv("t,u\r0,1\r1,2\r", "cr.csv");
  EXPECT_EQ(table.names, (std::vector<std::string>{"t", "u"}));
  EXPECT_EQ(table.rows(), 2);
  EXPECT_EQ(table.column("u")(1), 2.0);
  EXPECT_THAT(parse_error("t,u\r0,1\r\n1,x\r"), HasSubstr("data.csv:3: column 'u'"));
}

TEST(Csv, EchoedFieldsAreCutAndControlBytesEscaped) {
  const std::string message = parse_error("t,u\n0," + std::string(100000, '7') + "x\n");
  EXPECT_THAT(message,
              HasSubstr("malformed number '" + std::string(80, '7') + "... (100001 bytes)'"));
  EXPECT_LT(message.size(), 200u);
  EXPECT_THAT(parse_error(std::string("t,u\n0,\x01\x1b[0m\n")),
              HasSubstr("malformed number '\\x01\\x1b[0m'"));
}

TEST(Csv, MalformedNumberNamesFileLineAndColumn) {
  EXPECT_EQ(parse_error("t,u,y\n0,1,2\n0.1,abc,3\n"),
            "data.csv:3: column 'u' (field 2): malformed number 'abc'");
  EXPECT_THAT(parse_error("t,u\n0,1.2.3\n"), HasSubstr("data.csv:2: column 'u'"));
  EXPECT_THAT(parse_error("t,u\n0,1e\n"), HasSubstr("malformed number '1e'"));
  EXPECT_THAT(parse_error("t,u\n0,+-1\n"), HasSubstr("malformed number '+-1'"));
  EXPECT_THAT(parse_error("t,u\n0,1 2\n"), HasSubstr("malformed number '1 2'"));
}

TEST(Csv, LineNumbersCountCommentsAndBlankLines) {
  EXPECT_THAT(parse_error("# c\n\nt,u\n0,1\n\n# c\n1,x\n"), HasSubstr("data.csv:7: column 'u'"));
}

TEST(Csv, WrongFieldCountNamesTheLineAndTheExpectedColumns) {
  EXPECT_EQ(parse_error("t,u,y\n0,1,2\n1,2\n"),
            "data.csv:3: expected 3 fields (t, u, y) but found 2");
  EXPECT_THAT(parse_error("t,u\n0,1,2\n"), HasSubstr("data.csv:2: expected 2 fields"));
}

TEST(Csv, EmptyFieldIsAnError) {
  EXPECT_EQ(parse_error("t,u\n0,\n"),
            "data.csv:2: column 'u' (field 2): empty field; expected a number");
}

TEST(Csv, NonFiniteValuesAreRejectedWithTheirLine) {
  for (const std::string bad : {"nan", "NaN", "inf", "-inf", "infinity", "1e999"}) {
    EXPECT_THAT(parse_error("t,u\n0,1\n1," + bad + "\n"),
                HasSubstr("data.csv:3: column 'u' (field 2): value '" + bad + "' is not finite"))
        << bad;
  }
}

TEST(Csv, UnderflowIsAcceptedAsTheNearestDouble) {
  const CsvTable table = parse_csv("u\n1e-400\n", "x.csv");
  EXPECT_EQ(table.column("u")(0), 0.0);
}

TEST(Csv, EmptyFileHeaderOnlyAndMissingHeaderAreErrors) {
  EXPECT_THAT(parse_error(""), HasSubstr("data.csv: file is empty"));
  EXPECT_THAT(parse_error("\n# only a comment\n\n"), HasSubstr("data.csv: file is empty"));
  EXPECT_EQ(parse_error("t,u\n"), "data.csv: no data rows after the header on line 1");
  EXPECT_THAT(parse_error("0,1\n1,2\n"), HasSubstr("data.csv:1: the first line holds numbers"));
}

TEST(Csv, BadHeaderNamesAreErrors) {
  EXPECT_THAT(parse_error("t,,y\n0,1,2\n"), HasSubstr("data.csv:1: header field 2 is empty"));
  EXPECT_THAT(parse_error("t,u,u\n0,1,2\n"),
              HasSubstr("data.csv:1: column name 'u' appears twice"));
}

TEST(Csv, MissingColumnListsTheColumnsPresent) {
  const CsvTable table = parse_csv("t,u\n0,1\n", "data.csv");
  try {
    table.column("y");
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "data.csv: no column 'y' (columns: t, u)");
  }
}

TEST(Csv, FormatThenParseIsBitIdentical) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  CsvTable table;
  Eigen::VectorXd a(200), b(200);
  for (int k = 0; k < 200; ++k) {
    a(k) = normal(rng) * std::pow(10.0, k % 40 - 20);
    b(k) = std::nextafter(1.0 / 3.0 * k, 1e300);
  }
  a(0) = -0.0;
  a(1) = std::numeric_limits<double>::denorm_min();
  a(2) = std::numeric_limits<double>::max();
  table.add_column("a", a);
  table.add_column("b_2", b);
  const CsvTable back = parse_csv(format_csv(table), "round.csv");
  ASSERT_EQ(back.names, table.names);
  for (int k = 0; k < 200; ++k) {
    EXPECT_EQ(back.column("a")(k), a(k)) << k;
    EXPECT_EQ(back.column("b_2")(k), b(k)) << k;
  }
  EXPECT_TRUE(std::signbit(back.column("a")(0)));
}

TEST(Csv, AddColumnChecksNamesAndLengths) {
  CsvTable table;
  table.add_column("t", Eigen::VectorXd::Zero(3));
  EXPECT_THROW(table.add_column("t", Eigen::VectorXd::Zero(3)), InvalidArgument);
  EXPECT_THROW(table.add_column("u", Eigen::VectorXd::Zero(2)), InvalidArgument);
  EXPECT_THROW(table.add_column("a,b", Eigen::VectorXd::Zero(3)), InvalidArgument);
  EXPECT_THROW(table.add_column("", Eigen::VectorXd::Zero(3)), InvalidArgument);
}

TEST(Csv, WriteRefusesToOverwriteUnlessAsked) {
  const testing::TestDirectory dir;
  CsvTable table;
  table.add_column("x", Eigen::VectorXd::LinSpaced(4, 0.0, 3.0));
  const auto path = dir / "x.csv";
  write_csv(path, table);
  EXPECT_EQ(read_csv(path).column("x"), table.column("x"));

  CsvTable other;
  other.add_column("x", Eigen::VectorXd::Constant(2, 9.0));
  try {
    write_csv(path, other);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("file exists and overwriting was not requested"));
  }
  EXPECT_EQ(read_csv(path).rows(), 4) << "the existing file must be left untouched";
  write_csv(path, other, Overwrite::yes);
  EXPECT_EQ(read_csv(path).rows(), 2);
  // No temporary files are left behind.
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path()))
    ++files;
  EXPECT_EQ(files, 1);
}

// Well-formed rows take a fast path; odd ones (blanks, '+', tabs, a value strtod must read)
// are read the slow way. Both must give strtod's value for every field.
TEST(Csv, EveryRowReadsAsStrtodWhicheverPathTakesIt) {
  std::mt19937_64 random(5);
  std::uniform_real_distribution<double> mantissa(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-320, 300);
  std::string text = "a,b\n";
  std::vector<std::pair<double, double>> expected;
  char a[40];
  char b[40];
  for (int k = 0; k < 400; ++k) {
    std::snprintf(a, sizeof a, "%.17g",
                  std::abs(mantissa(random)) * std::pow(10.0, exponent(random)));
    const double second = mantissa(random) * std::pow(10.0, exponent(random) / 10);
    if (k % 3 == 0) {
      std::snprintf(b, sizeof b, "%.3g", k % 4 >= 2 ? std::abs(second) : second);
    } else {
      std::snprintf(b, sizeof b, "%.17g", k % 4 >= 2 ? std::abs(second) : second);
    }
    const std::string x = a;
    const std::string y = b;
    switch (k % 4) {
      case 0:
        text += x + "," + y + "\n";
        break;
      case 1:
        text += " " + x + " ,\t" + y + " \r\n";
        break;
      case 2:
        text += "+" + x + "," + y + "\r";
        break;
      default:
        text += x + " , +" + y + "\n";
        break;
    }
    expected.emplace_back(std::strtod(a, nullptr), std::strtod(b, nullptr));
  }
  text += "1e-400,2\n";  // underflow: only strtod gives the signed zero or denormal
  expected.emplace_back(std::strtod("1e-400", nullptr), 2.0);
  const CsvTable table = parse_csv(text, "r.csv");
  ASSERT_EQ(table.rows(), static_cast<int>(expected.size()));
  for (int k = 0; k < table.rows(); ++k) {
    EXPECT_EQ(table.column("a")(k), expected[static_cast<size_t>(k)].first) << k;
    EXPECT_EQ(table.column("b")(k), expected[static_cast<size_t>(k)].second) << k;
  }
}

TEST(Csv, ReadingAMissingFileNamesIt) {
  try {
    read_csv("/nonexistent/dir/data.csv");
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/dir/data.csv: no such file");
  }
}

TEST(Csv, WritingIntoAMissingDirectoryIsBadInput) {
  CsvTable table;
  table.add_column("x", Eigen::VectorXd::Zero(2));
  EXPECT_THROW(write_csv("/nonexistent/dir/out.csv", table), InvalidArgument);
}

// Issue 35: a file as MATLAB or a spreadsheet exports it: quoted names, a delimiter ending
// every line, CRLF, and an unused column that is text on its first row and empty after.
TEST(Csv, ReadsAnExportWithQuotesTrailingDelimitersAndASparseUnusedColumn) {
  const CsvTable table = parse_csv(
      "\"uEst\",\"uVal\",\"yEst\",\"note\",\r\n1.5,2,3,exported from MATLAB,\r\n"
      "-1,0.25,4,,\r\n",
      "tank.csv");
  ASSERT_EQ(table.names, (std::vector<std::string>{"uEst", "uVal", "yEst", "note"}));
  EXPECT_EQ(table.column("uEst")(0), 1.5);
  EXPECT_EQ(table.column("uVal")(1), 0.25);
  EXPECT_EQ(table.column("yEst")(1), 4.0);
  // The unused column is an error only when asked for, and says where and why.
  EXPECT_THAT([&] { table.column("note"); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  "tank.csv:2: column 'note' (field 4): malformed number 'exported from MATLAB'"));
  // A missing column lists the names as the header has them, without quotes.
  EXPECT_THAT([&] { table.column("u"); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  "tank.csv: no column 'u' (columns: uEst, uVal, yEst, note)"));
}

TEST(Csv, SemicolonsAndTabsWithDecimalCommasAreDetected) {
  const CsvTable semicolons = parse_csv("t;u;y\n0,05;-1,5;2\n0,10;3;4,25\n", "eu.csv");
  ASSERT_EQ(semicolons.names, (std::vector<std::string>{"t", "u", "y"}));
  EXPECT_EQ(semicolons.column("t")(1), 0.1);
  EXPECT_EQ(semicolons.column("u")(0), -1.5);
  EXPECT_EQ(semicolons.column("y")(1), 4.25);
  const CsvTable tabs = parse_csv("t\tu\n0\t1,5\n1\t2.5\n", "tabs.csv");
  EXPECT_EQ(tabs.column("u")(0), 1.5);
  EXPECT_EQ(tabs.column("u")(1), 2.5);
  // A comma-separated file keeps the comma as its delimiter: "1,5" there is two fields.
  EXPECT_THAT(parse_error("t,u\n0,1,5\n"), HasSubstr("expected 2 fields"));
  // A semicolon row under a comma header is diagnosed as another dialect.
  EXPECT_THAT(parse_error("t,u,y\n0;1;2,0,0\n"),
              HasSubstr("looks separated by semicolons or tabs"));
}

}  // namespace
}  // namespace ctid::io::csv_test
