// SRIVC on irregular time stamps (irregular_srivc.h, docs/decisions/0034): the filters of
// eq. (30) with the instrument (10), discretised exactly on each interval as it is. The
// uniform-grid engine (refined_iv.cc) and its sampled filters are not touched; this file
// builds the same realisations (filter_bank.h) and runs them interval by interval.
#include "ctid/refined_iv/irregular_srivc.h"

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
#include "ctid/core/preprocessing.h"
#include "ctid/core/sampled_data.h"
#include "ctid/estimation/validation.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/refined_iv.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/stamps.h"
#include "estimation/internal/scaled_least_squares.h"
#include "refined_iv/internal/refined_iv_engine.h"
#include "refined_iv/internal/refined_iv_passes.h"

namespace ctid {

void IrregularRecord::validate() const {
  const Eigen::Index n = time.size();
  require(input.size() == n && output.size() == n, "irregular record: ", n, " time stamps, ",
          input.size(), " input and ", output.size(), " output samples; the sizes must agree");
  require(n >= 2, "irregular record: ", n, " samples; at least 2 are needed");
  check_stamp_order(time, "irregular record");
  for (Eigen::Index k = 0; k < n; ++k) {
    require(std::isfinite(input(k)), "irregular record: input sample ", k, " is ", input(k));
    require(std::isfinite(output(k)), "irregular record: output sample ", k, " is ", output(k));
  }
  require(time(n - 1) > time(0), "irregular record: every time stamp is ", time(0),
          "; the record spans no time");
}

double IrregularRecord::median_step() const {
  std::vector<double> steps;
  for (Eigen::Index k = 1; k < time.size(); ++k) {
    if (time(k) > time(k - 1)) steps.push_back(time(k) - time(k - 1));
  }
  require(!steps.empty(), "irregular record: no positive step between time stamps");
  const auto mid = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
  std::nth_element(steps.begin(), mid, steps.end());
  return *mid;
}

namespace irregular_srivc_detail {

// Runs `filter` over x at the stamps t from rest at the first stamp: row k is C z(t_k) +
// d x_k (simulation/stamps.h).
Eigen::MatrixXd run_on_stamps(const FilterRealization& filter, const Eigen::VectorXd& t,
                              const Eigen::VectorXd& x, Hold hold) {
  return ctid::run_on_stamps(filter.a, filter.b, filter.c, filter.d, t, x, hold);
}

// The filtered signals of (30) at theta = [a_1..a_n, b_0..b_m]: the instrument psi (10), the
// regressor phi, the filtered output 1/A y and the model output B/(p^l A) u, all at the stamps.
struct FilteredSignals {
  Eigen::MatrixXd instrument;
  Eigen::MatrixXd regressor;
  Eigen::VectorXd filtered_output;
  Eigen::VectorXd model_output;
};

Polynomial denominator(const SubmodelOrder& o, const Eigen::VectorXd& theta) {
  Eigen::VectorXd a(o.n + 1);
  a(0) = 1.0;
  a.tail(o.n) = theta.head(o.n);
  return Polynomial::trimmed(a);
}

// The instrument source: the bank of 1/(p^l A) cascaded (through B/||B||) into p^k/A, read as
// p^j/(p^l A) u (j = 0..m), p^k B/(p^l A^2) u (k = 1..n) and the model output, as the
// uniform-grid engine forms them (refined_iv.cc, submodel_filters).
FilterRealization source_filter(const SubmodelOrder& o, const Polynomial& a,
                                const Eigen::VectorXd& b) {
  const FilterRealization bank = derivative_filters(Polynomial::monomial(o.integrators) * a);
  const int s1 = bank.order();
  Eigen::VectorXd w = Eigen::VectorXd::Zero(bank.outputs());
  w.head(o.m + 1) = b;
  const double gain = w.norm() > 0.0 ? w.norm() : 1.0;
  FilterRealization chain = bank;
  if (o.n > 0) chain = cascade(bank, w / gain, derivative_filters(a));
  const int rows = o.m + 1 + o.n + 1;
  FilterRealization f;
  f.a = chain.a;
  f.b = chain.b;
  f.c = Eigen::MatrixXd::Zero(rows, chain.order());
  f.d = Eigen::VectorXd::Zero(rows);
  f.c.topLeftCorner(o.m + 1, s1) = bank.c.topRows(o.m + 1);
  f.d.head(o.m + 1) = bank.d.head(o.m + 1);
  if (o.n > 0) {
    f.c.middleRows(o.m + 1, o.n) = gain * chain.c.middleRows(1, o.n);
    f.d.segment(o.m + 1, o.n) = gain * chain.d.segment(1, o.n);
  }
  f.c.block(rows - 1, 0, 1, s1) = w.transpose() * bank.c;
  f.d(rows - 1) = w.dot(bank.d);
  return f;
}

FilteredSignals filter_signals(const IrregularRecord& r, const SubmodelOrder& o,
                               const Eigen::VectorXd& theta, Hold output_interpolation) {
  const Polynomial a = denominator(o, theta);
  const Eigen::VectorXd b = theta.tail(o.m + 1);
  const Eigen::Index n = r.time.size();
  const int p = o.n + o.m + 1;
  const Eigen::MatrixXd source =
      run_on_stamps(source_filter(o, a, b), r.time, r.input, r.input_hold);
  FilteredSignals f;
  f.instrument.resize(n, p);
  f.regressor.resize(n, p);
  f.instrument.rightCols(o.m + 1) = source.leftCols(o.m + 1);
  f.regressor.rightCols(o.m + 1) = source.leftCols(o.m + 1);
  f.model_output = source.col(o.m + o.n + 1);
  if (o.n > 0) {
    f.instrument.leftCols(o.n) = -source.middleCols(o.m + 1, o.n);
    const Eigen::MatrixXd y =
        run_on_stamps(derivative_filters(a), r.time, r.output, output_interpolation);
    f.regressor.leftCols(o.n) = -y.middleCols(1, o.n);
    f.filtered_output = y.col(0);
  } else {
    f.filtered_output = r.output;
  }
  return f;
}

// The block relative change of the uniform-grid engine: max of ||d a|| / ||a||, ||d b|| / ||b||.
double relative_change(const SubmodelOrder& o, const Eigen::VectorXd& from,
                       const Eigen::VectorXd& to) {
  const double whole = std::max(from.norm(), 1e-300);
  double largest = 0.0;
  for (const auto& [first, count] : {std::pair{0, o.n}, std::pair{o.n, o.m + 1}}) {
    if (count == 0) continue;
    const double size = from.segment(first, count).norm();
    const double step = (to.segment(first, count) - from.segment(first, count)).norm();
    largest = std::max(largest, step / (size > 1e-12 * whole ? size : whole));
  }
  return largest;
}

void reflect(const SubmodelOrder& o, Eigen::VectorXd& theta, int& reflections) {
  if (o.n < 1) return;
  bool reflected = false;
  const Polynomial a = internal::reflect_unstable_roots(denominator(o, theta), reflected);
  if (!reflected || a.degree() != o.n) return;
  ++reflections;
  for (int k = 1; k <= o.n; ++k) theta(k - 1) = a[k];
}

// The record with equal stamps reduced to their last sample, on the grid of its median step:
// the record the start is found on.
SampledData start_record(const IrregularRecord& r) {
  std::vector<Eigen::Index> keep;
  for (Eigen::Index k = 0; k < r.time.size(); ++k) {
    if (!keep.empty() && r.time(k) == r.time(keep.back())) {
      keep.back() = k;
    } else {
      keep.push_back(k);
    }
  }
  const auto m = static_cast<Eigen::Index>(keep.size());
  Eigen::VectorXd t(m), u(m), y(m);
  for (Eigen::Index j = 0; j < m; ++j) {
    t(j) = r.time(keep[static_cast<size_t>(j)]);
    u(j) = r.input(keep[static_cast<size_t>(j)]);
    y(j) = r.output(keep[static_cast<size_t>(j)]);
  }
  return resample(t, u, y, std::nullopt, r.median_step(), r.input_hold);
}

Eigen::VectorXd start_parameters(const IrregularRecord& r, const SubmodelOrder& o,
                                 const RefinedIvOptions& options) {
  if (options.initial_model) {
    return internal::unfactored_parameters(
        options.initial_model->to_transfer_function().with_input_delay(0.0), o);
  }
  RefinedIvOptions start = options;
  start.compute_covariance = false;
  start.record_history = false;
  const EstimationResult fitted = srivc(start_record(r), o, start);
  return fitted.parameters;
}

void check_inputs(const IrregularRecord& r, const SubmodelOrder& o,
                  const RefinedIvOptions& options) {
  options.validate();
  r.validate();
  require(o.n >= 0 && o.m >= 0 && o.integrators >= 0, "srivc_irregular: negative order (n = ", o.n,
          ", m = ", o.m, ", integrators = ", o.integrators, ")");
  require(o.n + o.integrators >= 1, "srivc_irregular: the model has no poles");
  require(o.m <= o.n + o.integrators, "srivc_irregular: m = ", o.m,
          " > n + integrators = ", o.n + o.integrators, " (improper)");
  require(options.input_delay_samples == 0 && options.input_delay_fraction == 0.0 &&
              options.record_delay_samples.empty() && !options.delay_estimated,
          "srivc_irregular: an input delay is not supported on irregular stamps yet");
  require(options.initial_conditions == InitialConditions::zero,
          "srivc_irregular: initial_conditions = estimate is not supported on irregular "
          "stamps yet");
  require(!options.noise_model,
          "srivc_irregular: noise_model is set; a discrete ARMA noise model needs a uniform "
          "sample time, so irregular stamps are fitted without one");
  const int p = o.n + o.m + 1;
  const auto n = static_cast<int>(r.time.size());
  const int needed = std::max(3 * p, p + 20);
  require(n >= needed, "srivc_irregular: ", n, " samples are too few for ", p,
          " parameters; at least ", needed, " are needed");
}

// One solve of (30) from the filtered signals: theta_{j+1}, with the reciprocal condition of
// the column-scaled instrument-regressor matrix; nothing if it is singular or non-finite.
std::optional<Eigen::VectorXd> solve_step(const FilteredSignals& f, double& rcond) {
  return internal::solve_scaled_instrument_equations(f.instrument, f.regressor, f.filtered_output,
                                                     rcond);
}

struct IterationEnd {
  Eigen::VectorXd theta;
  double start_sse = std::numeric_limits<double>::quiet_NaN();
};

// The iteration (30) on the stamps from theta; result's termination, message, iterations,
// relative_change, reciprocal_condition, reflections and history are set.
IterationEnd iterate(const IrregularRecord& r, const SubmodelOrder& o, Eigen::VectorXd theta,
                     const RefinedIvOptions& options, EstimationResult& result) {
  const std::string name = "srivc_irregular";
  IterationEnd end;
  double best_sse = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best = theta;
  result.termination = Termination::iteration_limit;
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    const FilteredSignals f = filter_signals(r, o, theta, options.output_interpolation);
    const double sse = (r.output - f.model_output).squaredNorm();
    if (std::isnan(end.start_sse)) end.start_sse = sse;
    if (std::isfinite(sse) && sse < best_sse) {
      best_sse = sse;
      best = theta;
    }
    double rcond = std::numeric_limits<double>::quiet_NaN();
    std::optional<Eigen::VectorXd> next = solve_step(f, rcond);
    result.reciprocal_condition = rcond;
    if (!next) {
      const bool singular = std::isfinite(rcond);
      result.termination = singular ? Termination::singular_equations : Termination::non_finite;
      result.message = name +
                       (singular ? ": the instrument-regressor matrix is numerically "
                                   "singular (reciprocal condition " +
                                       format_significant(rcond, 3) + ")"
                                 : ": the filtered signals became non-finite") +
                       " at iteration " + std::to_string(iteration) +
                       "; the iterate with the lowest output error is returned";
      end.theta = best;
      return end;
    }
    reflect(o, *next, result.unstable_reflections);
    const double change = relative_change(o, theta, *next);
    result.relative_change = change;
    result.iterations = iteration;
    theta = *next;
    if (options.record_history) result.history.push_back({iteration, theta, change, 0.0});
    if (change < options.tolerance) {
      result.termination = Termination::converged;
      result.message = name + ": converged after " + std::to_string(iteration) +
                       " iterations on the time stamps (relative parameter change " +
                       format_significant(change, 3) + ")";
      end.theta = theta;
      return end;
    }
  }
  result.message = name + ": stopped at the iteration limit (" +
                   std::to_string(options.max_iterations) + ") with relative parameter change " +
                   format_significant(result.relative_change, 3);
  end.theta = theta;
  return end;
}

}  // namespace irregular_srivc_detail

EstimationResult srivc_irregular(const IrregularRecord& record, const SubmodelOrder& order,
                                 const RefinedIvOptions& options) {
  namespace d = irregular_srivc_detail;
  d::check_inputs(record, order, options);
  const int p = order.n + order.m + 1;
  DataChecks checks;
  checks.excitation_order_required = 2 * (order.n + order.integrators);
  checks.excitation_order =
      persistent_excitation_order(record.input, std::max(checks.excitation_order_required, p));
  require(checks.excitation_order >= p,
          "srivc_irregular: the input is persistently exciting of order ", checks.excitation_order,
          " only; the ", p, " parameters need at least order ", p);
  internal::note_excitation(checks, "input");
  Eigen::VectorXd theta = d::start_parameters(record, order, options);
  require(theta.size() == p && theta.allFinite(),
          "srivc_irregular: no finite start was found on the resampled record");
  const std::vector<SubmodelOrder> orders{order};
  EstimationResult result{AdditiveModel::from_parameters(orders, theta, 0.0),
                          TransferFunction(Polynomial{1.0}, Polynomial{1.0})};
  d::reflect(order, theta, result.unstable_reflections);
  const d::IterationEnd end = d::iterate(record, order, theta, options, result);
  theta = end.theta;
  result.parameters = theta;
  result.model = AdditiveModel::from_parameters(orders, theta, 0.0);
  result.transfer_function = result.model.to_transfer_function();
  result.additive_view = AdditiveModel::split_transfer_function(result.transfer_function);
  const d::FilteredSignals f =
      d::filter_signals(record, order, theta, options.output_interpolation);
  const Eigen::VectorXd residual = record.output - f.model_output;
  const auto n = static_cast<int>(record.time.size());
  result.mean_squared_error = residual.squaredNorm() / n;
  result.noise_variance = residual.squaredNorm() / std::max(n - p, 1);
  result.fit_percent = fit_percent(record.output, f.model_output);
  const double spread = (record.output.array() - record.output.mean()).matrix().norm();
  result.start_fit_percent = spread > 0.0 ? 100.0 * (1.0 - std::sqrt(end.start_sse) / spread)
                                          : std::numeric_limits<double>::quiet_NaN();
  if (options.compute_covariance && f.instrument.allFinite() && residual.allFinite()) {
    result.covariance = instrumental_variable_covariance(f.instrument, residual, p, options.noise,
                                                         options.noise_model_max_order);
    result.standard_errors = result.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    result.modes = modal_estimates(result.model, result.covariance, true);
  }
  internal::note_sampling_rate(checks, result.model, record.median_step(), "pi / (median step)");
  result.checks = std::move(checks);
  result.verdict = refined_iv_verdict(result, false, false);
  result.verdict.active_constraints =
      internal::srivc_engine::active_constraint_notes(result.unstable_reflections, {}, {});
  return result;
}

}  // namespace ctid
