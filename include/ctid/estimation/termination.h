// The outcome of every iterative method in ctid (the refined IV iterations of González et al.,
// the delayed-feedback refinements of De Iuliis et al., searches and scans): why it stopped,
// one sentence saying where, and how many iterations it took. A numerical outcome is never an
// exception: bad input throws ctid::InvalidArgument before anything runs, everything after
// that ends in a Termination. A result that was never computed reads `not_run`.
#pragma once

#include <array>
#include <span>
#include <string>
#include <string_view>
#include <tuple>

#include "ctid/core/fields.h"

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

inline constexpr std::array<Enumerator<Termination>, 7> termination_enumerators{{
    {Termination::not_run, "not_run", "Nothing was computed."},
    {Termination::converged, "converged", "The stopping rule was met."},
    {Termination::iteration_limit, "iteration_limit", "The iteration budget ran out first."},
    {Termination::singular_equations, "singular_equations",
     "The equations of a step are numerically singular."},
    {Termination::non_finite, "non_finite", "An iterate, a cost or a signal became NaN/Inf."},
    {Termination::closed_loop_unstable, "closed_loop_unstable",
     "The controller does not stabilise the model the method needs."},
    {Termination::no_solution, "no_solution", "Every start or candidate failed."},
}};
constexpr std::span<const Enumerator<Termination>> enumerators(Termination) {
  return termination_enumerators;
}

/// Short name: "not_run", "converged", "iteration_limit", ...
inline std::string to_string(Termination termination) {
  return std::string(enum_name(termination));
}

/// Termination, message and iteration count: the fields every iterative result carries (by
/// deriving from it), with the one-line report the CLI prints, Python shows and JSON stores.
struct Outcome {
  Termination termination = Termination::not_run;
  std::string message;  ///< one sentence: why it stopped and where
  int iterations = 0;

  static constexpr std::string_view type_name = "Outcome";
  static constexpr auto fields() {
    return std::tuple{
        field("termination", &Outcome::termination, "Why the method stopped."),
        field("message", &Outcome::message, "One sentence: why it stopped and where."),
        field("iterations", &Outcome::iterations, AtLeast{0}, "Iterations run."),
    };
  }

  bool converged() const { return termination == Termination::converged; }
  /// "converged after 8 iterations", followed by ": <message>" unless converged or empty.
  std::string brief_report() const;
};

}  // namespace ctid
