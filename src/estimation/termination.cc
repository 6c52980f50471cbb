#include "ctid/estimation/termination.h"

namespace ctid {

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
