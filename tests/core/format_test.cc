#include "ctid/core/format.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"

namespace ctid::format_test {
namespace {

// What the formatters replaced: printf %.Ng and a stream with precision N.
std::string printf_g(double x, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, x);
  return buffer;
}
std::string stream_g(double x, int digits) {
  std::ostringstream out;
  out.precision(digits);
  out << x;
  return out.str();
}

const double kSamples[] = {0.0,
                           -0.0,
                           0.1,
                           0.05,
                           1.0 / 3.0,
                           -2.5e-11,
                           8.37e-11,
                           1e-10,
                           123456789.0,
                           1.41629187e3,
                           1e300,
                           4.9e-324,
                           std::numeric_limits<double>::infinity(),
                           -std::numeric_limits<double>::infinity(),
                           std::numeric_limits<double>::quiet_NaN()};

TEST(Format, SignificantDigitsAreThePrintfAndStreamForms) {
  for (double x : kSamples) {
    for (int digits : {3, 6, 12, 17}) {
      EXPECT_EQ(format_significant(x, digits), printf_g(x, digits)) << x << " " << digits;
      EXPECT_EQ(format_significant(x, digits), stream_g(x, digits)) << x << " " << digits;
    }
  }
}

TEST(Format, BriefAndNumberKeepTheirPrecision) {
  EXPECT_EQ(format_brief(1.416291873), "1.41629");
  EXPECT_EQ(format_brief(2.53845e-11), "2.53845e-11");
  EXPECT_EQ(format_brief(80.0), "80");
  EXPECT_EQ(format_number(0.1), "0.1");
  EXPECT_EQ(format_number(0.1 + 0.2), "0.3");
  EXPECT_EQ(format_number(1e-10), "1e-10");
  EXPECT_EQ(format_number(0.123456789012345), "0.123456789012");
}

TEST(Format, RoundTripIsShortestAndExact) {
  EXPECT_EQ(format_round_trip(0.1), "0.1");
  EXPECT_EQ(format_round_trip(0.1 + 0.2), "0.30000000000000004");
  EXPECT_EQ(format_round_trip(1e-10), "1e-10");
  EXPECT_EQ(format_round_trip(-0.0), "-0");
  EXPECT_EQ(format_round_trip(std::numeric_limits<double>::infinity()), "inf");
  for (double x : kSamples) {
    if (std::isnan(x)) {
      EXPECT_EQ(format_round_trip(x), "nan");
      continue;
    }
    const std::string text = format_round_trip(x);
    EXPECT_EQ(std::strtod(text.c_str(), nullptr), x) << text;
    EXPECT_LE(text.size(), printf_g(x, 17).size()) << text;
  }
}

TEST(Format, DigitsOutsideOneToSeventeenAreRefused) {
  EXPECT_THROW(format_significant(1.0, 0), InvalidArgument);
  EXPECT_THROW(format_significant(1.0, 18), InvalidArgument);
}

}  // namespace
}  // namespace ctid::format_test
