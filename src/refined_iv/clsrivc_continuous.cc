// CLSRIVC with a continuous-time controller (clsrivc_continuous.h, decision 0067).
#include "ctid/refined_iv/clsrivc_continuous.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/estimation/validation.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/refined_iv/srivc.h"
#include "estimation/internal/scaled_least_squares.h"
#include "refined_iv/internal/refined_iv_engine.h"
#include "refined_iv/internal/unstable_loop.h"

namespace ctid {
namespace {

// Starts iterated from, at most (the best by their closed-loop fit from r).
constexpr int kAnalogLoopStarts = 3;

// theta = [a_1..a_n, b_0..b_m] of B / (p^l A) as A (anti-monic) and B, zero leading
// coefficients dropped: a start with fewer zeros than the order is padded with b_m = 0, and an
// iterate whose a_n is 0 has a loop of lower degree, which stable_loop_denominator refuses.
Polynomial analog_plant_a(const SubmodelOrder& o, const Eigen::VectorXd& theta) {
  Eigen::VectorXd a(o.n + 1);
  a(0) = 1.0;
  a.tail(o.n) = theta.head(o.n);
  return Polynomial::trimmed(a);
}

Polynomial analog_plant_b(const SubmodelOrder& o, const Eigen::VectorXd& theta) {
  return Polynomial::trimmed(theta.tail(o.m + 1));
}

// A_cl = p^l A D_c + B N_c, or none when the loop is ill-posed (its degree falls below
// n + l + deg D_c) or not stable.
std::optional<Polynomial> stable_loop_denominator(const SubmodelOrder& o,
                                                  const Eigen::VectorXd& theta,
                                                  const TransferFunction& controller) {
  if (!theta.allFinite()) return std::nullopt;
  const Polynomial acl =
      Polynomial::monomial(o.integrators) * analog_plant_a(o, theta) * controller.denominator() +
      analog_plant_b(o, theta) * controller.numerator();
  const int degree = o.n + o.integrators + controller.denominator().degree();
  const Eigen::VectorXd& c = acl.coefficients();
  if (acl.degree() != degree || !c.allFinite()) return std::nullopt;
  if (!(std::abs(c(degree)) > 1e-12 * c.cwiseAbs().maxCoeff())) return std::nullopt;
  const Eigen::VectorXcd roots = acl.roots();
  if (!roots.allFinite() || (roots.size() > 0 && !(roots.real().maxCoeff() < 0.0))) {
    return std::nullopt;
  }
  return acl;
}

// The signals of one step at theta: instrument, regressor, left side (p^l D_c / A_cl) y and
// the model's output x = B N_c / A_cl r.
struct AnalogLoopSignals {
  Eigen::MatrixXd instrument;
  Eigen::MatrixXd regressor;
  Eigen::VectorXd left;
  Eigen::VectorXd output;
};

// Column k of `bank` combined as sum_c poly_c column(c + shift).
Eigen::VectorXd shifted_combination(const Eigen::MatrixXd& bank, const Polynomial& poly,
                                    int shift) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(bank.rows());
  for (int c = 0; c <= poly.degree(); ++c) out += poly[c] * bank.col(c + shift);
  return out;
}

std::optional<AnalogLoopSignals> analog_loop_signals(const SampledData& data,
                                                     const SubmodelOrder& o,
                                                     const Eigen::VectorXd& theta,
                                                     const TransferFunction& controller,
                                                     Hold output_interpolation) {
  const std::optional<Polynomial> acl = stable_loop_denominator(o, theta, controller);
  if (!acl) return std::nullopt;
  const std::optional<FilterRealization> bank = finite_derivative_filters(*acl);
  if (!bank) return std::nullopt;
  const double h = data.sample_time();
  const Polynomial bn = analog_plant_b(o, theta) * controller.numerator();
  Eigen::VectorXd w = Eigen::VectorXd::Zero(bank->outputs());
  w.head(bn.degree() + 1) = bn.coefficients();
  const double gain = w.norm() > 0.0 ? w.norm() : 1.0;
  const Eigen::MatrixXd fr = SampledFilter(*bank, h, data.input_hold()).apply(data.reference());
  const Eigen::MatrixXd fy = SampledFilter(*bank, h, output_interpolation).apply(data.output());
  // p^k / A_cl x from r through two cascaded banks (never one of order 2 deg A_cl).
  const Eigen::MatrixXd fx =
      gain *
      SampledFilter(cascade(*bank, w / gain, *bank), h, data.input_hold()).apply(data.reference());
  const Polynomial& dc = controller.denominator();
  const Polynomial& nc = controller.numerator();
  const int p = o.n + o.m + 1;
  AnalogLoopSignals s;
  s.instrument.resize(data.size(), p);
  s.regressor.resize(data.size(), p);
  s.left = shifted_combination(fy, dc, o.integrators);
  s.output = fr * w;
  for (int i = 1; i <= o.n; ++i) {
    s.regressor.col(i - 1) = -shifted_combination(fy, dc, o.integrators + i);
    s.instrument.col(i - 1) = -shifted_combination(fx, dc, o.integrators + i);
  }
  for (int j = 0; j <= o.m; ++j) {
    const Eigen::VectorXd r = shifted_combination(fr, nc, j);
    s.regressor.col(o.n + j) = r - shifted_combination(fy, nc, j);
    s.instrument.col(o.n + j) = r - shifted_combination(fx, nc, j);
  }
  if (!s.instrument.allFinite() || !s.output.allFinite()) return std::nullopt;
  return s;
}

// numerator / A_cl at theta as one filter sampled for `hold`, or none as
// stable_loop_denominator.
std::optional<SampledFilter> over_loop_denominator(const SampledData& data, const SubmodelOrder& o,
                                                   const Eigen::VectorXd& theta,
                                                   const TransferFunction& controller,
                                                   const Polynomial& numerator, Hold hold) {
  const std::optional<Polynomial> acl = stable_loop_denominator(o, theta, controller);
  if (!acl) return std::nullopt;
  const std::optional<FilterRealization> bank = finite_derivative_filters(*acl);
  if (!bank) return std::nullopt;
  Eigen::VectorXd w = Eigen::VectorXd::Zero(bank->outputs());
  w.head(numerator.degree() + 1) = numerator.coefficients();
  return SampledFilter(combine_outputs(*bank, w), data.sample_time(), hold);
}

// The model's output x = B N_c / A_cl r alone (a start's score), or none as
// analog_loop_signals.
std::optional<Eigen::VectorXd> analog_loop_output(const SampledData& data, const SubmodelOrder& o,
                                                  const Eigen::VectorXd& theta,
                                                  const TransferFunction& controller) {
  const std::optional<SampledFilter> loop =
      over_loop_denominator(data, o, theta, controller,
                            analog_plant_b(o, theta) * controller.numerator(), data.input_hold());
  if (!loop) return std::nullopt;
  Eigen::VectorXd x = loop->apply(data.reference());
  if (!x.allFinite()) return std::nullopt;
  return x;
}

// The covariance of the estimate when the residual is the loop's sensitivity acting on a
// white disturbance held between samples, y - x = S_d v with S = p^l A D_c / A_cl at the
// estimate (decision 0067): sigma_v^2 R^-1 Q R^-1 with R = sum psi psi', Q = sum psi~ psi~'
// and psi~ psi filtered by the adjoint of S_d (time reversed, filtered, reversed), sigma_v^2
// from the residual's variance over the energy of S_d's pulse response. An AR model of the
// residual cannot hold this colour when the loop is lightly damped and finely sampled.
std::optional<Eigen::MatrixXd> loop_covariance(const SampledData& data, const SubmodelOrder& o,
                                               const Eigen::VectorXd& theta,
                                               const TransferFunction& controller,
                                               const Eigen::MatrixXd& psi,
                                               const Eigen::VectorXd& residual) {
  const std::optional<SampledFilter> sensitivity = over_loop_denominator(
      data, o, theta, controller,
      Polynomial::monomial(o.integrators) * analog_plant_a(o, theta) * controller.denominator(),
      Hold::zero_order_hold);
  if (!sensitivity) return std::nullopt;
  const Eigen::Index n = psi.rows();
  const auto p = static_cast<int>(psi.cols());
  Eigen::VectorXd pulse = Eigen::VectorXd::Zero(n);
  pulse(0) = 1.0;
  const double energy = sensitivity->apply(pulse).squaredNorm();
  const double sigma2 = residual.squaredNorm() / static_cast<double>(n - p) / energy;
  Eigen::MatrixXd adjoint(n, p);
  for (int c = 0; c < p; ++c) {
    const Eigen::VectorXd reversed = psi.col(c).reverse();
    adjoint.col(c) = sensitivity->apply(reversed).col(0).reverse();
  }
  const Eigen::VectorXd scale = internal::column_scales(psi);
  const Eigen::MatrixXd scaled = psi * scale.cwiseInverse().asDiagonal();
  const Eigen::MatrixXd scaled_adjoint = adjoint * scale.cwiseInverse().asDiagonal();
  const Eigen::MatrixXd r_inv =
      (scaled.transpose() * scaled).completeOrthogonalDecomposition().pseudoInverse();
  const Eigen::MatrixXd middle =
      sigma2 * r_inv * (scaled_adjoint.transpose() * scaled_adjoint) * r_inv;
  Eigen::MatrixXd covariance =
      scale.cwiseInverse().asDiagonal() * middle * scale.cwiseInverse().asDiagonal();
  if (!covariance.allFinite() || !(energy > 0.0)) return std::nullopt;
  return covariance;
}

// The indirect start: the closed-loop map r -> y fitted by open-loop SRIVC as N/D (order
// deg A_cl, numerator deg B N_c), then the plant whose loop has those polynomials, A_cl = a D and
// B N_c = a N for a scale a, by least squares over [a_1..a_n, b_0..b_m, a] (each coefficient
// equation weighted by w^k, w the geometric mean of D's root magnitudes, so that no power of p
// dominates). Its loop denominator is near D, which SRIVC keeps stable. None when the first fit
// cannot be made (too short, too poorly excited) or gives nothing finite.
std::optional<AdditiveModel> indirect_start(const SampledData& data, const SubmodelOrder& o,
                                            const TransferFunction& controller) {
  const Polynomial& dc = controller.denominator();
  const Polynomial& nc = controller.numerator();
  const int d = o.n + o.integrators + dc.degree();
  const int mt = o.m + nc.degree();
  TransferFunction loop(Polynomial{1.0}, Polynomial{1.0});
  try {
    RefinedIvOptions quick;
    quick.compute_covariance = false;
    const EstimationResult fitted =
        srivc(SampledData(data.sample_time(), data.reference(), data.output())
                  .with_input_hold(data.input_hold()),
              SubmodelOrder{d, std::min(mt, d), 0}, quick);
    loop = fitted.transfer_function;
  } catch (const InvalidArgument&) {
    return std::nullopt;
  }
  const Polynomial& den = loop.denominator();
  const Polynomial& num = loop.numerator();
  if (den.degree() != d || !den.coefficients().allFinite() || !num.coefficients().allFinite()) {
    return std::nullopt;
  }
  const double w = std::pow(std::abs(den[0] / den[d]), 1.0 / d);
  const int p = o.n + o.m + 1;
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(d + 1 + mt + 1, p + 1);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(x.rows());
  const Polynomial lead = Polynomial::monomial(o.integrators) * dc;
  for (int k = 0; k <= d; ++k) {
    const double row = std::pow(w, k);
    for (int i = 1; i <= o.n; ++i) x(k, i - 1) = row * (Polynomial::monomial(i) * lead)[k];
    for (int j = 0; j <= o.m; ++j) x(k, o.n + j) = row * (Polynomial::monomial(j) * nc)[k];
    x(k, p) = -row * den[k];
    y(k) = -row * lead[k];
  }
  for (int k = 0; k <= mt; ++k) {
    const double row = std::pow(w, k);
    for (int j = 0; j <= o.m; ++j) x(d + 1 + k, o.n + j) = row * (Polynomial::monomial(j) * nc)[k];
    x(d + 1 + k, p) = -row * num[k];
  }
  if (!x.allFinite() || !y.allFinite()) return std::nullopt;
  const Eigen::VectorXd solution = internal::scaled_least_squares(x, y).coefficients;
  const Eigen::VectorXd theta = solution.head(p);
  if (!theta.allFinite()) return std::nullopt;
  return AdditiveModel::from_parameters({o}, theta, 0.0);
}

// The iteration from theta: the accepted iterate and its signals (none if the controller
// does not stabilise even the start); result's termination, message, iterations,
// relative_change, reciprocal_condition, step_halvings and history are set.
std::optional<AnalogLoopSignals> iterate_analog_loop(
    const SampledData& data, const TransferFunction& controller, const SubmodelOrder& o,
    const RefinedIvOptions& options, Eigen::VectorXd& theta, EstimationResult& result) {
  const std::string name = "clsrivc_continuous";
  const Hold y_hold = options.output_interpolation;
  std::optional<AnalogLoopSignals> signals =
      analog_loop_signals(data, o, theta, controller, y_hold);
  if (!signals) {
    result.termination = Termination::closed_loop_unstable;
    result.message = name +
                     ": the controller does not stabilise the initial model, so the closed-loop "
                     "filters cannot be formed; give a model the controller stabilises";
    return signals;
  }
  result.start_closed_loop_fit_percent = fit_percent(data.output(), signals->output);
  result.termination = Termination::iteration_limit;
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    double rcond = std::numeric_limits<double>::quiet_NaN();
    const std::optional<Eigen::VectorXd> step = internal::solve_scaled_instrument_equations(
        signals->instrument, signals->regressor, signals->left, rcond);
    result.reciprocal_condition = rcond;
    if (!step) {
      result.termination =
          std::isfinite(rcond) ? Termination::singular_equations : Termination::non_finite;
      result.message = name +
                       ": the instrument-regressor matrix is numerically singular or "
                       "non-finite at iteration " +
                       std::to_string(iteration);
      return signals;
    }
    // A step to a model the controller does not stabilise is halved toward the iterate.
    Eigen::VectorXd next = *step;
    std::optional<AnalogLoopSignals> next_signals =
        analog_loop_signals(data, o, next, controller, y_hold);
    for (int h = 0; !next_signals && h < options.max_step_halvings; ++h) {
      next = 0.5 * (theta + next);
      ++result.step_halvings;
      next_signals = analog_loop_signals(data, o, next, controller, y_hold);
    }
    if (!next_signals) {
      result.termination = Termination::closed_loop_unstable;
      result.message = name + ": at iteration " + std::to_string(iteration) +
                       " no step toward the next iterate kept the loop stable; the last "
                       "iterate the controller stabilises is returned";
      return signals;
    }
    const double change = (next - theta).norm() / std::max(next.norm(), 1e-300);
    result.relative_change = change;
    result.iterations = iteration;
    theta = next;
    signals = std::move(next_signals);
    if (options.record_history) result.history.push_back({iteration, theta, change, 0.0});
    if (change < options.tolerance) {
      result.termination = Termination::converged;
      result.message = name + ": converged after " + std::to_string(iteration) +
                       " iterations (relative parameter change " + format_significant(change, 3) +
                       " < tolerance " + format_significant(options.tolerance, 3) + ")";
      return signals;
    }
  }
  result.message = name + ": stopped at the iteration limit (" +
                   std::to_string(options.max_iterations) + ") with relative parameter change " +
                   format_significant(result.relative_change, 3);
  return signals;
}

// Assumption 1 on the reference (the order the engine asks of a closed loop) and 4 on the
// estimate.
DataChecks analog_loop_checks(const SampledData& data, const SubmodelOrder& o,
                              const TransferFunction& controller, const AdditiveModel& model) {
  DataChecks checks;
  const int p = o.n + o.m + 1;
  checks.excitation_order_required = 2 * (o.n + o.integrators) + controller.denominator().degree();
  checks.excitation_order =
      persistent_excitation_order(data.reference(), std::max(checks.excitation_order_required, p));
  internal::note_excitation(checks, "reference");
  internal::note_sampling_rate(checks, model, data.sample_time(), "the Nyquist frequency");
  return checks;
}

EstimationResult clsrivc_continuous_from(const SampledData& data,
                                         const TransferFunction& controller, const SubmodelOrder& o,
                                         const RefinedIvOptions& options,
                                         const AdditiveModel& start) {
  Eigen::VectorXd theta = internal::parameters_for_orders(start, {o});
  EstimationResult result{start, start.to_transfer_function()};
  const std::optional<AnalogLoopSignals> signals =
      iterate_analog_loop(data, controller, o, options, theta, result);
  const int p = o.n + o.m + 1;
  result.parameters = theta;
  result.model = AdditiveModel::from_parameters({o}, theta, 0.0);
  result.transfer_function = result.model.to_transfer_function();
  result.additive_view = AdditiveModel::split_transfer_function(result.transfer_function);
  if (signals) {
    const Eigen::VectorXd residual = data.output() - signals->output;
    result.closed_loop_fit_percent = fit_percent(data.output(), signals->output);
    result.mean_squared_error = residual.squaredNorm() / static_cast<double>(data.size());
    result.noise_variance = residual.squaredNorm() / std::max<double>(data.size() - p, 1.0);
    const std::optional<Eigen::MatrixXd> covariance =
        options.compute_covariance
            ? loop_covariance(data, o, theta, controller, signals->instrument, residual)
            : std::nullopt;
    if (covariance) {
      result.covariance = *covariance;
      result.standard_errors = result.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
      result.modes = modal_estimates(result.model, result.covariance, true);
    }
  }
  result.fit_percent = result.closed_loop_fit_percent;
  result.start_fit_percent = result.start_closed_loop_fit_percent;
  result.checks = analog_loop_checks(data, o, controller, result.model);
  result.verdict = internal::unstable_loop_verdict(result, signals.has_value());
  return result;
}

}  // namespace

std::optional<std::string> clsrivc_continuous_refusal(const SampledData& data,
                                                      const TransferFunction& controller,
                                                      const SubmodelOrder& order,
                                                      const RefinedIvOptions& options) {
  options.validate();
  using internal::concat;
  const std::string name = "clsrivc_continuous";
  if (!data.has_reference()) {
    return concat(name, ": closed-loop estimation needs a measured reference r");
  }
  if (!controller.numerator().coefficients().allFinite() ||
      !controller.denominator().coefficients().allFinite() || controller.numerator().is_zero()) {
    return concat(name, ": the controller ", controller.to_string(),
                  " has a coefficient that is not finite, or is zero");
  }
  if (!controller.is_proper()) {
    return concat(name, ": the controller ", controller.to_string(),
                  " is improper (more zeros than poles); give its derivative a filter");
  }
  if (controller.input_delay() != 0.0) {
    return concat(name, ": the controller has a delay (", controller.input_delay(),
                  " s); a delay in an analog loop is not supported");
  }
  if (order.n < 0 || order.m < 0 || order.integrators < 0 || order.n + order.integrators < 1 ||
      order.m > order.n + order.integrators) {
    return concat(
        name, ": the order needs n + integrators >= 1 and 0 <= m <= n + integrators (n = ", order.n,
        ", m = ", order.m, ", integrators = ", order.integrators, ")");
  }
  if (options.noise_model) {
    return concat(name,
                  ": noise_model is set; the fit with a continuous-time controller has no "
                  "noise model");
  }
  if (options.input_delay_samples != 0 || options.input_delay_fraction != 0.0 ||
      !options.record_delay_samples.empty() || options.delay_estimated) {
    return concat(name, ": an input delay is not supported with a continuous-time controller");
  }
  if (options.initial_conditions != InitialConditions::zero) {
    return concat(name,
                  ": initial_conditions = estimate is not supported with a "
                  "continuous-time controller");
  }
  const int p = order.n + order.m + 1;
  if (data.size() < 3 * p + 20) {
    return concat(name, ": ", data.size(), " samples are too few for ", p, " parameters; at least ",
                  3 * p + 20, " are needed");
  }
  if (const int excited = persistent_excitation_order(data.reference(), p); excited < p) {
    return concat(name, ": the reference is persistently exciting of order ", excited,
                  " only; the ", p, " parameters need at least order ", p,
                  " (e.g. a constant or a single sine cannot)");
  }
  return std::nullopt;
}

EstimationResult clsrivc_continuous(const SampledData& data, const TransferFunction& controller,
                                    const SubmodelOrder& order, const RefinedIvOptions& options) {
  if (std::optional<std::string> refusal =
          clsrivc_continuous_refusal(data, controller, order, options)) {
    throw InvalidArgument(*refusal);
  }
  if (options.initial_model) {
    return clsrivc_continuous_from(data, controller, order, options, *options.initial_model);
  }
  // The open-loop start (u treated as held: a start, not an estimate), the start on the
  // input's part r explains and the indirect start, with their roots moved until the
  // controller stabilises them.
  std::vector<AdditiveModel> bases{
      internal::loop_start_submodel(initial_transfer_function(data, order, {}))};
  const int loop_order = order.n + order.integrators + controller.denominator().degree();
  if (std::optional<AdditiveModel> explained =
          internal::explained_input_start(data, order, loop_order)) {
    bases.push_back(std::move(*explained));
  }
  if (std::optional<AdditiveModel> indirect = indirect_start(data, order, controller)) {
    bases.push_back(std::move(*indirect));
  }

  const internal::LoopFit fit = [&](const Eigen::VectorXd& theta) -> std::optional<double> {
    const std::optional<Eigen::VectorXd> x = analog_loop_output(data, order, theta, controller);
    if (!x) return std::nullopt;
    return fit_percent(data.output(), *x);
  };
  std::vector<AdditiveModel> starts =
      internal::stabilised_starts(bases, order, fit, kAnalogLoopStarts);
  if (starts.empty()) starts.push_back(bases.front());  // none stabilised: fails, named
  return internal::best_loop_fit(starts, [&](const AdditiveModel& start) {
    return clsrivc_continuous_from(data, controller, order, options, start);
  });
}

}  // namespace ctid
