#include "ctid/estimation/arma.h"

#include <algorithm>
#include <cmath>
#include <complex>

#include <Eigen/Dense>

#include "ctid/core/error.h"
#include "ctid/core/polynomial.h"
#include "estimation/internal/difference_equation.h"
#include "estimation/internal/scaled_least_squares.h"

namespace ctid {

namespace internal {

Eigen::VectorXd filter_from_rest(const Eigen::VectorXd& b, const Eigen::VectorXd& a,
                                 const Eigen::VectorXd& x, const RecordRanges& records) {
  Eigen::VectorXd y(x.size());
  for (const auto& [first, end] : records) {
    for (Eigen::Index t = first; t < end; ++t) {
      double value = 0.0;
      for (Eigen::Index i = 0; i < b.size() && t - i >= first; ++i) value += b(i) * x(t - i);
      for (Eigen::Index j = 1; j < a.size() && t - j >= first; ++j) value -= a(j) * y(t - j);
      y(t) = value;
    }
  }
  return y;
}

}  // namespace internal

namespace {

using internal::RecordRanges;

// The records of v as [first, end) ranges.
RecordRanges arma_records(Eigen::Index n, const std::vector<Eigen::Index>& starts) {
  RecordRanges out;
  Eigen::Index first = 0;
  for (Eigen::Index s : starts) {
    require(s > first && s < n, "fit_arma: record start ", s, " is not after ", first,
            " and before the end ", n);
    out.emplace_back(first, s);
    first = s;
  }
  out.emplace_back(first, n);
  return out;
}

// x delayed by k samples within each record (zeros before its first sample).
Eigen::VectorXd arma_shift(const Eigen::VectorXd& x, int k, const RecordRanges& records) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(x.size());
  for (const auto& [first, end] : records) {
    if (end - first > k)
      out.segment(first + k, end - first - k) = x.segment(first, end - first - k);
  }
  return out;
}

// Roots of 1 + c_1 x + ... + c_q x^q (x = q^-1) inside the unit disc mirrored outside it, so
// that 1/C is stable.
void make_invertible(Eigen::VectorXd& c) {
  const Polynomial poly = Polynomial::trimmed(c);
  if (poly.degree() < 1) return;
  Eigen::VectorXcd roots = poly.roots();
  bool changed = false;
  for (Eigen::Index i = 0; i < roots.size(); ++i) {
    if (std::abs(roots(i)) < 1.0 + 1e-8) {
      roots(i) = (1.0 + 1e-3) / std::conj(roots(i));
      changed = true;
    }
  }
  if (!changed) return;
  const Eigen::VectorXd mirrored = Polynomial::from_roots(roots).anti_monic().coefficients();
  c.setZero();
  c.head(mirrored.size()) = mirrored;
}

bool invertible(const Eigen::VectorXd& c) {
  if (!c.allFinite()) return false;
  const Polynomial poly = Polynomial::trimmed(c);
  if (poly.degree() < 1) return true;
  return poly.roots().cwiseAbs().minCoeff() > 1.0 + 1e-10;
}

// The Hannan-Rissanen estimate: a long AR model's residual as the innovations, then least
// squares of v on its own past and that residual's past.
void hannan_rissanen(const Eigen::VectorXd& v, int p, int q, const RecordRanges& records,
                     Eigen::VectorXd& d, Eigen::VectorXd& c) {
  const Eigen::Index n = v.size();
  d = Eigen::VectorXd::Zero(p + 1);
  c = Eigen::VectorXd::Zero(q + 1);
  d(0) = 1.0;
  c(0) = 1.0;
  if (p + q == 0) return;
  Eigen::VectorXd innovations = v;
  const int long_order =
      q == 0 ? 0 : static_cast<int>(std::min<Eigen::Index>(std::max(20, 2 * (p + q)), n / 10));
  if (long_order > 0) {
    Eigen::MatrixXd design(n, long_order);
    for (int i = 1; i <= long_order; ++i) design.col(i - 1) = -arma_shift(v, i, records);
    innovations = internal::scaled_least_squares(design, v).residual;
  }
  Eigen::MatrixXd design(n, p + q);
  for (int i = 1; i <= p; ++i) design.col(i - 1) = -arma_shift(v, i, records);
  for (int j = 1; j <= q; ++j) design.col(p + j - 1) = arma_shift(innovations, j, records);
  const Eigen::VectorXd theta = internal::scaled_least_squares(design, v).coefficients;
  d.tail(p) = theta.head(p);
  c.tail(q) = theta.tail(q);
  if (!c.allFinite()) c.tail(q).setZero();
  if (!d.allFinite()) d.tail(p).setZero();
  make_invertible(c);
}

}  // namespace

ArmaModel fit_arma(const Eigen::VectorXd& v, int ar_order, int ma_order,
                   const std::vector<Eigen::Index>& record_starts) {
  require(ar_order >= 0 && ar_order <= kMaxArmaOrder && ma_order >= 0 && ma_order <= kMaxArmaOrder,
          "fit_arma: the orders (", ar_order, ", ", ma_order, ") must each lie in [0, ",
          kMaxArmaOrder, "]");
  require(v.allFinite(), "fit_arma: the noise sequence has a value that is not finite");
  const int p = ar_order;
  const int q = ma_order;
  const Eigen::Index n = v.size();
  const Eigen::Index needed = 10 * (p + q) + 20;
  require(n >= needed, "fit_arma: ", n, " samples cannot hold an ARMA(", p, ", ", q,
          ") noise model; it needs at least ", needed);
  const auto records = arma_records(n, record_starts);
  ArmaModel model;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const int k = p + q;
  Eigen::VectorXd d;
  Eigen::VectorXd c;
  if (v.squaredNorm() == 0.0) {
    model.ar = Eigen::VectorXd::Unit(p + 1, 0);
    model.ma = Eigen::VectorXd::Unit(q + 1, 0);
    model.covariance = Eigen::MatrixXd::Constant(k, k, nan);
    model.standard_errors = Eigen::VectorXd::Constant(k, nan);
    model.converged = true;
    return model;
  }
  hannan_rissanen(v, p, q, records, d, c);
  Eigen::VectorXd e = internal::filter_from_rest(d, c, v, records);
  double sse = e.squaredNorm();
  Eigen::MatrixXd jacobian(n, k);
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(1);
  auto gradient = [&]() {
    // de/dd_i = q^-i (1/C) v; de/dc_j = -q^-j (1/C) e.
    const Eigen::VectorXd w = internal::filter_from_rest(one, c, v, records);
    const Eigen::VectorXd s = internal::filter_from_rest(one, c, e, records);
    for (int i = 1; i <= p; ++i) jacobian.col(i - 1) = arma_shift(w, i, records);
    for (int j = 1; j <= q; ++j) jacobian.col(p + j - 1) = -arma_shift(s, j, records);
  };
  constexpr int kMaxIterations = 100;
  constexpr double kTolerance = 1e-11;
  for (int iteration = 1; iteration <= kMaxIterations && k > 0; ++iteration) {
    gradient();
    const Eigen::VectorXd step = -internal::scaled_least_squares(jacobian, e).coefficients;
    if (!step.allFinite()) break;
    double scale = 1.0;
    bool accepted = false;
    for (int halving = 0; halving < 30; ++halving, scale *= 0.5) {
      Eigen::VectorXd d_new = d;
      Eigen::VectorXd c_new = c;
      d_new.tail(p) += scale * step.head(p);
      c_new.tail(q) += scale * step.tail(q);
      if (!d_new.allFinite() || !invertible(c_new)) continue;
      const Eigen::VectorXd e_new = internal::filter_from_rest(d_new, c_new, v, records);
      const double sse_new = e_new.squaredNorm();
      if (!(sse_new <= sse * (1.0 + 1e-14))) continue;
      d = std::move(d_new);
      c = std::move(c_new);
      e = e_new;
      sse = sse_new;
      accepted = true;
      break;
    }
    model.iterations = iteration;
    if (!accepted) break;
    Eigen::VectorXd theta(k);
    theta << d.tail(p), c.tail(q);
    if (scale * step.lpNorm<Eigen::Infinity>() <=
        kTolerance * std::max(1.0, theta.lpNorm<Eigen::Infinity>())) {
      model.converged = true;
      break;
    }
  }
  if (k == 0) model.converged = true;
  model.ar = d;
  model.ma = c;
  const double dof = static_cast<double>(std::max<Eigen::Index>(n - k, 1));
  model.innovation_variance = sse / dof;
  model.criterion = static_cast<double>(n) * std::log(sse / static_cast<double>(n)) +
                    k * std::log(static_cast<double>(n));
  if (k > 0) {
    gradient();
    const Eigen::MatrixXd information = jacobian.transpose() * jacobian;
    model.covariance =
        model.innovation_variance * information.completeOrthogonalDecomposition().pseudoInverse();
  } else {
    model.covariance = Eigen::MatrixXd(0, 0);
  }
  model.standard_errors = model.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  return model;
}

ArmaModel fit_arma_by_criterion(const Eigen::VectorXd& v, int max_order,
                                const std::vector<Eigen::Index>& record_starts) {
  require(max_order >= 0 && max_order <= kMaxArmaOrder,
          "fit_arma_by_criterion: max_order = ", max_order, " must lie in [0, ", kMaxArmaOrder,
          "]");
  std::optional<ArmaModel> best;
  for (int p = 0; p <= max_order; ++p) {
    for (int q = 0; q <= max_order; ++q) {
      if (v.size() < 10 * (p + q) + 20 && (p + q) > 0) continue;
      ArmaModel m = fit_arma(v, p, q, record_starts);
      // A sequence of zeros: the white model, nothing to choose.
      if (!std::isfinite(m.criterion)) return m;
      if (!best || m.criterion < best->criterion) best = std::move(m);
    }
  }
  if (!best) return fit_arma(v, 0, 0, record_starts);
  return std::move(*best);
}

Eigen::VectorXd arma_innovations(const ArmaModel& model, const Eigen::VectorXd& v,
                                 const std::vector<Eigen::Index>& record_starts) {
  return internal::filter_from_rest(model.ar, model.ma, v, arma_records(v.size(), record_starts));
}

void arma_spectrum(ArmaModel& model, double sample_time, int points) {
  require(sample_time > 0.0 && points >= 2, "arma_spectrum: sample_time = ", sample_time,
          " and points = ", points, " must be > 0 and >= 2");
  model.spectrum_frequencies = Eigen::VectorXd::LinSpaced(points, 0.0, 0.5 / sample_time);
  model.spectrum.resize(points);
  // C and D as polynomials in x = q^-1, evaluated at x = e^{-i 2 pi f h}.
  const Polynomial c = Polynomial::trimmed(model.ma);
  const Polynomial d = Polynomial::trimmed(model.ar);
  for (int i = 0; i < points; ++i) {
    const std::complex<double> x =
        std::polar(1.0, -2.0 * M_PI * model.spectrum_frequencies(i) * sample_time);
    model.spectrum(i) =
        2.0 * sample_time * model.innovation_variance * std::norm(c(x)) / std::norm(d(x));
  }
}

InverseNoiseFilter::InverseNoiseFilter(const ArmaModel& model, Eigen::Index columns) {
  const Eigen::Index order = std::max(model.ar.size(), model.ma.size()) - 1;
  numerator_ = Eigen::VectorXd::Zero(order + 1);
  denominator_ = Eigen::VectorXd::Zero(order + 1);
  numerator_.head(model.ar.size()) = model.ar;
  denominator_.head(model.ma.size()) = model.ma;
  state_ = Eigen::MatrixXd::Zero(order, columns);
}

void InverseNoiseFilter::apply(Eigen::Ref<Eigen::MatrixXd> block) {
  const Eigen::Index order = state_.rows();
  if (order == 0) return;  // D = C = 1
  Eigen::RowVectorXd x(block.cols());
  for (Eigen::Index t = 0; t < block.rows(); ++t) {
    x = block.row(t);
    block.row(t) = numerator_(0) * x + state_.row(0);
    for (Eigen::Index i = 0; i + 1 < order; ++i) {
      state_.row(i) =
          state_.row(i + 1) + numerator_(i + 1) * x - denominator_(i + 1) * block.row(t);
    }
    state_.row(order - 1) = numerator_(order) * x - denominator_(order) * block.row(t);
  }
}

}  // namespace ctid
