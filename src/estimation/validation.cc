// Model output, fit and the data checks of Assumptions 1 and 4.
#include "ctid/estimation/validation.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/transfer_function.h"
#include "ctid/estimation/residual_correlation.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/simulate.h"

namespace ctid {

Eigen::VectorXd model_output(const AdditiveModel& model, const Eigen::VectorXd& input,
                             double sample_time, Hold input_hold) {
  require(std::isfinite(sample_time) && sample_time > 0.0,
          "model_output: sample_time must be positive, got ", sample_time);
  require(input.allFinite(), "model_output: the input has a non-finite value");
  const DelaySplit delay = split_delay(model.input_delay(), sample_time);
  const Eigen::VectorXd u = delay_samples(input, delay.samples);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(input.size());
  for (int i = 0; i < model.size(); ++i) {
    const Submodel& s = model[i];
    const Polynomial den = Polynomial::monomial(s.integrators) * s.a;
    if (den.degree() == 0) {
      // A static gain sees the delayed input at the samples.
      const DelayedSample now = delayed_sample(delay.fraction, input_hold);
      y += (s.b[0] / den[0]) * (now.previous * delay_samples(u, 1) + now.current * u);
      continue;
    }
    const Eigen::MatrixXd f =
        SampledFilter(derivative_filters(den), sample_time, input_hold, delay.fraction).apply(u);
    for (int k = 0; k <= s.m(); ++k) y += s.b[k] * f.col(k);
  }
  return y;
}

Eigen::MatrixXd free_responses(const AdditiveModel& model, int samples, double sample_time) {
  require(std::isfinite(sample_time) && sample_time > 0.0,
          "free_responses: sample_time must be positive, got ", sample_time);
  require(samples >= 0, "free_responses: samples is ", samples, "; it must be >= 0");
  int states = 0;
  for (int i = 0; i < model.size(); ++i) {
    states += model[i].integrators + model[i].a.degree();
  }
  Eigen::MatrixXd f = Eigen::MatrixXd::Zero(samples, states);
  int column = 0;
  for (int i = 0; i < model.size(); ++i) {
    const Submodel& s = model[i];
    const Polynomial den = Polynomial::monomial(s.integrators) * s.a;
    const int n = den.degree();
    if (n == 0) continue;
    const StateSpace continuous = TransferFunction(s.b, den).to_state_space();
    const StateSpace discrete = discretize_zoh(continuous, sample_time);
    Eigen::RowVectorXd row = discrete.c;
    for (int k = 0; k < samples; ++k) {
      f.block(k, column, 1, n) = row;
      row = row * discrete.a;
    }
    column += n;
  }
  return f;
}

double fit_percent(const Eigen::VectorXd& measured, const Eigen::VectorXd& modelled) {
  require(measured.size() == modelled.size(), "fit_percent: ", measured.size(),
          " measured samples against ", modelled.size(), " modelled");
  require(measured.size() >= 2, "fit_percent: needs at least 2 samples");
  const double spread = (measured.array() - measured.mean()).matrix().norm();
  const double error = (measured - modelled).norm();
  if (!(spread > 0.0)) return error == 0.0 ? 100.0 : -std::numeric_limits<double>::infinity();
  return 100.0 * (1.0 - error / spread);
}

void ValidationOptions::check_relations(const std::string& path) const {
  if (window_start && window_end) {
    require(*window_end > *window_start, path, ".window_end is ", *window_end,
            "; it must be > window_start (", *window_start, ")");
  }
}

namespace {

struct Window {
  int first = 0;
  int count = 0;
};

// The samples k with window_start <= start_time + k h <= window_end (a tolerance of 1e-6 h
// absorbs times typed with fewer digits than the record's).
Window scored_window(const SampledData& data, const ValidationOptions& options) {
  const int n = data.size();
  const double h = data.sample_time();
  const double t0 = data.start_time();
  const double t_last = t0 + (n - 1) * h;
  const double start = options.window_start.value_or(t0);
  const double end = options.window_end.value_or(t_last);
  const double tolerance = 1e-6 * h;
  const auto describe = [&] {
    return internal::concat("the window [", format_number(start), ", ", format_number(end), "] s");
  };
  const auto record = [&] {
    return internal::concat("the record (", n, " samples of ", format_number(h),
                            " s, t = ", format_number(t0), " to ", format_number(t_last), " s)");
  };
  require(start >= t0 - tolerance && end <= t_last + tolerance, describe(), " is not inside ",
          record());
  Window w;
  w.first = static_cast<int>(std::ceil((start - t0) / h - 1e-6));
  const int last = static_cast<int>(std::floor((end - t0) / h + 1e-6));
  w.first = std::clamp(w.first, 0, n - 1);
  w.count = std::clamp(last, 0, n - 1) - w.first + 1;
  require(w.count >= 2, describe(), " holds ", std::max(w.count, 0), " samples of ", record(),
          "; at least 2 are needed");
  return w;
}

// y_rest + F x0 with x0 the least-squares fit of y - y_rest on the free responses F over the
// window. Returns the free response over the whole record and the rank used.
Eigen::VectorXd estimated_free_response(const AdditiveModel& model, const SampledData& data,
                                        const Eigen::VectorXd& rest, const Window& w, int* states,
                                        int* rank) {
  const Eigen::MatrixXd f = free_responses(model, data.size(), data.sample_time());
  *states = static_cast<int>(f.cols());
  *rank = 0;
  Eigen::VectorXd free = Eigen::VectorXd::Zero(data.size());
  if (f.cols() == 0 || !f.allFinite()) return free;
  const Eigen::MatrixXd fw = f.middleRows(w.first, w.count);
  const Eigen::VectorXd target = (data.output() - rest).segment(w.first, w.count);
  // Columns scaled by their norm over the whole record (states in comparable units), not on
  // the window: a state whose free response has died out before the window keeps a tiny
  // column there and falls below the rank threshold instead of being fitted to rounding.
  Eigen::VectorXd scale = f.colwise().norm().transpose();
  const double largest_scale = scale.maxCoeff();
  if (!(largest_scale > 0.0)) return free;
  for (Eigen::Index j = 0; j < scale.size(); ++j) {
    scale(j) = scale(j) > 1e-300 * largest_scale ? 1.0 / scale(j) : 0.0;
  }
  const Eigen::MatrixXd scaled = fw * scale.asDiagonal();
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd& sigma = svd.singularValues();
  // Columns have unit norm over the record, so a singular value is the fraction of a state
  // direction's free response that the window sees. Below 1e-6 the direction would be
  // extrapolated backwards from the window's noise (a fast mode that has died out before it
  // comes back as a huge transient at the record's start); it is dropped instead.
  const double threshold = 1e-6 * sigma(0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(f.cols());
  for (Eigen::Index j = 0; j < sigma.size(); ++j) {
    if (!(sigma(j) > threshold)) break;
    x += svd.matrixV().col(j) * (svd.matrixU().col(j).dot(target) / sigma(j));
    ++*rank;
  }
  const Eigen::VectorXd x0 = scale.asDiagonal() * x;
  free = f * x0;
  return free;
}

}  // namespace

ValidationReport validate_model(const AdditiveModel& model, const SampledData& data, int max_lag) {
  require(max_lag >= 1, "validate_model: max_lag must be at least 1, got ", max_lag);
  ValidationOptions options;
  options.max_lag = max_lag;
  return validate_model(model, data, options);
}

ValidationReport validate_model(const AdditiveModel& model, const SampledData& data,
                                const ValidationOptions& options) {
  options.validate();
  const Window w = scored_window(data, options);
  const Eigen::VectorXd rest =
      model_output(model, data.input(), data.sample_time(), data.input_hold());
  int states = 0;
  int rank = 0;
  const Eigen::VectorXd free = estimated_free_response(model, data, rest, w, &states, &rank);
  const Eigen::VectorXd estimated = rest + free;
  const SampledData scored = data.segment(w.first, w.count);
  const bool estimate = options.initial_state == InitialState::estimate;
  ValidationReport r = residual_report(
      scored, (estimate ? estimated : rest).segment(w.first, w.count), options.max_lag);
  r.initial_state = options.initial_state;
  r.fit_zero_state = fit_percent(scored.output(), rest.segment(w.first, w.count));
  r.fit_estimated_state = fit_percent(scored.output(), estimated.segment(w.first, w.count));
  r.window_start = data.start_time() + w.first * data.sample_time();
  r.window_end = data.start_time() + (w.first + w.count - 1) * data.sample_time();
  r.window_samples = w.count;
  r.states = states;
  r.initial_state_rank = rank;
  r.free_response_rms = free.segment(w.first, w.count).norm() / std::sqrt(double(w.count));
  return r;
}

MimoValidationReport validate_model(const MimoAdditiveModel& model, const MimoData& data,
                                    const ValidationOptions& options) {
  options.validate();
  require(model.inputs() == data.input_count() && model.outputs() == data.output_count(),
          "validate_model: the model is ", model.outputs(), " x ", model.inputs(),
          " (outputs x inputs) but the record has ", data.output_count(), " outputs and ",
          data.input_count(), " inputs");
  const Window w = scored_window(data.channel(0, 0), options);
  const int outputs = data.output_count();
  MimoValidationReport r;
  r.initial_state = options.initial_state;
  for (Eigen::VectorXd* v : {&r.fit_percent, &r.fit_zero_state, &r.fit_estimated_state,
                             &r.max_residual_autocorrelation, &r.max_cross_correlation}) {
    v->resize(outputs);
  }
  for (int j = 0; j < outputs; ++j) {
    Eigen::VectorXd rest = Eigen::VectorXd::Zero(data.size());
    for (int k = 0; k < data.input_count(); ++k) {
      rest += model_output(model.channel(j, k), data.inputs().col(k), data.sample_time(),
                           data.input_hold());
    }
    const SampledData first = data.channel(0, j);
    int states = 0;
    int rank = 0;
    const Eigen::VectorXd estimated =
        rest + estimated_free_response(model.channel(j, 0), first, rest, w, &states, &rank);
    const Eigen::VectorXd& used =
        options.initial_state == InitialState::estimate ? estimated : rest;
    const Eigen::VectorXd y = data.outputs().col(j).segment(w.first, w.count);
    r.fit_zero_state(j) = fit_percent(y, rest.segment(w.first, w.count));
    r.fit_estimated_state(j) = fit_percent(y, estimated.segment(w.first, w.count));
    r.fit_percent(j) = fit_percent(y, used.segment(w.first, w.count));
    r.max_cross_correlation(j) = 0.0;
    for (int k = 0; k < data.input_count(); ++k) {
      const ValidationReport one = residual_report(data.channel(k, j).segment(w.first, w.count),
                                                   used.segment(w.first, w.count), options.max_lag);
      r.max_residual_autocorrelation(j) = one.max_residual_autocorrelation;
      r.max_cross_correlation(j) = std::max(r.max_cross_correlation(j), one.max_cross_correlation);
      r.whiteness_bound = one.whiteness_bound;
    }
  }
  r.window_start = data.start_time() + w.first * data.sample_time();
  r.window_end = data.start_time() + (w.first + w.count - 1) * data.sample_time();
  r.window_samples = w.count;
  return r;
}

Eigen::VectorXd validation_output(const AdditiveModel& model, const SampledData& data,
                                  const ValidationOptions& options) {
  options.validate();
  const Window w = scored_window(data, options);
  Eigen::VectorXd rest = model_output(model, data.input(), data.sample_time(), data.input_hold());
  if (options.initial_state == InitialState::zero) return rest;
  int states = 0;
  int rank = 0;
  rest += estimated_free_response(model, data, rest, w, &states, &rank);
  return rest;
}

ValidationReport residual_report(const SampledData& data, const Eigen::VectorXd& modelled,
                                 int max_lag) {
  require(max_lag >= 1, "residual_report: max_lag must be at least 1, got ", max_lag);
  require(modelled.size() == data.size(), "residual_report: the modelled output has ",
          modelled.size(), " samples but the record has ", data.size());
  const Eigen::VectorXd e = data.output() - modelled;
  const Eigen::Index n = e.size();
  ValidationReport r;
  r.fit_percent = fit_percent(data.output(), modelled);
  r.mean_squared_error = e.squaredNorm() / static_cast<double>(n);
  r.residual_mean = e.mean();
  const Eigen::VectorXd c = e.array() - r.residual_mean;
  r.residual_std = std::sqrt(c.squaredNorm() / static_cast<double>(n));
  r.whiteness_bound = 2.58 / std::sqrt(static_cast<double>(n));
  r.max_lag = static_cast<int>(std::min<Eigen::Index>(max_lag, n - 1));
  r.residual_autocorrelation = Eigen::VectorXd::Zero(r.max_lag);
  r.cross_correlation = Eigen::VectorXd::Zero(2 * r.max_lag + 1);
  if (r.max_lag > 0) {
    const ResidualCorrelations correlations = residual_correlations(e, data.input(), r.max_lag);
    r.residual_autocorrelation = correlations.autocorrelation.tail(r.max_lag);
    r.cross_correlation = correlations.cross_correlation;
    r.max_residual_autocorrelation = r.residual_autocorrelation.cwiseAbs().maxCoeff();
    r.max_cross_correlation = r.cross_correlation.cwiseAbs().maxCoeff();
  }
  return r;
}

namespace {

// Largest k <= top for which the Gram matrix of the windows [x_j, x_{j-d}, ..., x_{j-(k-1)d}]
// is numerically non-singular.
int lag_window_order(const Eigen::VectorXd& x, int top, int d, double tolerance) {
  const Eigen::Index span = static_cast<Eigen::Index>(top - 1) * d;
  const Eigen::Index len = x.size() - span;
  Eigen::MatrixXd g(top, top);
  for (int i = 0; i < top; ++i) {
    for (int j = i; j < top; ++j) {
      g(i, j) = x.segment(span - i * d, len).dot(x.segment(span - j * d, len));
      g(j, i) = g(i, j);
    }
  }
  int order = 0;
  for (int k = 1; k <= top; ++k) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(g.topLeftCorner(k, k),
                                                             Eigen::EigenvaluesOnly);
    const Eigen::VectorXd& ev = eig.eigenvalues();
    if (!(ev(0) > tolerance * ev(k - 1))) break;
    order = k;
  }
  return order;
}

}  // namespace

int persistent_excitation_order(const Eigen::VectorXd& x, int max_order, double tolerance) {
  require(max_order >= 1, "persistent_excitation_order: max_order is ", max_order,
          "; it must be >= 1");
  const Eigen::Index n = x.size();
  const int top = static_cast<int>(std::min<Eigen::Index>(max_order, n / 2));
  if (top < 1 || x.squaredNorm() == 0.0) return 0;
  // A signal obeying a linear recursion of order r (a constant: r = 1, one sinusoid: 2,
  // r/2 sinusoids: r) has lag windows of rank <= r at every lag spacing d. A rich but
  // band-limited signal (a multisine up to 500 Hz sampled at 4096 Hz) has unit-spacing
  // windows that are numerically singular, because its spectrum fills only part of the
  // band; windows spaced to match its band resolve it. So the order seen in the record is
  // the largest over a few spacings; white-like signals stop after the first.
  int order = 0;
  for (const int d : {1, 2, 3, 4, 6, 8, 12, 16}) {
    if (static_cast<Eigen::Index>(top - 1) * d >= n / 2) break;
    order = std::max(order, lag_window_order(x, top, d, tolerance));
    if (order >= top) break;
  }
  return order;
}

double largest_pole_frequency(const AdditiveModel& model) {
  double largest = 0.0;
  for (int i = 0; i < model.size(); ++i) {
    const Polynomial& a = model[i].a;
    if (a.degree() < 1) continue;
    const Eigen::VectorXcd roots = a.roots();
    for (Eigen::Index k = 0; k < roots.size(); ++k) {
      largest = std::max(largest, std::abs(roots(k).imag()));
    }
  }
  return largest;
}

}  // namespace ctid
