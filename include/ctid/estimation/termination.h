// The outcome of every iterative method in ctid (the refined IV iterations of González et al.,
// the delayed-feedback refinements of De Iuliis et al., searches and scans): why it stopped,
// one sentence saying where, and how many iterations it took. A numerical outcome is never an
// exception: bad input throws ctid::InvalidArgument before anything runs, everything after
// that ends in a Termination. A result that was never computed reads `not_run`.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>

namespace ctid {

/// Why an iterative method stopped. Only `converged` means its stationary point was met to
/// the tolerance; every other ending still returns the best iterate it has.
enum class Termination {
  not_run,               ///< nothing was computed (the default of every result)
  converged,             ///< the stopping rule was met
  iteration_limit,       ///< the iteration budget ran out first
  singular_equations,    ///< the (scaled) equations of a step are numerically singular
  non_finite,            ///< an iterate, a cost or a filtered signal became NaN/Inf
  closed_loop_unstable,  ///< the controller does not stabilise the model the method needs
  no_solution,           ///< every start or candidate failed (unstable or non-finite)
};

/// Every Termination, in declaration order (for readers, tables and tests).
inline constexpr std::array<Termination, 7> all_terminations{
    Termination::not_run,          Termination::converged,
    Termination::iteration_limit,  Termination::singular_equations,
    Termination::non_finite,       Termination::closed_loop_unstable,
    Termination::no_solution};

/// Short name: "not_run", "converged", "iteration_limit", ...
std::string to_string(Termination termination);

/// The Termination named `name`, or nullopt.
std::optional<Termination> termination_from_name(std::string_view name);

/// Termination, message and iteration count: the fields every iterative result carries (by
/// deriving from it), with the one-line report the CLI prints, Python shows and JSON stores.
struct Outcome {
  Termination termination = Termination::not_run;
  std::string message;  ///< one sentence: why it stopped and where
  int iterations = 0;

  bool converged() const { return termination == Termination::converged; }
  /// "converged after 8 iterations", followed by ": <message>" unless converged or empty.
  std::string brief_report() const;
};

}  // namespace ctid
