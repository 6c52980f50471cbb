// Errors raised by ctid. Failing to run (bad data, bad options, malformed files) throws
// ctid::InvalidArgument with one sentence naming what is wrong; the outcome of an
// iterative method (converged, iteration limit, unstable iterate) is never an exception
// and is reported in the method's result instead.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include "ctid/core/format.h"

namespace ctid {

/// Bad input to a ctid function: the message names the argument, its value and the rule.
class InvalidArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A computation that could not be carried out on valid input (e.g. a loop that is
/// unstable, a singular system that the caller could not have foreseen).
class ComputationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace internal {
/// A part of a message: a floating-point number as the shortest text that reads back as the
/// same value ("0.1", not "0.10000000000000001"; docs/conventions.md), anything else as is.
template <typename Part>
decltype(auto) message_part(Part&& part) {
  if constexpr (std::is_floating_point_v<std::remove_cvref_t<Part>>) {
    return format_round_trip(static_cast<double>(part));
  } else {
    return std::forward<Part>(part);
  }
}

/// The text of `parts` streamed one after the other; numbers as message_part writes them.
template <typename... Parts>
std::string concat(Parts&&... parts) {
  std::ostringstream out;
  out.precision(17);  // what still streams doubles itself (Eigen vectors) keeps every digit
  (out << ... << message_part(std::forward<Parts>(parts)));
  return out.str();
}
}  // namespace internal

/// Throws InvalidArgument with the concatenation of `parts` unless `condition` holds.
template <typename... Parts>
void require(bool condition, Parts&&... parts) {
  if (!condition) throw InvalidArgument(internal::concat(std::forward<Parts>(parts)...));
}

}  // namespace ctid
