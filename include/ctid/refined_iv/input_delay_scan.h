// Input-delay estimation for the refined IV estimators: run the estimator for every integer
// delay in a range and keep the best output-error fit (González et al., Section 7 reports a
// 4-sample delay found this way). Works with any estimator through a callback.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/sampled_data.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

struct InputDelayScanResult {
  EstimationResult best;  ///< the estimate at the delay with the smallest mean squared error
  std::vector<int> delays;
  std::vector<double> mean_squared_errors;  ///< per delay; +inf where the estimator threw
  std::vector<Termination> terminations;    ///< per delay (not_run where the estimator refused it)
  std::vector<bool> usable;  ///< per delay: the estimate's verdict (false if refused)
  /// False when another delay's estimate of the same usability has a mean squared error
  /// within kDelayScanTieRatio of the chosen one's: the data do not pick the delay clearly.
  bool choice_clear = true;
  std::string note;  ///< one sentence when the choice is not clear (or no estimate was usable)

  static constexpr std::string_view type_name = "InputDelayScanResult";
  static constexpr auto fields() {
    using S = InputDelayScanResult;
    return std::tuple{
        field("best", &S::best, "The estimate at the delay with the smallest output error."),
        field("delays", &S::delays, "Delays tried [samples]."),
        field("mean_squared_errors", &S::mean_squared_errors,
              "Output-error MSE per delay (inf where the estimator refused it)."),
        field("terminations", &S::terminations,
              "Termination per delay (not_run where the estimator refused it)."),
        field("usable", &S::usable, "Verdict per delay (false where the estimator refused it)."),
        field("choice_clear", &S::choice_clear,
              "False when a runner-up's output error is within 1 % of the chosen one's."),
        field("note", &S::note, "Why the choice is not clear, or empty."),
    };
  }
};

/// Relative margin of mean squared error under which two delays are not told apart.
inline constexpr double kDelayScanTieRatio = 0.01;

/// Calls `estimate(delay)` for delay = min_delay..max_delay and keeps the estimate with the
/// smallest output error among those whose verdict is usable (among all if none is), whether
/// or not its iteration converged: convergence of (29) says nothing about the fit. Throws
/// InvalidArgument for a bad range or if every delay throws (the first message is passed on).
/// `progress`, if given, is called after each delay with the number of delays tried and the
/// number in the range. The delays are fitted in parallel on all cores (core/parallel.h), so
/// `estimate` must be safe to call from several threads at once (progress is called under a
/// lock); the result is the serial one whatever the number of threads.
InputDelayScanResult scan_input_delay(const std::function<EstimationResult(int)>& estimate,
                                      int min_delay, int max_delay,
                                      const std::function<void(int, int)>& progress = {});

/// additive_srivc over a delay range (options.input_delay_samples is overridden).
InputDelayScanResult additive_srivc_delay_scan(const SampledData& data,
                                               const std::vector<SubmodelOrder>& orders,
                                               int min_delay, int max_delay,
                                               const RefinedIvOptions& options = {});

/// srivc over a delay range.
InputDelayScanResult srivc_delay_scan(const SampledData& data, const SubmodelOrder& order,
                                      int min_delay, int max_delay,
                                      const RefinedIvOptions& options = {});

}  // namespace ctid
