// Bias-corrected instrumental-variable iterations in the 2(n+m) true unknowns.
#include "ctid/delayed_feedback/structured_iv.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/QR>

#include "ctid/core/error.h"
#include "ctid/delayed_feedback/loop_parameters.h"
#include "ctid/delayed_feedback/structured_step1.h"
#include "delayed_feedback/internal/structured_system.h"

namespace ctid {

using internal::project_nuisance;
using internal::ProjectedSystem;
using internal::structured_least_squares;
namespace internal {

StructuredIvResult iv_start(const SampledData& data, int n, int m, double delay,
                            FeedbackRegressorOptions regressors, double pole,
                            const StructuredIvOptions& iv) {
  regressors.filter = RegressorFilter::linear_integral_filter;
  regressors.filter_pole = pole;
  const FeedbackRegression reg = build_feedback_regression(data, n, m, delay, regressors);
  const StructuredStep1Result st = estimate_structured_step1(reg);
  if (!std::isfinite(st.cost)) {
    StructuredIvResult none;
    none.termination = Termination::no_solution;
    none.message = "structured step 1 found no start";
    none.output_rms = std::numeric_limits<double>::infinity();
    return none;
  }
  return estimate_structured_step1_iv(data, st.loop, regressors, iv);
}

}  // namespace internal

void StructuredIvOptions::check_agrees(const std::string& path, Hold caller_hold,
                                       int caller_substeps) const {
  if (hold && *hold != caller_hold)
    throw InvalidArgument(internal::concat(path, ".hold is ", enum_name(*hold),
                                           "; it must be empty or ", enum_name(caller_hold),
                                           " (every stage continues the input the same way)"));
  if (substeps && *substeps != caller_substeps)
    throw InvalidArgument(internal::concat(path, ".substeps is ", *substeps,
                                           "; it must be empty or ", caller_substeps,
                                           " (every stage simulates the same way)"));
}

StructuredIvResult estimate_structured_step1_iv(const SampledData& data,
                                                const DelayedFeedbackLoop& start,
                                                const FeedbackRegressorOptions& regressors,
                                                const StructuredIvOptions& options) {
  options.validate();
  start.validate();
  const Hold hold = options.hold.value_or(Hold::first_order_hold);
  const int substeps = options.substeps.value_or(4);
  const int n = start.forward.denominator().degree();
  const int m = start.feedback.denominator().degree();
  const double delay = start.delay;
  const FeedbackRegression reg = build_feedback_regression(data, n, m, delay, regressors);
  const ProjectedSystem sys = project_nuisance(reg);
  StructuredIvResult r;
  r.loop = DelayedFeedbackLoop{start.forward.normalized(), start.feedback.normalized(), delay};
  r.output_rms = loop_output_rms(data, r.loop, hold, substeps);
  r.output_rms_history.push_back(r.output_rms);
  if (!std::isfinite(r.output_rms)) {
    r.termination = Termination::non_finite;
    r.message = "the start is unstable or overflows";
    return r;
  }
  Eigen::VectorXd rho = loop_parameters(r.loop);
  DelayedFeedbackLoop current = r.loop;
  for (int it = 0; it < options.iterations; ++it) {
    // Instruments: the regressors rebuilt from the current model's noise-free output.
    const Eigen::VectorXd y_model =
        simulate_delayed(to_delayed_state_space(current), data.input(), data.sample_time(), hold,
                         DelayedSimulationOptions{substeps});
    if (!y_model.allFinite() || y_model.cwiseAbs().maxCoeff() > 1e12) {
      r.termination = Termination::non_finite;
      break;
    }
    const FeedbackRegression zreg = build_feedback_regression(
        SampledData(data.sample_time(), data.input(), y_model), n, m, delay, regressors);
    Eigen::MatrixXd z = zreg.regressor.leftCols(zreg.theta_size);
    if (sys.nuisance.cols() > 0) z -= sys.nuisance * (sys.nuisance.transpose() * z);
    for (Eigen::Index j = 0; j < z.cols(); ++j)
      if (z.col(j).norm() > 0.0) z.col(j) /= z.col(j).norm();
    // Two-stage least squares: the residual projected on the span of the instruments.
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(z);
    const Eigen::MatrixXd qz = qr.householderQ() * Eigen::MatrixXd::Identity(z.rows(), z.cols());
    const Eigen::MatrixXd c = qz.transpose() * sys.c;
    const Eigen::VectorXd y = qz.transpose() * sys.y;
    Eigen::VectorXd next = rho;
    structured_least_squares(c, y, n, m, options.max_iterations, next);
    if (options.bias_correction) {
      // The same estimator applied to the model's own output: its departure from ρ is the
      // systematic error of the regression (interpolation, filter transients), removed here.
      const ProjectedSystem model_sys = project_nuisance(zreg);
      const Eigen::MatrixXd cm = qz.transpose() * model_sys.c;
      const Eigen::VectorXd ym = qz.transpose() * model_sys.y;
      Eigen::VectorXd self = rho;
      structured_least_squares(cm, ym, n, m, options.max_iterations, self);
      next += rho - self;
    }
    ++r.iterations;
    if (!next.allFinite()) {
      r.termination = Termination::non_finite;
      break;
    }
    const DelayedFeedbackLoop candidate = loop_from_parameters(next, n, m, delay);
    const double rms = loop_output_rms(data, candidate, hold, substeps);
    r.output_rms_history.push_back(rms);
    if (!std::isfinite(rms)) {
      r.termination = Termination::non_finite;
      break;
    }
    const double change = (next - rho).norm() / std::max(1.0, rho.norm());
    rho = next;
    current = candidate;
    if (rms < r.output_rms) {
      r.output_rms = rms;
      r.loop = candidate;
    }
    if (change < options.tolerance) {
      r.termination = Termination::converged;
      break;
    }
  }
  if (r.termination == Termination::not_run) r.termination = Termination::iteration_limit;
  r.message = r.termination == Termination::converged ? "instrumental-variable iterations converged"
              : r.termination == Termination::iteration_limit
                  ? "instrumental-variable iterations stopped at the limit"
                  : "an instrumental-variable iterate is unstable or overflows; the best "
                    "iterate so far is kept";
  return r;
}

}  // namespace ctid
