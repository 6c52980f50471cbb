// Realisations of the p^k/D(p) filter banks and their exact sampled recursions.
#include "ctid/filtering/filter_bank.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <utility>
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

// The realisation behind derivative_filters, for deg D >= 1.
FilterRealization realize_derivative_filters(const Polynomial& denominator) {
  const int n = denominator.degree();
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
  require(finite(), "FilterRealization: an entry is not finite");
}

bool FilterRealization::finite() const {
  return a.allFinite() && b.allFinite() && c.allFinite() && d.allFinite();
}

FilterRealization derivative_filters(const Polynomial& denominator) {
  const int n = denominator.degree();
  require(n >= 1, "derivative_filters: the denominator must have degree >= 1, got ", n);
  return realize_derivative_filters(denominator);
}

std::optional<FilterRealization> finite_derivative_filters(const Polynomial& denominator) {
  if (denominator.degree() < 1) return std::nullopt;
  FilterRealization f = realize_derivative_filters(denominator);
  if (!f.finite()) return std::nullopt;
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
                             Hold interpolation, double delay_fraction) {
  filter.validate();
  require(std::isfinite(sample_time) && sample_time > 0.0,
          "SampledFilter: sample_time must be positive and finite, got ", sample_time);
  require(std::isfinite(delay_fraction) && delay_fraction >= 0.0 && delay_fraction < 1.0,
          "SampledFilter: the delay fraction is ", delay_fraction, "; it must be in [0, 1)");
  DelayedHoldDiscretization w =
      discretize_delayed(filter.a, filter.b, sample_time, delay_fraction, interpolation);
  phi_ = std::move(w.phi);
  gamma_previous_ = w.previous.col(0);
  gamma0_ = w.current.col(0);
  gamma1_ = w.next.col(0);
  fractional_ = delay_fraction > 0.0;
  const DelayedSample now = delayed_sample(delay_fraction, interpolation);
  output_previous_ = now.previous;
  output_current_ = now.current;
  c_ = filter.c;
  d_ = filter.d;
  // Exact zeros only: skipping them changes no result.
  const int s = order();
  phi_lo_.resize(s);
  phi_hi_.resize(s);
  for (int j = 0; j < s; ++j) {
    int lo = 0;
    int hi = s;
    while (lo < hi && phi_(lo, j) == 0.0) ++lo;
    while (hi > lo && phi_(hi - 1, j) == 0.0) --hi;
    phi_lo_(j) = lo;
    phi_hi_(j) = hi;
  }
  // Even halves only: Eigen sums a product of whole packets (two doubles) term by term in
  // column order, as the full product does, but an odd block by a tree, which rounds otherwise.
  const int half = s / 2;
  split_ = s % 4 == 0 && (phi_.topRightCorner(half, half).array() == 0.0).all();
  c_lo_.resize(outputs());
  c_hi_.resize(outputs());
  for (int j = 0; j < outputs(); ++j) {
    int lo = 0;
    int hi = s;
    while (lo < hi && c_(j, lo) == 0.0) ++lo;
    while (hi > lo && c_(j, hi - 1) == 0.0) --hi;
    c_lo_(j) = lo;
    c_hi_(j) = hi;
  }
}

SampledFilter::Stream SampledFilter::start() const {
  Stream stream;
  stream.state = Eigen::VectorXd::Zero(order());
  stream.scratch = Eigen::VectorXd::Zero(order());
  return stream;
}

namespace {

// Row j of the outputs at one sample: d_j now + the non-zeros of C's row j times z, in column
// order. Rows of at most two columns take the unrolled dense dot, which costs less than
// tracking the non-zeros (and adds the same numbers: the zeros it adds change no sum).
template <int S>
inline void write_outputs(const double* c_first, const double* d, const int* clo, const int* chi,
                          int r, int s, const double* z, double now, double* o, Eigen::Index k,
                          Eigen::Index stride) {
  for (int j = 0; j < r; ++j) {
    const double* row = c_first + static_cast<ptrdiff_t>(j) * s;
    double acc = d[j] * now;
    if constexpr (S > 0 && S <= 2) {
      for (int i = 0; i < S; ++i) acc += row[i] * z[i];
    } else {
      for (int i = clo[j]; i < chi[j]; ++i) acc += row[i] * z[i];
    }
    o[k + j * stride] = acc;
  }
}

}  // namespace

// S > 0 fixes the state dimension at compile time and the dense S x S update unrolls (H > 0:
// without the zero upper right block of a cascade). Above two states the state is a
// fixed-size vector the compiler keeps in registers, so the recursion from one sample to the
// next does not go through memory (twice as fast for the 4-state cascade); up to two it stays
// in a local array, measured faster there. Either way every sum keeps its order, so the numbers
// are the same. S == 0 is the general case, which skips the exact zeros of phi column by
// column. Per sample: finish the step from the previous sample (the first-order hold needs the
// current one), then read the outputs (sparse rows of C) at t_k.
template <int S, int H>
void SampledFilter::run_fixed(const Eigen::Ref<const Eigen::VectorXd>& x, Stream& stream,
                              Eigen::Ref<Eigen::MatrixXd> out, int first_output) const {
  const int s = S > 0 ? S : order();
  const Eigen::Index n = x.size();
  const int r = static_cast<int>(out.cols());
  const double* d = d_.data() + first_output;
  const int* clo = c_lo_.data() + first_output;
  const int* chi = c_hi_.data() + first_output;
  const double* c_first = c_.data() + static_cast<ptrdiff_t>(first_output) * s;
  const bool fractional = fractional_;
  const double out_previous = output_previous_;
  const double out_current = output_current_;
  double previous = stream.previous;
  double before_previous = stream.before_previous;
  bool started = stream.started;
  double* o = out.data();
  const Eigen::Index stride = out.outerStride();
  if constexpr (S > 2) {
    using Vector = Eigen::Matrix<double, S, 1>;
    using Matrix = Eigen::Matrix<double, S, S>;
    const Matrix p = Eigen::Map<const Matrix>(phi_.data());
    const Vector gp = Eigen::Map<const Vector>(gamma_previous_.data());
    const Vector g0 = Eigen::Map<const Vector>(gamma0_.data());
    const Vector g1 = Eigen::Map<const Vector>(gamma1_.data());
    Vector z = stream.state;
    for (Eigen::Index k = 0; k < n; ++k) {
      const double xk = x(k);
      if (started) {
        Vector next;
        if (fractional) {
          next = gp * before_previous + g0 * previous + g1 * xk;
        } else {
          next = g0 * previous + g1 * xk;
        }
        if constexpr (H > 0) {
          // Rows above H see only the first H states: the same sums in the same order
          // without the exact zeros, so the same numbers.
          next.template head<H>().noalias() +=
              p.template topLeftCorner<H, H>().lazyProduct(z.template head<H>());
          next.template tail<S - H>().noalias() += p.template bottomRows<S - H>().lazyProduct(z);
        } else {
          next.noalias() += p.lazyProduct(z);
        }
        z = next;
      }
      started = true;
      // The (delayed) signal at t_k; x_k itself without a delay fraction.
      const double now = fractional ? out_previous * previous + out_current * xk : xk;
      write_outputs<S>(c_first, d, clo, chi, r, s, z.data(), now, o, k, stride);
      before_previous = previous;
      previous = xk;
    }
    stream.state = z;
  } else {
    constexpr int kLocal = S > 0 ? S : 1;
    alignas(16) double local_z[kLocal];
    alignas(16) double local_next[kLocal];
    double* z = S > 0 ? local_z : stream.state.data();
    double* next = S > 0 ? local_next : stream.scratch.data();
    if (S > 0) {
      for (int i = 0; i < s; ++i) z[i] = stream.state(i);
    }
    const double* phi = phi_.data();
    const int* lo = phi_lo_.data();
    const int* hi = phi_hi_.data();
    const double* gp = gamma_previous_.data();
    const double* g0 = gamma0_.data();
    const double* g1 = gamma1_.data();
    for (Eigen::Index k = 0; k < n; ++k) {
      const double xk = x(k);
      if (started) {
        if (fractional) {
          for (int i = 0; i < s; ++i) {
            next[i] = gp[i] * before_previous + g0[i] * previous + g1[i] * xk;
          }
        } else {
          for (int i = 0; i < s; ++i) next[i] = g0[i] * previous + g1[i] * xk;
        }
        if constexpr (S > 0) {
          using Vector = Eigen::Matrix<double, kLocal, 1>;
          Eigen::Map<Vector> zv(z);
          Eigen::Map<Vector>(next).noalias() +=
              Eigen::Map<const Eigen::Matrix<double, kLocal, kLocal>>(phi).lazyProduct(zv);
          zv = Eigen::Map<const Vector>(next);
        } else {
          for (int j = 0; j < s; ++j) {
            const double zj = z[j];
            const double* col = phi + static_cast<ptrdiff_t>(j) * s;
            for (int i = lo[j]; i < hi[j]; ++i) next[i] += col[i] * zj;
          }
          std::swap(z, next);
        }
      }
      started = true;
      const double now = fractional ? out_previous * previous + out_current * xk : xk;
      write_outputs<S>(c_first, d, clo, chi, r, s, z, now, o, k, stride);
      before_previous = previous;
      previous = xk;
    }
    if (S > 0) {
      for (int i = 0; i < s; ++i) stream.state(i) = z[i];
    } else if (z != stream.state.data()) {
      stream.state.swap(stream.scratch);  // the pointers were swapped an odd number of times
    }
  }
  stream.previous = previous;
  stream.before_previous = before_previous;
  stream.started = started;
}

void SampledFilter::run(const Eigen::Ref<const Eigen::VectorXd>& x, Stream& stream,
                        Eigen::Ref<Eigen::MatrixXd> out, int first_output) const {
  require(out.rows() == x.size() && first_output >= 0 && first_output + out.cols() <= outputs(),
          "SampledFilter::run: out is ", out.rows(), " x ", out.cols(), " from output ",
          first_output, ", expected ", x.size(), " rows and at most ", outputs(), " outputs");
  require(stream.state.size() == order() && stream.scratch.size() == order(),
          "SampledFilter::run: the stream has ", stream.state.size(), " states, expected ",
          order());
  // A cascade of two equal-order filters (the refined IV instrument chain) has a zero upper
  // right quarter; its dedicated update skips it.
  switch (order()) {
    case 1:
      return run_fixed<1, 0>(x, stream, out, first_output);
    case 2:
      return run_fixed<2, 0>(x, stream, out, first_output);
    case 3:
      return run_fixed<3, 0>(x, stream, out, first_output);
    case 4:
      return split_ ? run_fixed<4, 2>(x, stream, out, first_output)
                    : run_fixed<4, 0>(x, stream, out, first_output);
    case 6:
      return run_fixed<6, 0>(x, stream, out, first_output);
    case 8:
      return split_ ? run_fixed<8, 4>(x, stream, out, first_output)
                    : run_fixed<8, 0>(x, stream, out, first_output);
    case 12:
      return split_ ? run_fixed<12, 6>(x, stream, out, first_output)
                    : run_fixed<12, 0>(x, stream, out, first_output);
    case 16:
      return split_ ? run_fixed<16, 8>(x, stream, out, first_output)
                    : run_fixed<16, 0>(x, stream, out, first_output);
    default:
      return run_fixed<0, 0>(x, stream, out, first_output);
  }
}

void SampledFilter::apply(const Eigen::Ref<const Eigen::VectorXd>& x,
                          Eigen::Ref<Eigen::MatrixXd> out) const {
  const Eigen::Index n = x.size();
  require(out.rows() == n && out.cols() == outputs(), "SampledFilter::apply: out is ", out.rows(),
          " x ", out.cols(), ", expected ", n, " x ", outputs());
  Stream stream = start();
  run(x, stream, out, 0);
}

Eigen::MatrixXd SampledFilter::apply(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  Eigen::MatrixXd out(x.size(), outputs());
  apply(x, out);
  return out;
}

Eigen::MatrixXd filter_derivatives(const Polynomial& denominator,
                                   const Eigen::Ref<const Eigen::VectorXd>& x, double sample_time,
                                   Hold interpolation) {
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
