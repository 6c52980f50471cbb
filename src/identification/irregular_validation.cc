// Validation of a SISO model on irregular time stamps (irregular_validation.h).
#include "ctid/identification/irregular_validation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/sampled_data.h"
#include "ctid/simulation/stamps.h"

namespace ctid {
namespace {

struct StampWindow {
  Eigen::Index first = 0;
  Eigen::Index count = 0;
};

// The stamps with window_start <= t_k <= window_end (within 1e-6 of the median step).
StampWindow stamp_window(const IrregularRecord& record, const ValidationOptions& options) {
  const Eigen::VectorXd& t = record.time;
  const Eigen::Index n = t.size();
  const double start = options.window_start.value_or(t(0));
  const double end = options.window_end.value_or(t(n - 1));
  const double tolerance = 1e-6 * record.median_step();
  const auto describe = [&] {
    return internal::concat("the window [", format_number(start), ", ", format_number(end), "] s");
  };
  const auto whole = [&] {
    return internal::concat("the record (", n, " irregular stamps, t = ", format_number(t(0)),
                            " to ", format_number(t(n - 1)), " s)");
  };
  require(start >= t(0) - tolerance && end <= t(n - 1) + tolerance, describe(), " is not inside ",
          whole());
  StampWindow w;
  while (w.first < n && t(w.first) < start - tolerance) ++w.first;
  Eigen::Index last = n - 1;
  while (last >= 0 && t(last) > end + tolerance) --last;
  w.count = std::max<Eigen::Index>(last - w.first + 1, 0);
  require(w.count >= 2, describe(), " holds ", w.count, " stamps of ", whole(),
          "; at least 2 are needed");
  return w;
}

}  // namespace

Eigen::VectorXd validation_output(const AdditiveModel& model, const IrregularRecord& record) {
  record.validate();
  return simulate_on_stamps(model, record.time, record.input, record.input_hold);
}

ValidationReport validate_model(const AdditiveModel& model, const IrregularRecord& record,
                                const ValidationOptions& options) {
  options.validate();
  record.validate();
  require(options.initial_state == InitialState::zero,
          "validate_model: initial_state = estimate is not supported on irregular time stamps; "
          "the model is simulated from rest (docs/decisions/0053)");
  const StampWindow w = stamp_window(record, options);
  const Eigen::VectorXd rest =
      simulate_on_stamps(model, record.time, record.input, record.input_hold);
  // residual_report reads the samples only; the median step stands in for a sample time.
  const SampledData scored(record.median_step(), record.input.segment(w.first, w.count),
                           record.output.segment(w.first, w.count));
  ValidationReport r = residual_report(scored, rest.segment(w.first, w.count), options.max_lag);
  r.initial_state = InitialState::zero;
  r.fit_zero_state = r.fit_percent;
  r.fit_estimated_state = std::numeric_limits<double>::quiet_NaN();
  r.window_start = record.time(w.first);
  r.window_end = record.time(w.first + w.count - 1);
  r.window_samples = static_cast<int>(w.count);
  return r;
}

}  // namespace ctid
