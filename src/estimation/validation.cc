// Model output, fit and the data checks of Assumptions 1 and 4.
#include "ctid/estimation/validation.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "ctid/core/error.h"
#include "ctid/filtering/filter_bank.h"

namespace ctid {

Eigen::VectorXd model_output(const AdditiveModel& model, const Eigen::VectorXd& input,
                             double sample_time) {
  require(std::isfinite(sample_time) && sample_time > 0.0,
          "model_output: sample_time must be positive, got ", sample_time);
  require(input.allFinite(), "model_output: the input has a non-finite value");
  const double samples = model.input_delay() / sample_time;
  const double rounded = std::round(samples);
  require(std::abs(samples - rounded) <= 1e-9 * std::max(1.0, samples),
          "model_output: the input delay ", model.input_delay(), " s is not a whole number of ",
          "samples of ", sample_time, " s (", samples, " samples)");
  const Eigen::VectorXd u = delay_samples(input, static_cast<int>(rounded));
  Eigen::VectorXd y = Eigen::VectorXd::Zero(input.size());
  for (int i = 0; i < model.size(); ++i) {
    const Submodel& s = model[i];
    const Polynomial den = Polynomial::monomial(s.integrators) * s.a;
    if (den.degree() == 0) {
      y += (s.b[0] / den[0]) * u;
      continue;
    }
    const Eigen::MatrixXd f = filter_derivatives(den, u, sample_time, Hold::zero_order_hold);
    for (int k = 0; k <= s.m(); ++k) y += s.b[k] * f.col(k);
  }
  return y;
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

ValidationReport validate_model(const AdditiveModel& model, const SampledData& data, int max_lag) {
  require(max_lag >= 1, "validate_model: max_lag must be at least 1, got ", max_lag);
  return residual_report(data, model_output(model, data.input(), data.sample_time()), max_lag);
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
  const Eigen::VectorXd u = data.input().array() - data.input().mean();
  const double c0 = c.squaredNorm();
  r.residual_std = std::sqrt(c0 / static_cast<double>(n));
  r.whiteness_bound = 2.58 / std::sqrt(static_cast<double>(n));
  r.max_lag = static_cast<int>(std::min<Eigen::Index>(max_lag, n - 1));
  r.residual_autocorrelation = Eigen::VectorXd::Zero(r.max_lag);
  r.cross_correlation = Eigen::VectorXd::Zero(2 * r.max_lag + 1);
  const double cross_scale = std::sqrt(c0 * u.squaredNorm());
  for (int k = 1; k <= r.max_lag && c0 > 0.0; ++k) {
    r.residual_autocorrelation(k - 1) = c.head(n - k).dot(c.tail(n - k)) / c0;
  }
  for (int k = -r.max_lag; k <= r.max_lag && cross_scale > 0.0; ++k) {
    const Eigen::Index m = n - std::abs(k);
    const double sum = k >= 0 ? c.tail(m).dot(u.head(m)) : c.head(m).dot(u.tail(m));
    r.cross_correlation(k + r.max_lag) = sum / cross_scale;
  }
  if (r.max_lag > 0) {
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
