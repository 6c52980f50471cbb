// Numbers as text: the one formatter behind every number ctid prints in a summary, a table or a
// message (docs/conventions.md, "What ctid prints"). Four forms are in use: 6 significant
// digits for summaries (the JSON keeps every digit), 12 for a number the user gave or a file
// held, shown back in a summary, the shortest text that reads back as the same double for
// messages (internal::concat writes every floating-point part so: 0.1 reads "0.1", not
// "0.10000000000000001"), and a fixed count of decimals for a table column whose numbers
// line up (fit % to 2 decimals). All but the last two are printf's %g form: trailing zeros
// dropped, "1e-10", "nan", "inf".
#pragma once

#include <string>

namespace ctid {

/// x with `digits` significant digits (1..17) in printf's %.<digits>g form.
std::string format_significant(double x, int digits);

/// 12 significant digits: a number given on the command line or read from a file, shown back
/// in a message or a summary ("0.05", "1e-10").
std::string format_number(double x);

/// 6 significant digits: the numbers of a one-screen summary ("1.41629", "2.53845e-11").
std::string format_brief(double x);

/// The shortest text that reads back (strtod) as exactly x: "0.1", "0.30000000000000004",
/// "1e-10", "nan", "inf", "-inf".
std::string format_round_trip(double x);

/// x with `decimals` (0..17) digits after the point, for a table column: "92.77", "1.0000";
/// "nan", "inf" as printf writes them.
std::string format_fixed(double x, int decimals);

}  // namespace ctid
