#include "ctid/estimation/verdict.h"

#include <cmath>
#include <complex>
#include <utility>

#include "ctid/core/format.h"

namespace ctid {

void Verdict::fail(std::string reason, std::initializer_list<std::string_view> remedies) {
  usable = false;
  reasons.push_back(std::move(reason));
  for (const std::string_view remedy : remedies) {
    if (remedy.empty() || advice.find(remedy) != std::string::npos) continue;
    if (!advice.empty()) advice += "; ";
    advice += remedy;
  }
}

std::string Verdict::summary() const {
  if (usable) return {};
  std::string text = "no usable model: ";
  for (std::size_t i = 0; i < reasons.size(); ++i) {
    if (i > 0) text += "; ";
    text += reasons[i];
  }
  text += ".";
  if (!advice.empty()) text += " Try: " + advice + ".";
  return text;
}

void check_finite(Verdict& verdict, bool finite, std::string_view what) {
  if (!finite) {
    verdict.fail(std::string(what) + " is not finite", {verdict_advice::better_start});
  }
}

void check_fit(Verdict& verdict, double fit_percent, double start_fit_percent) {
  if (!std::isfinite(fit_percent)) {
    verdict.fail("the output-error fit is not finite", {verdict_advice::better_start});
    return;
  }
  if (fit_percent < 0.0) {
    verdict.fail("the output-error fit " + format_brief(fit_percent) +
                     " % is negative (worse than the mean of the output)",
                 {verdict_advice::lower_order, verdict_advice::better_start});
  }
  if (std::isfinite(start_fit_percent) &&
      fit_percent < start_fit_percent - verdict_thresholds::fit_tolerance_points) {
    verdict.fail("the output-error fit " + format_brief(fit_percent) +
                     " % is worse than the start's " + format_brief(start_fit_percent) + " %",
                 {verdict_advice::better_start});
  }
}

void check_closed_loop_fit(Verdict& verdict, double fit_percent, double start_fit_percent) {
  if (std::isfinite(fit_percent) && fit_percent < 0.0) {
    verdict.fail("the closed-loop fit from the reference " + format_brief(fit_percent) +
                     " % is negative (the model's loop output from r is worse than the mean of "
                     "the output)",
                 {verdict_advice::lower_order, verdict_advice::better_start});
    return;
  }
  if (std::isfinite(fit_percent) && std::isfinite(start_fit_percent) && start_fit_percent > 0.0 &&
      fit_percent < verdict_thresholds::closed_loop_fit_share * start_fit_percent) {
    verdict.fail("the closed-loop fit from the reference " + format_brief(fit_percent) +
                     " % is less than half the start's " + format_brief(start_fit_percent) + " %",
                 {verdict_advice::better_start});
  }
}

void check_stable(Verdict& verdict, const Eigen::VectorXcd& poles) {
  for (Eigen::Index j = 0; j < poles.size(); ++j) {
    if (poles(j) == std::complex<double>(0.0, 0.0)) continue;
    if (!(poles(j).real() < 0.0)) {
      verdict.fail("the pole " + format_brief(poles(j).real()) +
                       (poles(j).imag() >= 0.0 ? " + " : " - ") +
                       format_brief(std::abs(poles(j).imag())) + "i is not stable",
                   {verdict_advice::lower_order});
      return;
    }
  }
}

void check_standard_errors(Verdict& verdict, const std::vector<std::string>& names,
                           const Eigen::VectorXd& values, const Eigen::VectorXd& standard_errors) {
  for (Eigen::Index j = 0; j < values.size() && j < standard_errors.size(); ++j) {
    const double se = standard_errors(j);
    if (std::isfinite(se) && se > std::abs(values(j))) {
      const std::string name =
          static_cast<std::size_t>(j) < names.size() ? names[static_cast<std::size_t>(j)] : "";
      verdict.fail("the standard error " + format_brief(se) + " of " + name + " " +
                       format_brief(values(j)) + " is larger than its value",
                   {verdict_advice::lower_order});
    }
  }
}

void check_cancellation(Verdict& verdict, const Eigen::VectorXcd& poles,
                        const Eigen::VectorXcd& zeros) {
  for (Eigen::Index j = 0; j < poles.size(); ++j) {
    const std::complex<double> pole = poles(j);
    // One report per conjugate pair; poles at the origin are integrators the structure chose.
    if (pole.imag() < 0.0 || std::abs(pole) == 0.0) continue;
    for (Eigen::Index k = 0; k < zeros.size(); ++k) {
      const double distance = std::abs(zeros(k) - pole);
      if (distance < verdict_thresholds::cancellation_distance * std::abs(pole)) {
        verdict.fail("a zero cancels the pole " + format_brief(pole.real()) +
                         (pole.imag() > 0.0 ? " + " + format_brief(pole.imag()) + "i" : "") +
                         " (distance " + format_brief(distance / std::abs(pole)) +
                         " of |pole|): the order is higher than the data support",
                     {verdict_advice::lower_order});
        break;
      }
    }
  }
}

void check_conditioning(Verdict& verdict, double reciprocal_condition, double fit_percent) {
  if (std::isnan(reciprocal_condition)) return;
  if (fit_percent >= verdict_thresholds::exact_fit_percent) return;
  if (!(reciprocal_condition >= verdict_thresholds::reciprocal_condition)) {
    verdict.fail(
        "the instrument-regressor equations are numerically singular (reciprocal "
        "condition " +
            format_brief(reciprocal_condition) + ")",
        {verdict_advice::lower_order, verdict_advice::more_data});
  }
}

}  // namespace ctid
