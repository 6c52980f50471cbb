#include "ctid/core/format.h"

#include <charconv>
#include <system_error>

#include "ctid/core/error.h"

namespace ctid {

// Every number is written with std::to_chars, which gives the characters printf gives in the C
// locale whatever the process's LC_NUMERIC: Python's locale.setlocale(LC_NUMERIC, "de_DE")
// made snprintf write "0,05" into messages and files (issue 33).

std::string format_significant(double x, int digits) {
  require(digits >= 1 && digits <= 17, "format_significant: digits is ", digits,
          "; it must be in [1, 17]");
  char buffer[40];
  const auto [end, error] =
      std::to_chars(buffer, buffer + sizeof buffer, x, std::chars_format::general, digits);
  require(error == std::errc(), "format_significant: ", digits, " digits do not fit");
  return std::string(buffer, end);
}

std::string format_number(double x) { return format_significant(x, 12); }

std::string format_brief(double x) { return format_significant(x, 6); }

std::string format_fixed(double x, int decimals) {
  require(decimals >= 0 && decimals <= 17, "format_fixed: decimals is ", decimals,
          "; it must be in [0, 17]");
  char buffer[360];  // 309 digits of DBL_MAX, the sign, the point and 17 decimals
  const auto [end, error] =
      std::to_chars(buffer, buffer + sizeof buffer, x, std::chars_format::fixed, decimals);
  require(error == std::errc(), "format_fixed: ", decimals, " decimals do not fit");
  return std::string(buffer, end);
}

std::string format_round_trip(double x) {
  char buffer[40];
  const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, x);
  if (error != std::errc()) return format_significant(x, 17);  // not reached: 40 chars suffice
  return std::string(buffer, end);
}

}  // namespace ctid
