// FRF matrices from files (mimo_frf_file.h, uff58.h): the CSV table `ctid frf -o` writes read
// back bit for bit, universal file dataset 58 round trips, malformed files refused with a
// message naming what is wrong, and the fit result's document read back.
#include "ctid/io/mimo_frf_file.h"

#include <complex>
#include <fstream>
#include <numbers>
#include <random>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/frf_fit/frf_matrix_fit.h"
#include "ctid/io/documents.h"
#include "ctid/io/report_json.h"
#include "ctid/io/uff58.h"
#include "io/test_directory.h"

namespace ctid::mimo_frf_file_test {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// A 3 x 2 FRF matrix with seeded random entries on a 0.5 Hz grid, named by node and direction.
MimoFrf random_frf(int lines, bool with_variance) {
  std::mt19937_64 rng(42);
  std::normal_distribution<double> normal;
  MimoFrf frf;
  frf.output_names = {"11+Z", "12-Y", "7"};
  frf.input_names = {"101+X", "102+RZ"};
  frf.frequencies.resize(lines);
  for (int l = 0; l < lines; ++l) {
    frf.frequencies(l) = 2.0 * std::numbers::pi * 0.5 * (l + 1);
    Eigen::MatrixXcd h(3, 2);
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 2; ++k) h(j, k) = {normal(rng), normal(rng)};
    }
    frf.response.push_back(h);
    if (with_variance) frf.variance.push_back(h.cwiseAbs2() * 1e-3);
  }
  return frf;
}

TEST(MimoFrfCsv, TableRoundTripsBitForBit) {
  const MimoFrf frf = random_frf(20, true);
  const MimoFrf back =
      io::mimo_frf_from_table(io::parse_csv(io::format_csv(io::mimo_frf_table(frf)), "t.csv"));
  EXPECT_EQ(back.output_names, frf.output_names);
  EXPECT_EQ(back.input_names, frf.input_names);
  EXPECT_EQ(back.frequencies, frf.frequencies);
  ASSERT_EQ(back.response.size(), frf.response.size());
  for (size_t l = 0; l < frf.response.size(); ++l) {
    EXPECT_EQ(back.response[l], frf.response[l]);
    EXPECT_EQ(back.variance[l], frf.variance[l]);
  }
}

TEST(MimoFrfCsv, FrequencyInHzAndNoVariance) {
  const std::string text =
      "frequency_hz,y1/u1_real,y1/u1_imag,y2/u1_real,y2/u1_imag\n"
      "1,1,2,3,4\n"
      "2,5,6,7,8\n";
  const MimoFrf frf = io::mimo_frf_from_table(io::parse_csv(text, "f.csv"));
  EXPECT_EQ(frf.output_count(), 2);
  EXPECT_EQ(frf.input_count(), 1);
  EXPECT_DOUBLE_EQ(frf.frequencies(1), 4.0 * std::numbers::pi);
  EXPECT_EQ(frf.response[1](1, 0), std::complex<double>(7.0, 8.0));
  EXPECT_TRUE(frf.variance.empty());
}

TEST(MimoFrfCsv, MalformedTablesGetOneClearMessage) {
  const auto fails = [](const std::string& text, const char* message) {
    EXPECT_THAT([&] { io::mimo_frf_from_table(io::parse_csv(text, "f.csv")); },
                ThrowsMessage<InvalidArgument>(HasSubstr(message)));
  };
  fails("f,y1/u1_real,y1/u1_imag\n1,1,1\n", "f.csv: no frequency column");
  fails("frequency,y1/u1_real\n1,1\n", "column 'y1/u1_real' has no partner 'y1/u1_imag'");
  fails("frequency,y1/u1_imag\n1,1\n", "column 'y1/u1_imag' has no partner 'y1/u1_real'");
  fails("frequency,a\n1,1\n", "no FRF columns");
  fails("frequency,y1/u1_real,y1/u1_imag,y2/u2_real,y2/u2_imag\n1,1,1,1,1\n",
        "entry y1/u2 of the 2 x 2 FRF matrix is missing");
  fails("frequency,y1/u1_real,y1/u1_imag\n2,1,1\n1,1,1\n",
        "row 2: frequency 1 does not exceed the row before's (2)");
  fails("frequency,y1/u1_real,y1/u1_imag,y1/u1_variance,y2/u1_real,y2/u1_imag\n1,1,1,1,1,1\n",
        "1 of the 2 entries have a _variance column");
}

TEST(Uff58, RoundTripKeepsNamesAndValues) {
  const io::testing::TestDirectory dir;
  const MimoFrf frf = random_frf(25, false);
  io::write_uff58(dir / "f.uff", frf);
  const MimoFrf back = io::read_mimo_frf(dir / "f.uff");
  EXPECT_EQ(back.output_names, frf.output_names);
  EXPECT_EQ(back.input_names, frf.input_names);
  ASSERT_EQ(back.frequencies.size(), frf.frequencies.size());
  // The abscissa is written as E13.5 (six digits), the values as E20.12.
  EXPECT_LT((back.frequencies - frf.frequencies).cwiseAbs().maxCoeff(), 1e-5);
  for (size_t l = 0; l < frf.response.size(); ++l) {
    EXPECT_LT((back.response[l] - frf.response[l]).cwiseAbs().maxCoeff(),
              1e-11 * frf.response[l].cwiseAbs().maxCoeff());
  }
}

TEST(Uff58, ValuesWithThreeDigitExponentsAreReadBack) {
  // fuzz/regressions/uff58/three_digit_exponent.uff: -2.75e-103 written as E20.12 filled its
  // field and ran into the value before it, so ctid refused its own file.
  MimoFrf frf = random_frf(3, false);
  frf.response[1](0, 0) = {2.802054509246e-3, -2.754250179950e-103};
  frf.response[2](0, 0) = {-1.5e250, 3.25e-300};
  const MimoFrf back = io::parse_uff58(io::format_uff58(frf), "f.uff");
  for (size_t l = 0; l < frf.response.size(); ++l) {
    EXPECT_LT((back.response[l] - frf.response[l]).cwiseAbs().maxCoeff(),
              1e-10 * frf.response[l].cwiseAbs().maxCoeff())
        << "line " << l;
  }
  EXPECT_NEAR(back.response[1](0, 0).imag() / -2.754250179950e-103, 1.0, 1e-10);
  EXPECT_NEAR(back.response[2](0, 0).imag() / 3.25e-300, 1.0, 1e-10);
}

TEST(Uff58, ChannelNamesWhoseNodeDoesNotFitItsFieldAreNumberedInstead) {
  // fuzz/regressions/uff58/wide_node.uff: a 16-digit node was written into the I10 field of
  // record 6, shifting its direction, so ctid refused its own file. Such a node is refused
  // on reading, and a channel name with one is written with the channel's own number.
  MimoFrf frf = random_frf(3, false);
  frf.output_names[0] = "2004100310041001+X";
  frf.input_names[0] = "9999999999-RZ";
  const MimoFrf back = io::parse_uff58(io::format_uff58(frf), "f.uff");
  EXPECT_EQ(back.output_names[0], "1");
  EXPECT_EQ(back.input_names[0], "9999999999-RZ");
  EXPECT_LT((back.response[0] - frf.response[0]).cwiseAbs().maxCoeff(),
            1e-10 * frf.response[0].cwiseAbs().maxCoeff());
}

TEST(Uff58, EveryChannelIsWrittenWithItsOwnNodeAndDirection) {
  // fuzz/regressions/uff58/taken_node.uff: a response read as node -10 (a name that is no
  // "<node><sign><direction>") was numbered 1 on writing, beside a response that is node 1, so
  // ctid refused its own file ("repeats response 1"). Names that are not channels, or that
  // name a channel an earlier name took, now get the first node no channel of the list uses.
  MimoFrf frf = random_frf(3, false);
  frf.output_names = {"-10+RY", "1", "01"};
  frf.input_names = {"accelerometer", "1001"};
  const MimoFrf back = io::parse_uff58(io::format_uff58(frf), "f.uff");
  EXPECT_EQ(back.output_names, (std::vector<std::string>{"2", "1", "3"}));
  EXPECT_EQ(back.input_names, (std::vector<std::string>{"1002", "1001"}));
  for (size_t l = 0; l < frf.response.size(); ++l) {
    EXPECT_LT((back.response[l] - frf.response[l]).cwiseAbs().maxCoeff(),
              1e-10 * frf.response[l].cwiseAbs().maxCoeff());
  }
}

// One record in the layout of the format's documentation, with fields to replace.
std::string record(const std::string& type = "4", const std::string& ordinate = "5",
                   const std::string& response = "1", const std::string& reference = "2",
                   const std::string& count = "2") {
  char r6[120];
  std::snprintf(r6, sizeof r6, "%5s%10d%5d%10d %-10s%10s%4d %-10s%10s%4d\n", type.c_str(), 1, 1, 0,
                "NONE", response.c_str(), 3, "NONE", reference.c_str(), 3);
  return std::string("    -1\n    58\nid\nNONE\nNONE\nNONE\nNONE\n") + r6 + "         " + ordinate +
         "         " + count +
         "         1  0.00000E+00  5.00000E-01  0.00000E+00\n"
         "        18    0    0    0 Frequency            Hz\n"
         "        12    0    0    0 NONE                 NONE\n"
         "        13    0    0    0 NONE                 NONE\n"
         "         0    0    0    0 NONE                 NONE\n"
         "  1.00000E+00  2.00000E+00  3.00000E+00 -4.00000E+00\n"
         "    -1\n";
}

// The ID line (record 1) holds the channel names as free text. A NUL or a line break in a
// name was written into it as is: a line break shifted every record after it, so ctid refused
// its own file, and a NUL went into the file. Control bytes are written escaped (\x00), and
// the reader, which names channels by node and direction, never takes a name from that line.
TEST(Uff58, ChannelNamesWithANulOrALineBreakAreWrittenEscapedAndReadBack) {
  MimoFrf frf = random_frf(3, false);
  frf.output_names[1] = std::string("a\0b", 3);
  frf.input_names[0] = "c\n    -1\nd";
  const std::string text = io::format_uff58(frf);
  EXPECT_EQ(text.find('\0'), std::string::npos);
  EXPECT_THAT(text, HasSubstr("\na\\x00b/c\\x0a    -1\\x0ad\n"));
  const MimoFrf back = io::parse_uff58(text, "f.uff");
  ASSERT_EQ(back.output_count(), 3);
  ASSERT_EQ(back.input_count(), 2);
  for (const auto* names : {&back.output_names, &back.input_names}) {
    for (const std::string& name : *names) {
      for (const char c : name) EXPECT_GE(static_cast<unsigned char>(c), 0x20) << name;
    }
  }
  for (std::size_t l = 0; l < back.response.size(); ++l) {
    EXPECT_LT((back.response[l] - frf.response[l]).cwiseAbs().maxCoeff(),
              1e-10 * frf.response[l].cwiseAbs().maxCoeff());
  }
}

TEST(Uff58, ANulByteInAFilesIdLineIsNoPartOfAChannelName) {
  const MimoFrf frf = random_frf(2, false);
  std::string text = io::format_uff58(frf);
  const std::size_t id = text.find("11+Z/101+X");
  ASSERT_NE(id, std::string::npos);
  text.insert(id + 2, std::string(1, '\0'));
  const MimoFrf back = io::parse_uff58(text, "f.uff");
  EXPECT_EQ(back.output_names, frf.output_names);
  EXPECT_EQ(back.input_names, frf.input_names);
}

TEST(Uff58, EvenSingleRecordsAndOtherDatasetsAreRead) {
  const std::string text =
      "    -1\n   151\nmodel\n    -1\n" + record("4", "5", "1", "2") + record("4", "5", "3", "2");
  const MimoFrf frf = io::parse_uff58(text, "f.uff");
  EXPECT_EQ(frf.output_names, (std::vector<std::string>{"1+Z", "3+Z"}));
  EXPECT_EQ(frf.input_names, (std::vector<std::string>{"2+Z"}));
  ASSERT_EQ(frf.frequencies.size(), 2);
  EXPECT_DOUBLE_EQ(frf.frequencies(1), std::numbers::pi);  // 0.5 Hz
  EXPECT_EQ(frf.response[1](1, 0), std::complex<double>(3.0, -4.0));
}

TEST(Uff58, MalformedFilesGetOneClearMessage) {
  const auto fails = [](const std::string& text, const char* message) {
    EXPECT_THAT([&] { io::parse_uff58(text, "f.uff"); },
                ThrowsMessage<InvalidArgument>(HasSubstr(message)));
  };
  fails(record("1"), "function type 1 (time response) is not an FRF");
  fails(record("4", "2"), "ordinate data type 2 is not complex");
  fails(record("4", "5", "1", "2", "3"), "record 12 holds 4 numbers but record 7 announces 3");
  fails(record() + record(), "repeats response 1+Z / reference 2+Z");
  fails(record("4", "5", "1", "2") + record("4", "5", "1", "4") + record("4", "5", "3", "2"),
        "the FRF from reference 4+Z to response 3+Z is missing");
  fails("    -1\n   151\nmodel\n    -1\n", "no dataset 58");
  fails("    -1\n    58b     2\nx\n    -1\n", "dataset 58b (binary) is not read");
  fails("    -1\n    58\nid\n", "dataset 58 is not closed");
  fails("    -1\n    58\nid\nNONE\n    -1\n", "a dataset 58 has 11 header records");
  fails("junk\n", "f.uff:1: 'junk' is outside any dataset");
  // A node of more than 10 digits, readable from blank-separated fields only.
  std::string wide = record();
  const std::size_t r6 = wide.find("NONE\nNONE\nNONE\nNONE\n") + 20;
  wide.replace(r6, wide.find('\n', r6) - r6, "    4 1 1 0 NONE 1 3 NONE 2004100310041001 0");
  fails(wide, "node 2004100310041001 does not fit the 10 columns of its field");
  std::string bad = record();
  bad.replace(bad.find("-4.00000E+00"), 12, "-4.0000XE+00");
  fails(bad, "'-4.0000XE+00' is not a finite number");
}

TEST(FrfMatrixFitDocument, RoundTripsThroughReadResult) {
  const io::testing::TestDirectory dir;
  MimoSubmodel mode{Polynomial{1.0, 0.02, 0.25}, {Polynomial{1.0, 0.1}, Polynomial{-0.5, 0.2}}};
  const MimoAdditiveModel truth(1, 2, {mode});
  MimoFrf frf;
  frf.frequencies = Eigen::VectorXd::LinSpaced(60, 0.2, 6.0);
  frf.response = mimo_frequency_response(truth, frf.frequencies);
  frf.output_names = {"a", "b"};
  frf.input_names = {"u"};
  std::mt19937_64 rng(1);
  std::normal_distribution<double> normal;
  for (Eigen::MatrixXcd& h : frf.response) h(0, 0) += 0.01 * std::complex<double>(normal(rng), 0);
  const FrfMatrixFitResult r = frf_matrix_fit(frf, {{2, 1, 0}});
  io::write_result(dir / "r.json", r);
  const auto back = std::get<FrfMatrixFitResult>(io::read_result(dir / "r.json"));
  EXPECT_EQ(back.message, r.message);
  EXPECT_EQ(back.fit_percent, r.fit_percent);
  EXPECT_EQ(back.covariance, r.covariance);
  ASSERT_EQ(back.modes.size(), 1u);
  EXPECT_EQ(back.modes[0].natural_frequency_se, r.modes[0].natural_frequency_se);
  EXPECT_EQ(back.model->numerator(0, 1, 0).coefficients(),
            r.model->numerator(0, 1, 0).coefficients());
}

}  // namespace
}  // namespace ctid::mimo_frf_file_test
