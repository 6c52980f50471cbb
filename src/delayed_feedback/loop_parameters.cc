// Loop parameters ρ of a delayed-feedback loop, its simulation and output-error rms.
#include "ctid/delayed_feedback/loop_parameters.h"

#include <cmath>
#include <limits>

#include "ctid/core/error.h"
#include "delayed_feedback/internal/loop_polynomials.h"
#include "delayed_feedback/internal/loop_simulation.h"

namespace ctid {
namespace {

TransferFunction monic_model(const Eigen::VectorXd& rho, int offset, int order) {
  Eigen::VectorXd den(order + 1);
  den << rho.segment(offset, order), 1.0;
  return TransferFunction(Polynomial::trimmed(rho.segment(offset + order, order)), Polynomial(den));
}

}  // namespace

namespace internal {

// ŷ for ρ; +inf entries when the simulation overflows.
Eigen::VectorXd simulate_rho(const Eigen::VectorXd& rho, int n, int m, double delay,
                             const Eigen::VectorXd& input, double delta, Hold hold, int substeps) {
  const DelayedFeedbackLoop loop = loop_from_parameters(rho, n, m, delay);
  return simulate_delayed(to_delayed_state_space(loop), input, delta, hold,
                          DelayedSimulationOptions{substeps});
}

}  // namespace internal

Eigen::VectorXd loop_parameters(const DelayedFeedbackLoop& loop) {
  const TransferFunction f = loop.forward.normalized();
  const TransferFunction h = loop.feedback.normalized();
  const int n = f.denominator().degree();
  const int m = h.denominator().degree();
  Eigen::VectorXd rho(2 * (n + m));
  rho << internal::padded(f.denominator(), n), internal::padded(f.numerator(), n),
      internal::padded(h.denominator(), m), internal::padded(h.numerator(), m);
  return rho;
}

DelayedFeedbackLoop loop_from_parameters(const Eigen::VectorXd& rho, int n, int m, double delay) {
  require(n >= 1 && m >= 1 && rho.size() == 2 * (n + m),
          "loop_from_parameters: need n, m >= 1 and 2(n + m) = ", 2 * (n + m), " parameters, got ",
          rho.size());
  return {monic_model(rho, 0, n), monic_model(rho, 2 * n, m), delay};
}

double loop_output_rms(const SampledData& data, const DelayedFeedbackLoop& loop, Hold hold,
                       int substeps) {
  const double inf = std::numeric_limits<double>::infinity();
  if (!loop_is_simulable(loop)) return inf;
  const Eigen::VectorXd y =
      simulate_delayed(to_delayed_state_space(loop), data.input(), data.sample_time(), hold,
                       DelayedSimulationOptions{substeps});
  if (!y.allFinite() || y.cwiseAbs().maxCoeff() > 1e12) return inf;
  const double rms = std::sqrt((data.output() - y).squaredNorm() / static_cast<double>(y.size()));
  return std::isfinite(rms) ? rms : inf;
}

ValidationReport validate_loop(const DelayedFeedbackLoop& loop, const SampledData& data, Hold hold,
                               int substeps, int max_lag) {
  loop.validate();
  const Eigen::VectorXd y =
      simulate_delayed(to_delayed_state_space(loop), data.input(), data.sample_time(), hold,
                       DelayedSimulationOptions{substeps});
  return residual_report(data, y, max_lag);
}

bool loop_is_simulable(const DelayedFeedbackLoop& loop) {
  const auto finite = [](const TransferFunction& tf) {
    return tf.numerator().coefficients().allFinite() &&
           tf.denominator().coefficients().allFinite() && tf.denominator().degree() >= 1 &&
           tf.is_strictly_proper() && tf.input_delay() == 0.0;
  };
  return std::isfinite(loop.delay) && loop.delay >= 0.0 && finite(loop.forward) &&
         finite(loop.feedback);
}

}  // namespace ctid
