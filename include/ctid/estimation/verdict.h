// Is an estimate worth using? A verdict compares an estimate with its start and with simple
// facts (finite, stable where the structure says so, output-error fit not negative and not
// worse than the start, standard errors smaller than the values they qualify, no near
// pole-zero cancellation, a well-conditioned instrument matrix). It is separate from the
// Termination: a converged iteration can still give an unusable model, and a stopped one a
// usable model. Thresholds and why: docs/decisions/0007-quality-verdict.md.
#pragma once

#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"

namespace ctid {

/// The quality verdict on one estimate.
struct Verdict {
  bool usable = true;
  /// One sentence per failed check (empty when usable).
  std::vector<std::string> reasons;
  /// What to try, e.g. "a lower order or fewer modes; a start from the FRF peaks" (empty when
  /// usable).
  std::string advice;
  /// One sentence per constraint that acted on the estimate (enforced stability, a coefficient
  /// held at a bound; decision 0058). They do not make it unusable: they say it is the
  /// constrained estimate, not the free one.
  std::vector<std::string> active_constraints;

  static constexpr std::string_view type_name = "Verdict";
  static constexpr auto fields() {
    using S = Verdict;
    return std::tuple{
        field("usable", &S::usable, "False when any check failed: do not use the model as is."),
        field("reasons", &S::reasons, "One sentence per failed check."),
        field("advice", &S::advice, "What to try instead (empty when usable)."),
        field("active_constraints", &S::active_constraints,
              "One sentence per constraint that acted (stability, a bound)."),
    };
  }

  /// Marks the verdict unusable with `reason` and adds each remedy (once) to the advice.
  void fail(std::string reason, std::initializer_list<std::string_view> remedies);
  /// "no usable model: <reasons>. Try: <advice>" (empty when usable).
  std::string summary() const;
};

/// The thresholds of the checks (decision 0007).
namespace verdict_thresholds {
/// A zero closer to a pole than this times |pole| cancels it.
inline constexpr double cancellation_distance = 1e-3;
/// Reciprocal condition of the scaled instrument-regressor matrix below which the
/// equations do not determine the parameters.
inline constexpr double reciprocal_condition = 1e-12;
/// Fit may fall below the start's by this many percentage points before it counts as worse
/// (iterations that settle at the IV fixed point can lose a little output-error fit).
inline constexpr double fit_tolerance_points = 1.0;
/// Closed loop: a fit keeps at least this share of its start's closed-loop fit (decision 0028:
/// from the true system on tight-loop records CLSRIVC keeps 0.63 or more of it).
inline constexpr double closed_loop_fit_share = 0.5;
/// An output-error fit at or above this reproduces the record to a millionth of its RMS: 120 dB,
/// beyond any measured record, reached by noise-free data only.
inline constexpr double exact_fit_percent = 100.0 - 1e-4;
}  // namespace verdict_thresholds

// Advice strings shared by the checks, so the same remedy is written once.
namespace verdict_advice {
inline constexpr std::string_view lower_order = "a lower order or fewer modes";
inline constexpr std::string_view better_start =
    "a start nearer the data (an initial model, e.g. from the FRF peaks)";
inline constexpr std::string_view more_data = "a longer or richer record";
inline constexpr std::string_view other_structure =
    "another plant structure (more poles or zeros, or another input delay)";
}  // namespace verdict_advice

/// Fails when `finite` is false ("<what> is not finite").
void check_finite(Verdict& verdict, bool finite, std::string_view what);
/// Fails when the fit is not finite, negative, or more than fit_tolerance_points below
/// `start_fit_percent` (ignored when NaN).
void check_fit(Verdict& verdict, double fit_percent, double start_fit_percent);
/// Closed loop: fails when the closed-loop fit (of the model's output from the reference
/// through the known controller) is negative, or below closed_loop_fit_share of the start's, a
/// start with a positive closed-loop fit (ignored when either is NaN). The true loop's fit from
/// r is positive whatever the noise (y - mean y holds its output from r plus noise independent
/// of r), so a negative one is a wrong loop. In closed loop neither this fit nor
/// the output-error fit with the measured input is the estimator's criterion, so a consistent
/// estimate can fit worse than a good start; the check catches an iteration that went astray,
/// not that (decision 0028).
void check_closed_loop_fit(Verdict& verdict, double fit_percent, double start_fit_percent);
/// Fails when a pole has a non-negative real part; poles exactly at the origin (integrators
/// the structure asked for) are not counted.
void check_stable(Verdict& verdict, const Eigen::VectorXcd& poles);
/// Fails for each value whose standard error is finite and larger than |value|; `names`
/// gives each value's name in the reason (same length as `values`).
void check_standard_errors(Verdict& verdict, const std::vector<std::string>& names,
                           const Eigen::VectorXd& values, const Eigen::VectorXd& standard_errors);
/// Fails when a zero lies within cancellation_distance * |pole| of a non-zero pole.
void check_cancellation(Verdict& verdict, const Eigen::VectorXcd& poles,
                        const Eigen::VectorXcd& zeros);
/// Fails when the reciprocal condition (if not NaN) is below the threshold, unless the model
/// reproduces the record (`fit_percent` at least exact_fit_percent): then the
/// record itself pins the model down, and over-parameterised exact fits are caught by
/// check_cancellation instead (issue 33: noise-free 1/(s(s+1)) fitted with two free poles).
void check_conditioning(Verdict& verdict, double reciprocal_condition,
                        double fit_percent = std::numeric_limits<double>::quiet_NaN());

}  // namespace ctid
