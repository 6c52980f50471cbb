// Errors raised by ctid. Failing to run (bad data, bad options, malformed files) throws
// ctid::InvalidArgument with one sentence naming what is wrong; the outcome of an
// iterative method (converged, iteration limit, unstable iterate) is never an exception
// and is reported in the method's result instead.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

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
template <typename... Parts>
std::string concat(Parts&&... parts) {
  std::ostringstream out;
  out.precision(17);
  (out << ... << std::forward<Parts>(parts));
  return out.str();
}
}  // namespace internal

/// Throws InvalidArgument with the concatenation of `parts` unless `condition` holds.
template <typename... Parts>
void require(bool condition, Parts&&... parts) {
  if (!condition) throw InvalidArgument(internal::concat(std::forward<Parts>(parts)...));
}

}  // namespace ctid
