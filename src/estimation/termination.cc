#include "ctid/estimation/termination.h"

namespace ctid {

std::string to_string(Termination termination) {
  switch (termination) {
    case Termination::not_run:
      return "not_run";
    case Termination::converged:
      return "converged";
    case Termination::iteration_limit:
      return "iteration_limit";
    case Termination::singular_equations:
      return "singular_equations";
    case Termination::non_finite:
      return "non_finite";
    case Termination::closed_loop_unstable:
      return "closed_loop_unstable";
    case Termination::no_solution:
      return "no_solution";
  }
  return "unknown";
}

std::optional<Termination> termination_from_name(std::string_view name) {
  for (Termination t : all_terminations) {
    if (to_string(t) == name) return t;
  }
  return std::nullopt;
}

std::string Outcome::brief_report() const {
  if (termination == Termination::not_run) {
    return message.empty() ? "not run" : "not run: " + message;
  }
  std::string text = to_string(termination) + " after " + std::to_string(iterations) +
                     (iterations == 1 ? " iteration" : " iterations");
  if (!converged() && !message.empty()) text += " (" + message + ")";
  return text;
}

}  // namespace ctid
