// Realisations of the p^k/D(p) filter banks and their exact sampled recursions.
#include "ctid/filtering/filter_bank.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/simulation/discretization.h"

namespace ctid {
namespace {

// Diagonal similarity T = diag(2^k) making rows and columns of T^-1 A T comparable in norm
// (Osborne's iteration). Powers of two keep it exact; it only improves the conditioning of
// the realisation, never the transfer functions.
void balance(FilterRealization& f) {
  const int s = f.order();
  if (s < 2) return;
  Eigen::VectorXd t = Eigen::VectorXd::Ones(s);
  constexpr double radix = 2.0;
  bool changed = true;
  for (int sweep = 0; changed && sweep < 50; ++sweep) {
    changed = false;
    for (int i = 0; i < s; ++i) {
      double col = 0.0;
      double row = 0.0;
      for (int j = 0; j < s; ++j) {
        if (j == i) continue;
        col += std::abs(f.a(j, i));
        row += std::abs(f.a(i, j));
      }
      if (col == 0.0 || row == 0.0) continue;
      double g = row / radix;
      double scale = 1.0;
      const double total = col + row;
      while (col < g) {
        scale *= radix;
        col *= radix * radix;
      }
      g = row * radix;
      while (col > g) {
        scale /= radix;
        col /= radix * radix;
      }
      if ((col + row) / scale < 0.95 * total) {
        changed = true;
        // A <- T_i^-1 A T_i with T_i = diag(.., scale, ..): row i / scale, column i * scale.
        f.a.row(i) /= scale;
        f.a.col(i) *= scale;
        t(i) *= scale;
      }
    }
  }
  f.b.array() /= t.array();
  f.c = f.c * t.asDiagonal();
}

}  // namespace

void FilterRealization::validate() const {
  require(a.rows() == a.cols(), "FilterRealization: A must be square, got ", a.rows(), " x ",
          a.cols());
  require(b.size() == a.rows(), "FilterRealization: b has ", b.size(), " entries, expected ",
          a.rows());
  require(c.cols() == a.rows(), "FilterRealization: C has ", c.cols(), " columns, expected ",
          a.rows());
  require(d.size() == c.rows(), "FilterRealization: d has ", d.size(), " entries, expected ",
          c.rows());
  require(a.allFinite() && b.allFinite() && c.allFinite() && d.allFinite(),
          "FilterRealization: an entry is not finite");
}

FilterRealization derivative_filters(const Polynomial& denominator) {
  const int n = denominator.degree();
  require(n >= 1, "derivative_filters: the denominator must have degree >= 1, got ", n);
  const Eigen::VectorXd& c = denominator.coefficients();
  int lowest = 0;
  while (c(lowest) == 0.0) ++lowest;
  // Time scale: geometric mean of the magnitudes of the non-zero roots.
  const double omega =
      lowest < n ? std::pow(std::abs(c(lowest) / c(n)), 1.0 / static_cast<double>(n - lowest))
                 : 1.0;
  // z_j = p^j w / omega^j with w = x / D: dz_j = omega z_{j+1}, and
  // p^n w = (x - sum_j c_j omega^j z_j) / c_n.
  Eigen::VectorXd scaled(n);  // c_j omega^j
  double power = 1.0;
  for (int j = 0; j < n; ++j) {
    scaled(j) = c(j) * power;
    power *= omega;
  }
  const double top = c(n) * std::pow(omega, n - 1);  // c_n omega^(n-1)
  FilterRealization f;
  f.a = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j + 1 < n; ++j) f.a(j, j + 1) = omega;
  f.a.row(n - 1) = -scaled.transpose() / top;
  f.b = Eigen::VectorXd::Zero(n);
  f.b(n - 1) = 1.0 / top;
  f.c = Eigen::MatrixXd::Zero(n + 1, n);
  f.d = Eigen::VectorXd::Zero(n + 1);
  power = 1.0;
  for (int k = 0; k < n; ++k) {
    f.c(k, k) = power;
    power *= omega;
  }
  f.c.row(n) = -scaled.transpose() / c(n);
  f.d(n) = 1.0 / c(n);
  balance(f);
  return f;
}

FilterRealization cascade(const FilterRealization& first, const Eigen::VectorXd& weights,
                          const FilterRealization& second) {
  first.validate();
  second.validate();
  require(weights.size() == first.outputs(), "cascade: weights has ", weights.size(),
          " entries, expected one per output of the first filter (", first.outputs(), ")");
  const int s1 = first.order();
  const int s2 = second.order();
  const Eigen::RowVectorXd c1 = weights.transpose() * first.c;
  const double d1 = weights.dot(first.d);
  FilterRealization f;
  f.a = Eigen::MatrixXd::Zero(s1 + s2, s1 + s2);
  f.a.topLeftCorner(s1, s1) = first.a;
  f.a.bottomLeftCorner(s2, s1) = second.b * c1;
  f.a.bottomRightCorner(s2, s2) = second.a;
  f.b.resize(s1 + s2);
  f.b.head(s1) = first.b;
  f.b.tail(s2) = second.b * d1;
  f.c.resize(second.outputs(), s1 + s2);
  f.c.leftCols(s1) = second.d * c1;
  f.c.rightCols(s2) = second.c;
  f.d = second.d * d1;
  return f;
}

FilterRealization combine_outputs(const FilterRealization& filter, const Eigen::VectorXd& weights) {
  filter.validate();
  require(weights.size() == filter.outputs(), "combine_outputs: weights has ", weights.size(),
          " entries, expected ", filter.outputs());
  FilterRealization f;
  f.a = filter.a;
  f.b = filter.b;
  f.c = weights.transpose() * filter.c;
  f.d = Eigen::VectorXd::Constant(1, weights.dot(filter.d));
  return f;
}

SampledFilter::SampledFilter(const FilterRealization& filter, double sample_time,
                             Interpolation interpolation) {
  filter.validate();
  require(std::isfinite(sample_time) && sample_time > 0.0,
          "SampledFilter: sample_time must be positive and finite, got ", sample_time);
  if (interpolation == Interpolation::zero_order_hold) {
    const ZohDiscretization zoh = discretize_zoh(filter.a, filter.b, sample_time);
    phi_ = zoh.phi;
    gamma0_ = zoh.gamma.col(0);
    gamma1_ = Eigen::VectorXd::Zero(filter.order());
  } else {
    const FohDiscretization foh = discretize_foh(filter.a, filter.b, sample_time);
    phi_ = foh.phi;
    gamma0_ = foh.gamma0.col(0);
    gamma1_ = foh.gamma1.col(0);
  }
  c_ = filter.c;
  d_ = filter.d;
}

void SampledFilter::apply(const Eigen::Ref<const Eigen::VectorXd>& x,
                          Eigen::Ref<Eigen::MatrixXd> out) const {
  const Eigen::Index n = x.size();
  require(out.rows() == n && out.cols() == outputs(), "SampledFilter::apply: out is ", out.rows(),
          " x ", out.cols(), ", expected ", n, " x ", outputs());
  const int s = order();
  const int r = outputs();
  std::vector<double> z(static_cast<size_t>(s), 0.0);
  std::vector<double> next(static_cast<size_t>(s), 0.0);
  const double* phi = phi_.data();
  const double* c = c_.data();
  const double* g0 = gamma0_.data();
  const double* g1 = gamma1_.data();
  const double* d = d_.data();
  for (Eigen::Index k = 0; k < n; ++k) {
    const double xk = x(k);
    for (int j = 0; j < r; ++j) {
      const double* row = c + static_cast<ptrdiff_t>(j) * s;
      double acc = d[j] * xk;
      for (int i = 0; i < s; ++i) acc += row[i] * z[static_cast<size_t>(i)];
      out(k, j) = acc;
    }
    // The last sample is held: the state after it is never output.
    const double xnext = k + 1 < n ? x(k + 1) : xk;
    for (int i = 0; i < s; ++i) {
      const double* row = phi + static_cast<ptrdiff_t>(i) * s;
      double acc = g0[i] * xk + g1[i] * xnext;
      for (int m = 0; m < s; ++m) acc += row[m] * z[static_cast<size_t>(m)];
      next[static_cast<size_t>(i)] = acc;
    }
    z.swap(next);
  }
}

Eigen::MatrixXd SampledFilter::apply(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  Eigen::MatrixXd out(x.size(), outputs());
  apply(x, out);
  return out;
}

Eigen::MatrixXd filter_derivatives(const Polynomial& denominator,
                                   const Eigen::Ref<const Eigen::VectorXd>& x, double sample_time,
                                   Interpolation interpolation) {
  return SampledFilter(derivative_filters(denominator), sample_time, interpolation).apply(x);
}

Eigen::VectorXd delay_samples(const Eigen::Ref<const Eigen::VectorXd>& x, int delay) {
  require(delay >= 0, "delay_samples: delay must be >= 0 samples, got ", delay);
  const Eigen::Index n = x.size();
  Eigen::VectorXd out = Eigen::VectorXd::Zero(n);
  if (delay < n) out.tail(n - delay) = x.head(n - delay);
  return out;
}

}  // namespace ctid
