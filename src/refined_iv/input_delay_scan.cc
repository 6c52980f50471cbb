// Delay estimation by scanning whole-sample delays and keeping the best output-error fit.
#include "ctid/refined_iv/input_delay_scan.h"

#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/parallel.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/srivc.h"

namespace ctid {

InputDelayScanResult scan_input_delay(const std::function<EstimationResult(int)>& estimate,
                                      int min_delay, int max_delay,
                                      const std::function<void(int, int)>& progress) {
  require(min_delay >= 0 && max_delay >= min_delay, "scan_input_delay: the delay range [",
          min_delay, ", ", max_delay, "] must satisfy 0 <= min_delay <= max_delay");
  std::optional<EstimationResult> best;
  std::string first_error;
  InputDelayScanResult table{
      EstimationResult(AdditiveModel({{Polynomial{1.0, 1.0}, Polynomial{1.0}, 0}}),
                       TransferFunction(Polynomial{1.0}, Polynomial{1.0, 1.0})),
      {},
      {},
      {},
      {},
      true,
      {}};
  // The fits run in parallel (core/parallel.h), each into its own slot; the table and the
  // choice are then made in delay order, so the outcome is the serial one.
  const int count = max_delay - min_delay + 1;
  std::vector<std::optional<EstimationResult>> fits(static_cast<std::size_t>(count));
  std::vector<std::string> errors(static_cast<std::size_t>(count));
  std::mutex progress_mutex;
  int done = 0;
  parallel_for(count, 0, [&](int k) {
    const auto slot = static_cast<std::size_t>(k);
    try {
      fits[slot] = estimate(min_delay + k);
    } catch (const InvalidArgument& e) {
      errors[slot] = e.what();
    }
    if (progress) {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      progress(++done, count);
    }
  });
  for (int k = 0; k < count; ++k) {
    const auto slot = static_cast<std::size_t>(k);
    table.delays.push_back(min_delay + k);
    if (fits[slot]) {
      EstimationResult& r = *fits[slot];
      table.mean_squared_errors.push_back(r.mean_squared_error);
      table.terminations.push_back(r.termination);
      table.usable.push_back(r.verdict.usable);
      // Usable before unusable, then the smaller output error (NaN never wins).
      const bool better = !best || (r.verdict.usable && !best->verdict.usable) ||
                          (r.verdict.usable == best->verdict.usable &&
                           (r.mean_squared_error < best->mean_squared_error ||
                            std::isnan(best->mean_squared_error)));
      if (better) best = std::move(r);
    } else {
      if (first_error.empty()) first_error = errors[slot];
      table.mean_squared_errors.push_back(std::numeric_limits<double>::infinity());
      table.terminations.push_back(Termination::not_run);  // the estimator refused this delay
      table.usable.push_back(false);
    }
  }
  require(best.has_value(),
          "scan_input_delay: every delay failed; the first error was: ", first_error);
  const double chosen = best->mean_squared_error;
  for (size_t k = 0; k < table.delays.size(); ++k) {
    if (table.delays[k] == best->input_delay_samples || table.usable[k] != best->verdict.usable)
      continue;
    if (table.mean_squared_errors[k] <= chosen * (1.0 + kDelayScanTieRatio)) {
      table.choice_clear = false;
      table.note = "the delay is not clear: " + std::to_string(table.delays[k]) +
                   " samples fit within " + format_brief(100.0 * kDelayScanTieRatio) +
                   " % of the output error of the chosen " +
                   std::to_string(best->input_delay_samples);
      break;
    }
  }
  if (!best->verdict.usable) {
    table.note += std::string(table.note.empty() ? "" : "; ") +
                  "no delay gave a usable model (the one with the smallest output error is kept)";
  }
  table.best = std::move(*best);
  return table;
}

InputDelayScanResult additive_srivc_delay_scan(const SampledData& data,
                                               const std::vector<SubmodelOrder>& orders,
                                               int min_delay, int max_delay,
                                               const RefinedIvOptions& options) {
  return scan_input_delay(
      [&](int d) {
        RefinedIvOptions o = options;
        o.input_delay_samples = d;
        return additive_srivc(data, orders, o);
      },
      min_delay, max_delay);
}

InputDelayScanResult srivc_delay_scan(const SampledData& data, const SubmodelOrder& order,
                                      int min_delay, int max_delay,
                                      const RefinedIvOptions& options) {
  return scan_input_delay(
      [&](int d) {
        RefinedIvOptions o = options;
        o.input_delay_samples = d;
        return srivc(data, order, o);
      },
      min_delay, max_delay);
}

}  // namespace ctid
