// A shared-pole modal model fitted to a measured FRF matrix (frf_matrix_fit.h).
#include "ctid/frf_fit/frf_matrix_fit.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <limits>
#include <utility>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include "core/internal/signal_range.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/estimation/mimo_modes.h"
#include "ctid/estimation/verdict.h"
#include "estimation/internal/mimo_layout.h"
#include "estimation/internal/scaled_least_squares.h"

namespace ctid {

namespace {

using Complex = std::complex<double>;
constexpr Complex kJ{0.0, 1.0};
// A relative decrease of the cost this small is rounding: the iterate is a stationary point.
constexpr double kFlatCost = 4.0 * std::numeric_limits<double>::epsilon();

using Layout = internal::MimoLayout;

// The lines fitted: s = j w, the response per channel (column c = j * inputs + k) and the
// square roots of the weights.
struct Problem {
  Eigen::VectorXd w;
  Eigen::VectorXcd s;
  Eigen::MatrixXcd h;      // lines x channels
  Eigen::MatrixXd weight;  // lines x channels: 1 / sqrt(variance), or 1
  bool uniform = true;
  int lines() const { return static_cast<int>(w.size()); }
};

// Parameters: the denominators' coefficients a_i1..a_in and, per output, the numerator block.
struct Parameters {
  std::vector<Eigen::VectorXd> a;  // per submodel, [1, a_1, .., a_n]
  Eigen::MatrixXd u;               // u_count x outputs
};

Complex horner(const Eigen::VectorXd& c, Complex s) {
  Complex v = 0.0;
  for (Eigen::Index r = c.size() - 1; r >= 0; --r) v = v * s + c(r);
  return v;
}

// 1 / A_i(s) at every line (lines x submodels).
Eigen::MatrixXcd inverse_denominators(const Problem& p, const std::vector<Eigen::VectorXd>& a) {
  Eigen::MatrixXcd inv(p.lines(), static_cast<Eigen::Index>(a.size()));
  for (size_t i = 0; i < a.size(); ++i) {
    for (int l = 0; l < p.lines(); ++l) {
      inv(l, static_cast<Eigen::Index>(i)) = 1.0 / horner(a[i], p.s(l));
    }
  }
  return inv;
}

// The columns of one channel's response in its own parameters: s^r / A_i(s) for every
// submodel and r <= m_i, then 1 for D (lines x channel_columns), unweighted.
Eigen::MatrixXcd channel_basis(const Layout& layout, const Problem& p,
                               const Eigen::MatrixXcd& inv) {
  Eigen::MatrixXcd x(p.lines(), layout.channel_columns());
  int c = 0;
  for (int i = 0; i < layout.size(); ++i) {
    for (int r = 0; r <= layout.orders[static_cast<size_t>(i)].m; ++r, ++c) {
      for (int l = 0; l < p.lines(); ++l) x(l, c) = std::pow(p.s(l), r) * inv(l, i);
    }
  }
  if (layout.direct) x.col(c).setOnes();
  return x;
}

// [Re; Im] of a complex matrix, rows stacked.
Eigen::MatrixXd stacked(const Eigen::MatrixXcd& x) {
  Eigen::MatrixXd r(2 * x.rows(), x.cols());
  r << x.real(), x.imag();
  return r;
}

// Position of channel column c of (submodel/power, D) in an output's numerator block for input k.
int block_column(const Layout& layout, int k, int c) {
  for (int i = 0; i < layout.size(); ++i) {
    const int count = layout.orders[static_cast<size_t>(i)].m + 1;
    if (c < count) return layout.u_column(i, k, c);
    c -= count;
  }
  return layout.d_at + k;
}

// The numerators (and D) by weighted linear least squares given the denominators (LSFD).
Eigen::MatrixXd fit_numerators(const Layout& layout, const Problem& p,
                               const std::vector<Eigen::VectorXd>& a) {
  const Eigen::MatrixXcd basis = channel_basis(layout, p, inverse_denominators(p, a));
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(layout.u_count, layout.outputs);
  const int channels = layout.inputs * layout.outputs;
  const auto store = [&](int channel, const Eigen::VectorXd& x) {
    const int j = channel / layout.inputs;
    const int k = channel % layout.inputs;
    for (Eigen::Index c = 0; c < x.size(); ++c) {
      u(block_column(layout, k, static_cast<int>(c)), j) = x(c);
    }
  };
  if (p.uniform) {
    // One factorisation serves every channel.
    const Eigen::MatrixXd x = stacked(basis);
    const Eigen::VectorXd scale = internal::column_scales(x);
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(x * scale.cwiseInverse().asDiagonal());
    Eigen::MatrixXd rhs(2 * p.lines(), channels);
    rhs << p.h.real(), p.h.imag();
    const Eigen::MatrixXd z = qr.solve(rhs);
    for (int c = 0; c < channels; ++c) store(c, z.col(c).cwiseQuotient(scale));
  } else {
    for (int c = 0; c < channels; ++c) {
      const Eigen::MatrixXcd xw = p.weight.col(c).asDiagonal() * basis;
      const Eigen::VectorXcd yw = p.weight.col(c).cwiseProduct(p.h.col(c));
      Eigen::VectorXd rhs(2 * p.lines());
      rhs << yw.real(), yw.imag();
      store(c, internal::scaled_least_squares(stacked(xw), rhs).coefficients);
    }
  }
  return u;
}

// The model's response at every line (lines x channels).
Eigen::MatrixXcd response_of(const Layout& layout, const Problem& p, const Parameters& theta) {
  const Eigen::MatrixXcd basis = channel_basis(layout, p, inverse_denominators(p, theta.a));
  Eigen::MatrixXcd g(p.lines(), layout.inputs * layout.outputs);
  Eigen::VectorXd x(layout.channel_columns());
  for (int j = 0; j < layout.outputs; ++j) {
    for (int k = 0; k < layout.inputs; ++k) {
      for (Eigen::Index c = 0; c < x.size(); ++c) {
        x(c) = theta.u(block_column(layout, k, static_cast<int>(c)), j);
      }
      g.col(j * layout.inputs + k) = basis * x.cast<Complex>();
    }
  }
  return g;
}

// Weighted residuals H - G (lines x channels).
Eigen::MatrixXcd residuals(const Layout& layout, const Problem& p, const Parameters& theta) {
  return p.weight.cast<Complex>().cwiseProduct(p.h - response_of(layout, p, theta));
}

double cost_of(const Eigen::MatrixXcd& e) { return e.squaredNorm(); }

bool stable_and_finite(const std::vector<Eigen::VectorXd>& a) {
  for (const Eigen::VectorXd& c : a) {
    if (!c.allFinite() || c(c.size() - 1) == 0.0) return false;
    const Eigen::VectorXcd roots = Polynomial(c).roots();
    for (Eigen::Index q = 0; q < roots.size(); ++q) {
      if (!(roots(q).real() < 0.0)) return false;
    }
  }
  return true;
}

// ---- The start: vector fitting with relaxed pole relocation ----

// Poles: each complex pair once (imaginary part > 0) and every real pole.
struct Poles {
  std::vector<Complex> pairs;
  std::vector<double> reals;
  int count() const { return static_cast<int>(2 * pairs.size() + reals.size()); }
};

// Partial-fraction basis at every line: 1/(s - p) for a real pole, 1/(s - p) + 1/(s - p*) and
// j/(s - p) - j/(s - p*) for a pair, then a constant (lines x (count + 1)).
Eigen::MatrixXcd partial_fractions(const Problem& p, const Poles& poles) {
  Eigen::MatrixXcd x(p.lines(), poles.count() + 1);
  for (int l = 0; l < p.lines(); ++l) {
    int c = 0;
    for (const Complex& q : poles.pairs) {
      const Complex f1 = 1.0 / (p.s(l) - q);
      const Complex f2 = 1.0 / (p.s(l) - std::conj(q));
      x(l, c++) = f1 + f2;
      x(l, c++) = kJ * f1 - kJ * f2;
    }
    for (double q : poles.reals) x(l, c++) = 1.0 / (p.s(l) - q);
    x(l, c) = 1.0;
  }
  return x;
}

// One relocation: the relaxed sigma function fitted over every channel (each channel's own
// residues projected out by a QR of its rows), its zeros the new poles (unstable ones
// reflected). None when the equations cannot be solved.
std::optional<Poles> relocate(const Problem& p, const Poles& poles,
                              const Eigen::VectorXd& channel_weights) {
  const int n = poles.count() + 1;
  const Eigen::MatrixXcd phi = partial_fractions(p, poles);
  const int channels = static_cast<int>(p.h.cols());
  Eigen::MatrixXd system = Eigen::MatrixXd::Zero(channels * n + 1, n);
  for (int c = 0; c < channels; ++c) {
    const Eigen::VectorXd wt = channel_weights(c) * p.weight.col(c);
    Eigen::MatrixXcd row(p.lines(), 2 * n);
    row.leftCols(n) = wt.asDiagonal() * phi;
    row.rightCols(n) = (wt.cwiseProduct(p.h.col(c).real()).cast<Complex>() +
                        kJ * wt.cwiseProduct(p.h.col(c).imag()).cast<Complex>())
                           .asDiagonal() *
                       (-phi);
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(stacked(row));
    // R22 of R = [R11 R12; 0 R22]: the equations left for sigma once the channel's own
    // residues are eliminated (its strictly lower part is zero, not Householder vectors).
    system.block(c * n, 0, n, n) =
        qr.matrixQR().block(n, n, n, n).triangularView<Eigen::Upper>().toDenseMatrix();
  }
  // Relaxation (Gustavsen 2006): the real part of sigma summed over the lines is fixed, so the
  // trivial solution sigma = 0 is excluded without fixing sigma's constant to 1.
  const double level = system.topRows(channels * n).norm() / std::max(1, p.lines());
  system.row(channels * n) = level * phi.real().colwise().sum();
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(channels * n + 1);
  rhs(channels * n) = level * p.lines();
  const Eigen::VectorXd sigma = internal::scaled_least_squares(system, rhs).coefficients;
  if (!sigma.allFinite()) return std::nullopt;
  double d = sigma(n - 1);
  if (std::abs(d) < 1e-8) d = d < 0.0 ? -1e-8 : 1e-8;
  // Zeros of sigma: eigenvalues of A - b c' / d in the real form of the poles.
  const int m = poles.count();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(m);
  int at = 0;
  for (const Complex& q : poles.pairs) {
    a(at, at) = q.real();
    a(at, at + 1) = q.imag();
    a(at + 1, at) = -q.imag();
    a(at + 1, at + 1) = q.real();
    b(at) = 2.0;
    at += 2;
  }
  for (double q : poles.reals) {
    a(at, at) = q;
    b(at) = 1.0;
    ++at;
  }
  const Eigen::MatrixXd z = a - b * sigma.head(m).transpose() / d;
  if (!z.allFinite()) return std::nullopt;
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(z, false);
  if (eig.info() != Eigen::Success) return std::nullopt;
  Poles next;
  for (Eigen::Index q = 0; q < eig.eigenvalues().size(); ++q) {
    Complex e = eig.eigenvalues()(q);
    e = {-std::abs(e.real()), e.imag()};
    if (e.imag() > 0.0) {
      next.pairs.push_back(e);
    } else if (e.imag() == 0.0) {
      next.reals.push_back(e.real());
    }
  }
  if (next.count() != m) return std::nullopt;
  return next;
}

double pole_change(const Poles& x, const Poles& y) {
  if (x.pairs.size() != y.pairs.size() || x.reals.size() != y.reals.size()) return 1.0;
  const auto sorted = [](const Poles& p) {
    std::vector<Complex> v = p.pairs;
    for (double r : p.reals) v.emplace_back(r, 0.0);
    std::sort(v.begin(), v.end(), [](Complex a, Complex b) {
      return std::abs(a) != std::abs(b) ? std::abs(a) < std::abs(b) : a.imag() < b.imag();
    });
    return v;
  };
  const std::vector<Complex> a = sorted(x);
  const std::vector<Complex> b = sorted(y);
  double change = 0.0;
  for (size_t q = 0; q < a.size(); ++q)
    change = std::max(change, std::abs(a[q] - b[q]) / std::abs(b[q]));
  return change;
}

// Lightly damped pairs spread evenly over the band (Gustavsen & Semlyen's start), and a real
// pole at the top of the band when the count is odd.
Poles initial_poles(const Problem& p, int count) {
  Poles poles;
  // A line at 0 rad/s (an analyser's DC line) would put a start pole at the origin.
  const double lo = p.w(0) > 0.0 ? p.w(0) : p.w(std::min(1, p.lines() - 1));
  const double hi = p.w(p.lines() - 1);
  const int pairs = count / 2;
  for (int q = 0; q < pairs; ++q) {
    const double beta = pairs == 1 ? 0.5 * (lo + hi) : lo + (hi - lo) * q / (pairs - 1.0);
    poles.pairs.emplace_back(-beta / 100.0, beta);
  }
  if (count % 2 == 1) poles.reals.push_back(-hi);
  return poles;
}

struct Start {
  Poles poles;
  int iterations = 0;
  bool converged = false;
};

// `progress(k)` is called as relocation k starts.
Start vector_fitting(const Problem& p, int count, int max_iterations,
                     const std::function<void(int)>& progress) {
  Eigen::VectorXd channel_weights(p.h.cols());
  for (Eigen::Index c = 0; c < p.h.cols(); ++c) {
    const double size = p.weight.col(c).cwiseProduct(p.h.col(c).cwiseAbs()).norm();
    channel_weights(c) = size > 0.0 ? 1.0 / size : 1.0;
  }
  Start start{initial_poles(p, count), 0, false};
  while (start.iterations < max_iterations) {
    progress(start.iterations + 1);
    const std::optional<Poles> next = relocate(p, start.poles, channel_weights);
    if (!next) break;
    ++start.iterations;
    const double change = pole_change(*next, start.poles);
    start.poles = *next;
    if (change < 1e-12) {
      start.converged = true;
      break;
    }
  }
  return start;
}

// The poles grouped into the submodels, from the slowest up: each pair into the first
// submodel with room for it whole, each real pole into the first with room (preferring one with
// an odd number of places left). A pair that finds no room for itself becomes two real poles
// at its magnitude. Each submodel's A_i = prod (1 - s / p).
// The FRF fit's own advice where the lines do not determine the modes.
constexpr std::string_view kBandAdvice =
    "a band (--band) holding every mode with lines on both sides of its peak";

// The result when the start cannot stand in anti-monic denominators (1 + a p cannot hold a
// pole at the origin or at infinity): a numerical outcome of the start, with more poles than
// the lines show, so a verdict, not an exception.
FrfMatrixFitResult unusable_start(FrfMatrixFitResult result, Eigen::Index lines) {
  result.termination = Termination::no_solution;
  result.message = "vector fitting placed a pole at the origin or at infinity";
  result.verdict.fail("the vector-fitting start placed a pole at the origin or at infinity: the " +
                          std::to_string(lines) +
                          " lines do not show as many modes as the structure has",
                      {verdict_advice::lower_order, kBandAdvice});
  return result;
}

// Whether every start pole can stand in an anti-monic denominator 1 + a1 p (+ a2 p^2): finite
// and away from the origin, so that -1/q and 1/|q|^2 are finite.
bool start_poles_usable(const Poles& poles) {
  const auto usable = [](Complex q) {
    return std::isfinite(q.real()) && std::isfinite(q.imag()) && std::isfinite(1.0 / std::norm(q));
  };
  for (const Complex& q : poles.pairs) {
    if (!usable(q)) return false;
  }
  for (double q : poles.reals) {
    if (!usable(Complex(q, 0.0))) return false;
  }
  return true;
}

std::vector<Eigen::VectorXd> group_poles(const Layout& layout, const Poles& poles) {
  struct Item {
    Complex pole;
    bool pair;
  };
  std::vector<Item> items;
  for (const Complex& q : poles.pairs) items.push_back({q, true});
  for (double q : poles.reals) items.push_back({Complex(q, 0.0), false});
  std::stable_sort(items.begin(), items.end(), [](const Item& x, const Item& y) {
    return std::abs(x.pole) < std::abs(y.pole);
  });
  std::vector<int> left;
  for (const SubmodelOrder& o : layout.orders) left.push_back(o.n);
  std::vector<Polynomial> a(static_cast<size_t>(layout.size()), Polynomial{1.0});
  const auto place_real = [&](double q) {
    int best = -1;
    for (int i = 0; i < layout.size(); ++i) {
      if (left[static_cast<size_t>(i)] == 0) continue;
      if (best < 0 ||
          (left[static_cast<size_t>(i)] % 2 == 1 && left[static_cast<size_t>(best)] % 2 == 0))
        best = i;
    }
    if (best < 0) return;
    a[static_cast<size_t>(best)] = a[static_cast<size_t>(best)] * Polynomial{1.0, -1.0 / q};
    --left[static_cast<size_t>(best)];
  };
  for (const Item& item : items) {
    if (!item.pair) {
      place_real(item.pole.real());
      continue;
    }
    int target = -1;
    for (int i = 0; i < layout.size() && target < 0; ++i) {
      if (left[static_cast<size_t>(i)] >= 2) target = i;
    }
    if (target < 0) {
      place_real(-std::abs(item.pole));
      place_real(-std::abs(item.pole));
      continue;
    }
    const double m2 = std::norm(item.pole);
    a[static_cast<size_t>(target)] =
        a[static_cast<size_t>(target)] * Polynomial{1.0, -2.0 * item.pole.real() / m2, 1.0 / m2};
    left[static_cast<size_t>(target)] -= 2;
  }
  std::vector<Eigen::VectorXd> result;
  for (const Polynomial& q : a) result.push_back(q.coefficients());
  return result;
}

// ---- Levenberg-Marquardt on all parameters ----

// Output j's Jacobian of the weighted residuals [Re; Im] (rows: input k, line l) in
// [a of every submodel, output j's numerator block].
Eigen::MatrixXd output_jacobian(const Layout& layout, const Problem& p, const Parameters& theta,
                                const Eigen::MatrixXcd& inv, int j) {
  const int lines = p.lines();
  Eigen::MatrixXcd jac =
      Eigen::MatrixXcd::Zero(lines * layout.inputs, layout.a_count + layout.u_count);
  for (int k = 0; k < layout.inputs; ++k) {
    const int channel = j * layout.inputs + k;
    for (int i = 0; i < layout.size(); ++i) {
      const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
      Eigen::VectorXd b(o.m + 1);
      for (int r = 0; r <= o.m; ++r) b(r) = theta.u(layout.u_column(i, k, r), j);
      for (int l = 0; l < lines; ++l) {
        const Complex s = p.s(l);
        const Complex v = inv(l, i);
        const double wt = p.weight(l, channel);
        const Complex bv = horner(b, s) * v * v * wt;
        Complex sq = s;
        for (int q = 1; q <= o.n; ++q, sq *= s) {
          jac(k * lines + l, layout.a_at[static_cast<size_t>(i)] + q - 1) = bv * sq;
        }
        Complex sr = 1.0;
        for (int r = 0; r <= o.m; ++r, sr *= s) {
          jac(k * lines + l, layout.a_count + layout.u_column(i, k, r)) = -wt * sr * v;
        }
      }
    }
    if (layout.direct) {
      for (int l = 0; l < lines; ++l) {
        jac(k * lines + l, layout.a_count + layout.d_at + k) = -p.weight(l, channel);
      }
    }
  }
  return stacked(jac);
}

// Output j's weighted residuals in the Jacobian's row order.
Eigen::VectorXd output_residual(const Layout& layout, const Eigen::MatrixXcd& e, int j) {
  const Eigen::Index lines = e.rows();
  Eigen::VectorXcd v(lines * layout.inputs);
  for (int k = 0; k < layout.inputs; ++k)
    v.segment(k * lines, lines) = e.col(j * layout.inputs + k);
  Eigen::VectorXd r(2 * v.size());
  r << v.real(), v.imag();
  return r;
}

struct Normal {
  Eigen::MatrixXd aa;               // a_count x a_count
  std::vector<Eigen::MatrixXd> au;  // per output, a_count x u_count
  std::vector<Eigen::MatrixXd> uu;  // per output, u_count x u_count
  Eigen::VectorXd ga;
  std::vector<Eigen::VectorXd> gu;
};

Normal normal_equations(const Layout& layout, const Problem& p, const Parameters& theta,
                        const Eigen::MatrixXcd& e) {
  const Eigen::MatrixXcd inv = inverse_denominators(p, theta.a);
  Normal n;
  const int pa = layout.a_count;
  n.aa = Eigen::MatrixXd::Zero(pa, pa);
  n.ga = Eigen::VectorXd::Zero(pa);
  for (int j = 0; j < layout.outputs; ++j) {
    const Eigen::MatrixXd jac = output_jacobian(layout, p, theta, inv, j);
    const Eigen::VectorXd r = output_residual(layout, e, j);
    const Eigen::MatrixXd ja = jac.leftCols(pa);
    const Eigen::MatrixXd ju = jac.rightCols(layout.u_count);
    n.aa += ja.transpose() * ja;
    n.au.push_back(ja.transpose() * ju);
    n.uu.push_back(ju.transpose() * ju);
    n.ga += ja.transpose() * r;
    n.gu.push_back(ju.transpose() * r);
  }
  return n;
}

// The damped Gauss-Newton step for the denominators, (N + lambda diag N) delta = -g with the
// numerators eliminated output by output (Schur complement). None when singular.
std::optional<Eigen::VectorXd> denominator_step(const Normal& n, double lambda) {
  const auto damped = [lambda](const Eigen::MatrixXd& m) {
    Eigen::MatrixXd d = m;
    for (Eigen::Index q = 0; q < m.rows(); ++q) {
      d(q, q) += lambda * m(q, q) + 1e-300;
    }
    return d;
  };
  Eigen::MatrixXd s = damped(n.aa);
  Eigen::VectorXd r = n.ga;
  for (size_t j = 0; j < n.uu.size(); ++j) {
    const Eigen::MatrixXd m = damped(n.uu[j]);
    const Eigen::VectorXd scale = m.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
    const Eigen::MatrixXd ms = scale.asDiagonal() * m * scale.asDiagonal();
    const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(ms);
    const Eigen::MatrixXd x =
        scale.asDiagonal() * cod.solve(scale.asDiagonal() * n.au[j].transpose());
    const Eigen::VectorXd y = scale.asDiagonal() * cod.solve(scale.asDiagonal() * n.gu[j]);
    s -= n.au[j] * x;
    r -= n.au[j] * y;
  }
  const Eigen::VectorXd scale = s.diagonal().cwiseAbs().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd ss = scale.asDiagonal() * s * scale.asDiagonal();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(ss);
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  const Eigen::VectorXd delta = -(scale.asDiagonal() * ldlt.solve(scale.asDiagonal() * r));
  if (!delta.allFinite()) return std::nullopt;
  return delta;
}

std::vector<Eigen::VectorXd> stepped(const Layout& layout, const std::vector<Eigen::VectorXd>& a,
                                     const Eigen::VectorXd& delta) {
  std::vector<Eigen::VectorXd> next = a;
  for (int i = 0; i < layout.size(); ++i) {
    for (int q = 1; q <= layout.orders[static_cast<size_t>(i)].n; ++q) {
      next[static_cast<size_t>(i)](q) += delta(layout.a_at[static_cast<size_t>(i)] + q - 1);
    }
  }
  return next;
}

double relative_change(const std::vector<Eigen::VectorXd>& x,
                       const std::vector<Eigen::VectorXd>& y) {
  double change = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    for (Eigen::Index q = 1; q < x[i].size(); ++q) {
      change = std::max(change, std::abs(x[i](q) - y[i](q)) / std::max(std::abs(y[i](q)), 1e-300));
    }
  }
  return change;
}

struct Refined {
  Parameters theta;
  double cost = 0.0;
  int iterations = 0;
  Termination termination = Termination::iteration_limit;
  std::string message;
};

// `progress(k)` is called as iteration k starts.
Refined levenberg_marquardt(const Layout& layout, const Problem& p, Parameters theta,
                            int max_iterations, double tolerance,
                            const std::function<void(int)>& progress) {
  Refined run;
  Eigen::MatrixXcd e = residuals(layout, p, theta);
  double cost = cost_of(e);
  double lambda = 1e-3;
  int rejected = 0;
  while (run.iterations < max_iterations) {
    if (cost == 0.0) {
      run.termination = Termination::converged;
      run.message = "the model reproduces the FRF exactly";
      break;
    }
    ++run.iterations;
    progress(run.iterations);
    const Normal n = normal_equations(layout, p, theta, e);
    bool accepted = false;
    while (!accepted && lambda < 1e12) {
      const std::optional<Eigen::VectorXd> delta = denominator_step(n, lambda);
      if (delta) {
        Parameters next;
        next.a = stepped(layout, theta.a, *delta);
        if (stable_and_finite(next.a)) {
          next.u = fit_numerators(layout, p, next.a);
          const Eigen::MatrixXcd e_next = residuals(layout, p, next);
          const double c = cost_of(e_next);
          if (std::isfinite(c) && c <= cost) {
            const double change = relative_change(next.a, theta.a);
            const double decrease = (cost - c) / cost;
            theta = std::move(next);
            e = e_next;
            cost = c;
            lambda = std::max(lambda / 4.0, 1e-12);
            accepted = true;
            rejected = 0;
            if (change < tolerance) {
              run.termination = Termination::converged;
              run.message = internal::concat("converged after ", run.iterations,
                                             " iterations (relative change of the denominators ",
                                             format_brief(change), ")");
            } else if (decrease <= kFlatCost) {
              run.termination = Termination::converged;
              run.message = internal::concat(
                  "converged after ", run.iterations,
                  " iterations (the cost no longer decreases; last relative change of the "
                  "denominators ",
                  format_brief(change), ")");
            }
            break;
          }
        }
      }
      lambda *= 8.0;
      ++rejected;
    }
    if (run.termination == Termination::converged) break;
    if (!accepted) {
      // No damped step lowers the cost: a stationary point to rounding.
      run.termination = Termination::converged;
      run.message = internal::concat("converged after ", run.iterations,
                                     " iterations (no step lowers the cost further)");
      break;
    }
  }
  if (run.termination == Termination::iteration_limit) {
    run.message = internal::concat("stopped at the iteration limit (", max_iterations,
                                   " iterations) before the denominators settled");
  }
  (void)rejected;
  run.theta = std::move(theta);
  run.cost = cost;
  return run;
}

// ---- Covariance ----

// Sandwich R^-1 Q R^-1 over the whole parameter vector. R = sum_j J_j' J_j (the outputs are
// fitted alike); the outputs' weighted FRF errors are taken as correlated with each other at a
// line (their covariance Sigma estimated from the residuals at the same line and input, real
// and imaginary parts alike) and independent across lines and inputs, so
// Q = sum_jl Sigma_jl J_j' J_l. Also the reciprocal condition of the scaled R.
Eigen::MatrixXd covariance_of(const Layout& layout, const Problem& p, const Parameters& theta,
                              const Eigen::MatrixXcd& e, double* reciprocal_condition) {
  const int pa = layout.a_count;
  const int pu = layout.u_count;
  const int per = pa + pu;
  const int n_y = layout.outputs;
  const int total = layout.parameters();
  const Eigen::MatrixXcd inv = inverse_denominators(p, theta.a);
  const Eigen::Index rows = 2 * static_cast<Eigen::Index>(p.lines()) * layout.inputs;
  // Every output's Jacobian side by side, and its residuals (the same row order in each).
  Eigen::MatrixXd jac(rows, static_cast<Eigen::Index>(n_y) * per);
  Eigen::MatrixXd res(rows, n_y);
  for (int j = 0; j < n_y; ++j) {
    jac.middleCols(static_cast<Eigen::Index>(j) * per, per) =
        output_jacobian(layout, p, theta, inv, j);
    res.col(j) = output_residual(layout, e, j);
  }
  const double all = static_cast<double>(rows) * n_y;
  const double dof = all / std::max(1.0, all - total);
  const Eigen::MatrixXd sigma = res.transpose() * res / static_cast<double>(rows) * dof;
  Eigen::MatrixXd jj = Eigen::MatrixXd::Zero(jac.cols(), jac.cols());
  jj.selfadjointView<Eigen::Lower>().rankUpdate(jac.transpose());
  jj = jj.selfadjointView<Eigen::Lower>();
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(total, total);
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(total, total);
  const auto at = [&](int j) { return pa + j * pu; };
  for (int j = 0; j < n_y; ++j) {
    for (int l = 0; l < n_y; ++l) {
      const auto m = jj.block(static_cast<Eigen::Index>(j) * per,
                              static_cast<Eigen::Index>(l) * per, per, per);
      const double c = sigma(j, l);
      q.topLeftCorner(pa, pa) += c * m.topLeftCorner(pa, pa);
      q.block(0, at(l), pa, pu) += c * m.topRightCorner(pa, pu);
      q.block(at(j), 0, pu, pa) += c * m.bottomLeftCorner(pu, pa);
      q.block(at(j), at(l), pu, pu) += c * m.bottomRightCorner(pu, pu);
      if (j == l) {
        r.topLeftCorner(pa, pa) += m.topLeftCorner(pa, pa);
        r.block(0, at(j), pa, pu) = m.topRightCorner(pa, pu);
        r.block(at(j), 0, pu, pa) = m.bottomLeftCorner(pu, pa);
        r.block(at(j), at(j), pu, pu) = m.bottomRightCorner(pu, pu);
      }
    }
  }
  const Eigen::VectorXd scale = r.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd rs = scale.asDiagonal() * r * scale.asDiagonal();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(rs);
  *reciprocal_condition = ldlt.info() == Eigen::Success ? ldlt.rcond() : 0.0;
  const Eigen::MatrixXd r_inv = ldlt.solve(Eigen::MatrixXd::Identity(total, total));
  const Eigen::MatrixXd qs = scale.asDiagonal() * q * scale.asDiagonal();
  return scale.asDiagonal() * (r_inv * qs * r_inv) * scale.asDiagonal();
}

// The model of the parameters (the layout's, shared with mimo_srivc).
MimoAdditiveModel to_model(const Layout& layout, const Parameters& theta) {
  std::vector<Polynomial> a;
  for (const Eigen::VectorXd& c : theta.a) a.emplace_back(c);
  return internal::model_from_columns(layout, a, theta.u);
}

// Submodels of equal orders listed from the slowest up (as mimo_srivc lists them).
Parameters slowest_first(const Layout& layout, Parameters theta) {
  for (const SubmodelOrder& o : layout.orders) {
    if (o.n != layout.orders[0].n || o.m != layout.orders[0].m) return theta;
  }
  std::vector<int> order(static_cast<size_t>(layout.size()));
  for (int i = 0; i < layout.size(); ++i) order[static_cast<size_t>(i)] = i;
  const auto speed = [&](int i) {
    const Eigen::VectorXd& a = theta.a[static_cast<size_t>(i)];
    return std::pow(std::abs(a(a.size() - 1)), -1.0 / static_cast<double>(a.size() - 1));
  };
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return speed(x) < speed(y); });
  Parameters sorted = theta;
  for (int i = 0; i < layout.size(); ++i) {
    const int from = order[static_cast<size_t>(i)];
    sorted.a[static_cast<size_t>(i)] = theta.a[static_cast<size_t>(from)];
    for (int k = 0; k < layout.inputs; ++k) {
      for (int r = 0; r <= layout.orders[0].m; ++r) {
        sorted.u.row(layout.u_column(i, k, r)) = theta.u.row(layout.u_column(from, k, r));
      }
    }
  }
  return sorted;
}

Problem problem_of(const MimoFrf& frf, const FrfMatrixFitOptions& options) {
  const int n_y = frf.output_count();
  const int n_u = frf.input_count();
  std::vector<int> kept;
  for (Eigen::Index l = 0; l < frf.frequencies.size(); ++l) {
    const double w = frf.frequencies(l);
    if (w >= options.min_frequency &&
        (options.max_frequency <= 0.0 || w <= options.max_frequency)) {
      kept.push_back(static_cast<int>(l));
    }
  }
  Problem p;
  const auto lines = static_cast<Eigen::Index>(kept.size());
  p.w.resize(lines);
  p.h.resize(lines, n_y * n_u);
  p.weight = Eigen::MatrixXd::Ones(lines, n_y * n_u);
  p.uniform = options.weighting == FrfWeighting::uniform;
  for (Eigen::Index l = 0; l < lines; ++l) {
    const auto at = static_cast<size_t>(kept[static_cast<size_t>(l)]);
    p.w(l) = frf.frequencies(static_cast<Eigen::Index>(at));
    for (int j = 0; j < n_y; ++j) {
      for (int k = 0; k < n_u; ++k) {
        p.h(l, j * n_u + k) = frf.response[at](j, k);
        if (!p.uniform) p.weight(l, j * n_u + k) = 1.0 / std::sqrt(frf.variance[at](j, k));
      }
    }
  }
  p.s = kJ * p.w.cast<Complex>();
  return p;
}

// Every entry must respond somewhere, and the response's magnitudes must leave its sums of
// squares finite (the fit percentages and the cost are such sums).
void check_frf_magnitudes(const MimoFrf& frf) {
  double largest = 0.0;
  for (int i = 0; i < frf.output_count(); ++i) {
    for (int j = 0; j < frf.input_count(); ++j) {
      double entry = 0.0;
      for (const Eigen::MatrixXcd& g : frf.response) entry = std::max(entry, std::abs(g(i, j)));
      require(entry > 0.0, "frf_matrix_fit: entry ", frf.output_names[static_cast<size_t>(i)], "/",
              frf.input_names[static_cast<size_t>(j)],
              " is zero at every line; a response of zeros has no modes (leave that entry out)");
      largest = std::max(largest, entry);
    }
  }
  require(
      largest >= internal::kSmallestSampleMagnitude && largest <= internal::kLargestSampleMagnitude,
      "frf_matrix_fit: the FRF reaches a magnitude of ", largest,
      "; ctid fits responses whose largest magnitude lies within 1e-100..1e+100, so that "
      "their sums of squares stay finite: rescale it (give it other units)");
}

void check_frf(const MimoFrf& frf, const FrfMatrixFitOptions& options) {
  const Eigen::Index lines = frf.frequencies.size();
  const int n_y = frf.output_count();
  const int n_u = frf.input_count();
  require(n_y >= 1 && n_u >= 1, "frf_matrix_fit: the FRF names ", n_y, " outputs and ", n_u,
          " inputs; it needs at least one of each");
  require(static_cast<Eigen::Index>(frf.response.size()) == lines,
          "frf_matrix_fit: ", frf.response.size(), " response matrices for ", lines,
          " frequencies");
  for (Eigen::Index l = 0; l < lines; ++l) {
    const auto at = static_cast<size_t>(l);
    require(std::isfinite(frf.frequencies(l)) && frf.frequencies(l) >= 0.0,
            "frf_matrix_fit: frequency ", l + 1, " is ", format_brief(frf.frequencies(l)),
            " rad/s; every frequency must be finite and not negative");
    require(l == 0 || frf.frequencies(l) > frf.frequencies(l - 1), "frf_matrix_fit: frequency ",
            l + 1, " (", format_brief(frf.frequencies(l)),
            " rad/s) does not exceed the one before (",
            format_brief(l > 0 ? frf.frequencies(l - 1) : 0.0),
            " rad/s); the frequencies must increase");
    require(frf.response[at].rows() == n_y && frf.response[at].cols() == n_u,
            "frf_matrix_fit: the response at frequency ", l + 1, " is ", frf.response[at].rows(),
            " x ", frf.response[at].cols(), " but the FRF names ", n_y, " outputs and ", n_u,
            " inputs");
    require(frf.response[at].allFinite(), "frf_matrix_fit: the response at frequency ", l + 1, " (",
            format_brief(frf.frequencies(l)), " rad/s) is not finite");
  }
  check_frf_magnitudes(frf);
  if (options.weighting == FrfWeighting::variance) {
    require(static_cast<Eigen::Index>(frf.variance.size()) == lines,
            "frf_matrix_fit: weighting 'variance' needs the FRF's variance at every line, but it "
            "has ",
            frf.variance.size(), " for ", lines, " lines");
    for (Eigen::Index l = 0; l < lines; ++l) {
      const Eigen::MatrixXd& v = frf.variance[static_cast<size_t>(l)];
      require(v.rows() == n_y && v.cols() == n_u && v.allFinite() && v.minCoeff() > 0.0,
              "frf_matrix_fit: weighting 'variance' needs a finite, positive variance of every "
              "entry, but the variance at frequency ",
              l + 1, " (", format_brief(frf.frequencies(l)), " rad/s) is not");
    }
  }
}

void check_orders(const std::vector<SubmodelOrder>& orders, bool direct) {
  require(!orders.empty(), "frf_matrix_fit: the structure has no submodels");
  for (size_t i = 0; i < orders.size(); ++i) {
    orders[i].validate();
    require(orders[i].n == 1 || orders[i].n == 2, "frf_matrix_fit: submodel ", i + 1,
            " has n = ", orders[i].n,
            " poles; the FRF fit takes first- and second-order submodels (n = 1 or 2)");
    require(orders[i].integrators == 0, "frf_matrix_fit: submodel ", i + 1,
            " has integrators, which the FRF fit does not take");
    require(orders[i].m <= orders[i].n, "frf_matrix_fit: submodel ", i + 1,
            " has m = ", orders[i].m, " > n = ", orders[i].n, "; the model must be proper");
    require(!(direct && orders[i].m == orders[i].n), "frf_matrix_fit: submodel ", i + 1,
            " is biproper (m = n) and a direct term is asked for too; the constant would be "
            "counted twice (use m < n with the direct term)");
  }
}

}  // namespace

void FrfMatrixFitOptions::validate() const {
  validate_fields(*this);
  require(max_frequency <= 0.0 || min_frequency < max_frequency,
          "FrfMatrixFitOptions: min_frequency ", format_brief(min_frequency),
          " rad/s is not below max_frequency ", format_brief(max_frequency), " rad/s");
}

std::vector<Eigen::MatrixXcd> mimo_frequency_response(const MimoAdditiveModel& model,
                                                      const Eigen::VectorXd& frequencies) {
  std::vector<Eigen::MatrixXcd> g;
  for (Eigen::Index l = 0; l < frequencies.size(); ++l) {
    const Complex s = kJ * frequencies(l);
    Eigen::MatrixXcd h = model.direct().cast<Complex>();
    if (h.size() == 0) h = Eigen::MatrixXcd::Zero(model.outputs(), model.inputs());
    for (const MimoSubmodel& sub : model.submodels()) {
      Complex den = horner(sub.a.coefficients(), s);
      for (int q = 0; q < sub.integrators; ++q) den *= s;
      const Complex inv = 1.0 / den;
      for (int j = 0; j < model.outputs(); ++j) {
        for (int k = 0; k < model.inputs(); ++k) {
          h(j, k) +=
              horner(sub.b[static_cast<size_t>(j * model.inputs() + k)].coefficients(), s) * inv;
        }
      }
    }
    if (model.has_input_delays()) {
      for (int k = 0; k < model.inputs(); ++k) h.col(k) *= std::exp(-s * model.input_delays()(k));
    }
    g.push_back(std::move(h));
  }
  return g;
}

FrfMatrixFitResult frf_matrix_fit(const MimoFrf& frf, const std::vector<SubmodelOrder>& orders,
                                  const FrfMatrixFitOptions& options,
                                  const std::optional<MimoAdditiveModel>& initial_model,
                                  const std::function<void(int, int)>& progress) {
  options.validate();
  check_orders(orders, options.direct_term);
  check_frf(frf, options);
  const Layout layout(orders, frf.input_count(), frf.output_count(), options.direct_term);
  const Problem p = problem_of(frf, options);
  const int per_channel = layout.a_count + layout.channel_columns();
  const int needed = std::max(layout.a_count + 2, (per_channel + 2) / 2);
  require(p.lines() >= needed, "frf_matrix_fit: ", p.lines(), " lines",
          options.min_frequency > 0.0 || options.max_frequency > 0.0 ? " in the band" : "",
          " are too few for ", layout.a_count, " poles and ", layout.channel_columns(),
          " numerator coefficients per channel; give at least ", needed,
          " lines or fewer submodels");

  FrfMatrixFitResult result;
  result.lines = p.lines();
  // One count over the vector-fitting relocations (when there is no start) and the
  // Levenberg-Marquardt iterations, against the most each may run.
  const int relocations = initial_model ? 0 : options.start_iterations;
  const int total = relocations + options.max_iterations;
  const auto report = [&](int offset) {
    return std::function<void(int)>([&progress, offset, total](int k) {
      if (progress) progress(offset + k, total);
    });
  };
  Parameters theta;
  if (initial_model) {
    internal::check_initial_model(layout, *initial_model, "frf_matrix_fit", "the FRF");
    for (int i = 0; i < layout.size(); ++i) {
      theta.a.push_back((*initial_model)[i].a.coefficients());
    }
  } else {
    const Start start = vector_fitting(p, layout.a_count, options.start_iterations, report(0));
    result.start_iterations = start.iterations;
    if (!start_poles_usable(start.poles)) return unusable_start(std::move(result), p.lines());
    theta.a = group_poles(layout, start.poles);
  }
  theta.u = fit_numerators(layout, p, theta.a);

  Refined run = levenberg_marquardt(layout, p, std::move(theta), options.max_iterations,
                                    options.tolerance, report(relocations));
  result.termination = run.termination;
  result.message = run.message;
  result.iterations = run.iterations;
  const Parameters best = slowest_first(layout, std::move(run.theta));
  const Eigen::MatrixXcd e = residuals(layout, p, best);
  const Eigen::MatrixXcd g = response_of(layout, p, best);

  result.fit_percent.resize(layout.outputs, layout.inputs);
  result.noise_variance.resize(layout.outputs);
  for (int j = 0; j < layout.outputs; ++j) {
    double sum = 0.0;
    for (int k = 0; k < layout.inputs; ++k) {
      const int c = j * layout.inputs + k;
      const double size = p.h.col(c).norm();
      result.fit_percent(j, k) = size > 0.0 ? 100.0 * (1.0 - (p.h.col(c) - g.col(c)).norm() / size)
                                            : std::numeric_limits<double>::quiet_NaN();
      sum += e.col(c).squaredNorm();
    }
    result.noise_variance(j) = sum / (static_cast<double>(p.lines()) * layout.inputs);
  }

  const MimoAdditiveModel model = to_model(layout, best);
  std::vector<Complex> poles;
  for (const MimoSubmodel& sub : model.submodels()) {
    const Eigen::VectorXcd r = sub.a.roots();
    poles.insert(poles.end(), r.data(), r.data() + r.size());
  }
  check_finite(result.verdict, result.fit_percent.allFinite(), "the fit");
  check_stable(result.verdict, Eigen::Map<const Eigen::VectorXcd>(
                                   poles.data(), static_cast<Eigen::Index>(poles.size())));
  for (int j = 0; j < layout.outputs; ++j) {
    for (int k = 0; k < layout.inputs; ++k) {
      if (!(result.fit_percent(j, k) >= 0.0)) {
        result.verdict.fail(
            internal::concat("channel ", frf.output_names[static_cast<size_t>(j)], "/",
                             frf.input_names[static_cast<size_t>(k)], " is fitted at ",
                             format_brief(result.fit_percent(j, k)), " %, worse than zero"),
            {verdict_advice::better_start, verdict_advice::lower_order});
      }
    }
  }
  if (options.compute_covariance) {
    double reciprocal_condition = 0.0;
    result.covariance = covariance_of(layout, p, best, e, &reciprocal_condition);
    // In the FRF fit's own terms (issue 35): the Jacobian of the weighted residuals over the
    // lines, not the instrument-regressor equations of a time-domain estimator.
    if (!std::isnan(reciprocal_condition) &&
        !(reciprocal_condition >= verdict_thresholds::reciprocal_condition)) {
      result.verdict.fail(internal::concat("the FRF fit's Jacobian over the ", p.lines(),
                                           " lines is numerically singular (reciprocal condition ",
                                           format_brief(reciprocal_condition),
                                           "): the lines do not determine every modal parameter"),
                          {verdict_advice::lower_order, kBandAdvice});
    }
  }
  result.modes = mimo_modes(model, orders, result.covariance);
  for (std::size_t i = 0; i < result.modes.size(); ++i) {
    const MimoMode& mode = result.modes[i];
    const std::string name = internal::concat("mode ", i + 1);  // as ctid fit-frf prints it
    check_standard_errors(result.verdict, {name + " natural frequency", name + " damping ratio"},
                          Eigen::Vector2d(mode.natural_frequency, mode.damping_ratio),
                          Eigen::Vector2d(mode.natural_frequency_se, mode.damping_ratio_se));
  }
  if (result.start_iterations > 0) {
    result.message += internal::concat(", from a vector-fitting start of ", result.start_iterations,
                                       " pole relocations");
  }
  result.model = model;
  return result;
}

}  // namespace ctid
