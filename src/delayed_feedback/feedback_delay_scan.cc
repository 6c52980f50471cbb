// Scan of the feedback delay by a criterion of the step-1 model.
#include "ctid/delayed_feedback/feedback_delay_scan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/delayed_feedback/loop_parameters.h"
#include "ctid/delayed_feedback/output_error.h"
#include "ctid/delayed_feedback/structured_step1.h"
#include "delayed_feedback/internal/golden_section.h"
#include "delayed_feedback/internal/structured_system.h"

namespace ctid {

using internal::golden_section_minimum;
using internal::iv_start;

void FeedbackDelayScanOptions::check_relations(const std::string& path) const {
  require(max_delay > min_delay, path, ".max_delay is ", max_delay, "; it must be > min_delay (",
          min_delay, ")");
  iv.check_agrees(path + ".iv", hold, substeps);
}

FeedbackDelayScanResult scan_feedback_delay(const SampledData& data, int n, int m,
                                            const FeedbackDelayScanOptions& options,
                                            const std::function<void(int, int)>& progress) {
  options.validate();
  require(n >= 1 && m >= 1, "scan_feedback_delay: orders must be >= 1, got n = ", n, ", m = ", m);
  const double inf = std::numeric_limits<double>::infinity();
  int evaluations = 0;
  auto criterion = [&](double delay) {
    ++evaluations;
    // A delay at which the regression cannot be built (beyond the record) scores +inf.
    if (feedback_regression_problem(data, n, m, delay, options.regressors)) return inf;
    {
      const FeedbackRegression reg =
          build_feedback_regression(data, n, m, delay, options.regressors);
      if (options.criterion == DelayCriterion::structured_output_error ||
          options.criterion == DelayCriterion::refined_output_error) {
        const StructuredStep1Result st = estimate_structured_step1(reg);
        double rms = loop_output_rms(data, st.loop, options.hold, options.substeps);
        if (options.criterion == DelayCriterion::refined_output_error) {
          OutputErrorOptions oe;
          oe.hold = options.hold;
          oe.substeps = options.substeps;
          oe.max_iterations = options.refined_iterations;
          std::vector<DelayedFeedbackLoop> starts;
          if (std::isfinite(rms)) starts.push_back(st.loop);
          StructuredIvOptions iv = options.iv;
          iv.hold = options.hold;
          iv.substeps = options.substeps;
          for (double pole : options.iv_filter_poles) {
            // No stable start at this pole: output_rms is +inf.
            const StructuredIvResult r = iv_start(data, n, m, delay, options.regressors, pole, iv);
            if (std::isfinite(r.output_rms)) starts.push_back(r.loop);
            rms = std::min(rms, r.output_rms);
          }
          for (const DelayedFeedbackLoop& start : starts) {
            const OutputErrorResult fit = refine_output_error(data, start, oe);
            if (std::isfinite(fit.residual_rms)) rms = std::min(rms, fit.residual_rms);
          }
        }
        return rms * rms;
      }
      const ClosedLoopEstimate est = estimate_closed_loop_batch(reg, options.least_squares);
      if (!est.converged()) return inf;  // a singular or non-finite step 1
      if (options.criterion == DelayCriterion::equation_error)
        return est.residual_rms * est.residual_rms;
      const Eigen::VectorXd y = simulate_delayed(
          to_delayed_state_space(est.alpha, est.beta, est.gamma, delay), data.input(),
          data.sample_time(), options.hold, DelayedSimulationOptions{options.substeps});
      if (!y.allFinite()) return inf;
      const double mse = (data.output() - y).squaredNorm() / static_cast<double>(y.size());
      return std::isfinite(mse) ? mse : inf;
    }
  };
  FeedbackDelayScanResult r;
  r.delays = Eigen::VectorXd::LinSpaced(options.points, options.min_delay, options.max_delay);
  r.criterion.resize(options.points);
  Eigen::Index best = 0;
  for (int i = 0; i < options.points; ++i) {
    r.criterion(i) = criterion(r.delays(i));
    if (r.criterion(i) < r.criterion(best)) best = i;
    if (progress) progress(i + 1, options.points);
  }
  r.delay = r.delays(best);
  r.best_criterion = r.criterion(best);
  if (options.refine && std::isfinite(r.best_criterion)) {
    const double lo = r.delays(std::max<Eigen::Index>(0, best - 1));
    const double hi = r.delays(std::min<Eigen::Index>(options.points - 1, best + 1));
    const auto [x, f] = golden_section_minimum(criterion, lo, hi, 25);
    if (f < r.best_criterion) {
      r.delay = x;
      r.best_criterion = f;
    }
  }
  r.iterations = evaluations;
  if (std::isfinite(r.best_criterion)) {
    r.termination = Termination::converged;
    r.message = "the criterion is smallest at delay " + internal::concat(r.delay) + " s";
  } else {
    r.termination = Termination::no_solution;
    r.message = "every delay of the scan is unstable, degenerate or beyond the record";
  }
  return r;
}

}  // namespace ctid
