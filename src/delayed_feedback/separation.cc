// Forward/feedback separation: Kronecker least squares (eqs. 19-21) and approximate GCD by
// observability SVD (eqs. 22-24).
#include "ctid/delayed_feedback/separation.h"

#include <ceres/ceres.h>

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "ctid/core/controllable_form.h"
#include "ctid/core/error.h"
#include "ctid/core/state_space.h"
#include "delayed_feedback/internal/ceres_solve.h"
#include "delayed_feedback/internal/loop_polynomials.h"

namespace ctid {
namespace {

void check(const Polynomial& alpha, const Polynomial& beta, int n, int m, const char* who) {
  require(n >= 1, who, ": forward order n must be >= 1, got ", n);
  require(m >= 1, who, ": feedback order m must be >= 1, got ", m);
  require(beta.degree() == n + m, who, ": beta must have degree n + m = ", n + m, ", got ",
          beta.degree());
  require(alpha.degree() < n + m, who, ": alpha must have degree < n + m = ", n + m, ", got ",
          alpha.degree());
}

// J's residuals for ρ = [a_F (n) | b_F (n) | a_H (m) | b_H (m)], all ascending; D_F and D_H
// monic. Coefficient vectors: α (q entries), β below s^q (q), γ (q - 1).
struct KroneckerResidual {
  Eigen::VectorXd alpha, beta, gamma;
  int n, m;
  template <typename T>
  bool operator()(T const* const* parameters, T* residual) const {
    const T* p = parameters[0];
    const int q = n + m;
    const internal::LoopPolynomials<T> poly = internal::loop_polynomials(p, n, m);
    const std::vector<T>& a = poly.alpha;
    const std::vector<T>& b = poly.beta;
    const std::vector<T>& g = poly.gamma;
    for (int i = 0; i < q; ++i) residual[i] = T(alpha(i)) - a[i];
    for (int i = 0; i < q; ++i) residual[q + i] = T(beta(i)) - b[i];
    for (int i = 0; i + 1 < q; ++i) residual[2 * q + i] = T(gamma(i)) - g[i];
    return true;
  }
};

// Convolution matrix: conv(x, b) = M x for x of length `len`.
Eigen::MatrixXd convolution_matrix(const Polynomial& b, int len, int rows) {
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(rows, len);
  for (int j = 0; j < len; ++j)
    for (int i = 0; i <= b.degree(); ++i)
      if (i + j < rows) c(i + j, j) = b.coefficient(i);
  return c;
}

Eigen::VectorXd pack(const TransferFunction& f, const TransferFunction& h, int n, int m) {
  const TransferFunction fn = f.normalized();
  const TransferFunction hn = h.normalized();
  Eigen::VectorXd p(2 * (n + m));
  p << internal::padded(fn.denominator(), n), internal::padded(fn.numerator(), n),
      internal::padded(hn.denominator(), m), internal::padded(hn.numerator(), m);
  return p;
}

TransferFunction unpack(const Eigen::VectorXd& p, int offset, int order) {
  Eigen::VectorXd den(order + 1);
  den << p.segment(offset, order), 1.0;
  return TransferFunction(Polynomial::trimmed(p.segment(offset + order, order)), Polynomial(den));
}

// Splits of the roots of β̂ into D_F (degree n) and D_H (degree m), conjugate pairs together.
std::vector<std::pair<Polynomial, Polynomial>> root_splits(const Polynomial& beta, int n) {
  const Eigen::VectorXcd roots = beta.roots();
  std::vector<Eigen::VectorXcd> units;
  std::vector<bool> used(static_cast<size_t>(roots.size()), false);
  for (Eigen::Index i = 0; i < roots.size(); ++i) {
    if (used[static_cast<size_t>(i)]) continue;
    used[static_cast<size_t>(i)] = true;
    const std::complex<double> r = roots(i);
    if (std::abs(r.imag()) <= 1e-8 * std::max(1.0, std::abs(r))) {
      units.push_back(Eigen::VectorXcd::Constant(1, std::complex<double>(r.real(), 0.0)));
      continue;
    }
    Eigen::Index partner = -1;
    double best = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < roots.size(); ++j) {
      if (used[static_cast<size_t>(j)]) continue;
      const double d = std::abs(roots(j) - std::conj(r));
      if (d < best) {
        best = d;
        partner = j;
      }
    }
    if (partner < 0) continue;
    used[static_cast<size_t>(partner)] = true;
    Eigen::VectorXcd pair(2);
    pair << r, std::conj(r);
    units.push_back(pair);
  }
  std::vector<std::pair<Polynomial, Polynomial>> splits;
  const size_t count = units.size();
  for (unsigned long mask = 0; mask < (1UL << count); ++mask) {
    int degree = 0;
    for (size_t i = 0; i < count; ++i)
      if (mask & (1UL << i)) degree += static_cast<int>(units[i].size());
    if (degree != n) continue;
    std::vector<std::complex<double>> f, h;
    for (size_t i = 0; i < count; ++i)
      for (Eigen::Index j = 0; j < units[i].size(); ++j)
        ((mask & (1UL << i)) ? f : h).push_back(units[i](j));
    splits.emplace_back(Polynomial::from_roots(Eigen::Map<Eigen::VectorXcd>(
                            f.data(), static_cast<Eigen::Index>(f.size()))),
                        Polynomial::from_roots(Eigen::Map<Eigen::VectorXcd>(
                            h.data(), static_cast<Eigen::Index>(h.size()))));
  }
  return splits;
}

struct Truncation {
  TransferFunction model{Polynomial{0.0}, Polynomial{1.0}};
  Eigen::VectorXd singular_values;
  double gap = 0.0;
  Polynomial cancelled;
};

// Keeps the `keep` most observable directions of the companion realisation (eq. 24).
Truncation truncate_observable(const Eigen::VectorXd& num, const Eigen::VectorXd& den_monic,
                               int keep) {
  const StateSpace s = controllable_form(num, den_monic);
  const Eigen::Index q = s.a.rows();
  Eigen::MatrixXd obs(q, q);
  Eigen::RowVectorXd row = s.c;
  for (Eigen::Index i = 0; i < q; ++i) {
    obs.row(i) = row;
    row = row * s.a;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(obs, Eigen::ComputeFullV);
  Truncation t;
  t.singular_values = svd.singularValues();
  const double next = t.singular_values(keep < q ? keep : q - 1);
  t.gap = keep < q ? (next > 0.0 ? t.singular_values(keep - 1) / next
                                 : std::numeric_limits<double>::infinity())
                   : std::numeric_limits<double>::infinity();
  const Eigen::MatrixXd v1 = svd.matrixV().leftCols(keep);
  StateSpace o;
  o.a = v1.transpose() * s.a * v1;
  o.b = v1.transpose() * s.b;
  o.c = s.c * v1;
  o.d = 0.0;
  t.model = TransferFunction::from_state_space(o).normalized();
  if (keep < q) {
    const Eigen::MatrixXd v2 = svd.matrixV().rightCols(q - keep);
    const Eigen::MatrixXd au = v2.transpose() * s.a * v2;
    t.cancelled = Polynomial::from_roots(au.eigenvalues());
  } else {
    t.cancelled = Polynomial{1.0};
  }
  return t;
}

}  // namespace

double kronecker_cost(const Polynomial& alpha, const Polynomial& beta, const Polynomial& gamma,
                      const TransferFunction& forward, const TransferFunction& feedback) {
  const int n = forward.denominator().degree();
  const int m = feedback.denominator().degree();
  const int q = n + m;
  KroneckerResidual r{internal::padded(alpha, q), internal::padded(beta, q),
                      internal::padded(gamma, q - 1), n, m};
  const Eigen::VectorXd p = pack(forward, feedback, n, m);
  Eigen::VectorXd res(3 * q - 1);
  const double* blocks[] = {p.data()};
  r(blocks, res.data());
  return res.squaredNorm();
}

GcdSeparationResult separate_approximate_gcd(const Polynomial& alpha, const Polynomial& beta,
                                             const Polynomial& gamma, int n, int m) {
  check(alpha, beta, n, m, "separate_approximate_gcd");
  const int q = n + m;
  require(alpha.degree() == q - 1, "separate_approximate_gcd: alpha must have degree n + m - 1 ",
          "= ", q - 1, " (a forward F of relative degree 1), got ", alpha.degree());
  const Eigen::VectorXd b = beta.monic().coefficients();
  const Truncation f = truncate_observable(internal::padded(alpha, q), b, n);
  // H̃ = γ̂/α̂ with α̂ made monic: order q - 1, keep m.
  const double lead = alpha.leading();
  const Truncation h =
      truncate_observable(internal::padded(gamma, q - 1) / lead, alpha.coefficients() / lead, m);
  GcdSeparationResult r;
  r.forward = f.model;
  r.feedback = h.model;
  r.forward_singular_values = f.singular_values;
  r.feedback_singular_values = h.singular_values;
  r.forward_gap = f.gap;
  r.feedback_gap = h.gap;
  r.cancelled_forward = f.cancelled;
  r.cancelled_feedback = h.cancelled;
  return r;
}

KroneckerSeparationResult separate_kronecker(const Polynomial& alpha, const Polynomial& beta,
                                             const Polynomial& gamma, int n, int m,
                                             const KroneckerSeparationOptions& options) {
  check(alpha, beta, n, m, "separate_kronecker");
  options.validate();
  const int q = n + m;
  const Eigen::VectorXd av = internal::padded(alpha, q), bv = internal::padded(beta.monic(), q),
                        gv = internal::padded(gamma, q - 1);

  std::vector<std::pair<std::string, Eigen::VectorXd>> starts;
  // With α̂ of low degree the GCD start is unavailable; the root splits remain.
  if (alpha.degree() == q - 1) {
    const GcdSeparationResult g = separate_approximate_gcd(alpha, beta, gamma, n, m);
    if (g.forward.denominator().degree() == n && g.feedback.denominator().degree() == m)
      starts.emplace_back("gcd", pack(g.forward, g.feedback, n, m));
  }
  if (options.multi_start || starts.empty()) {
    int index = 0;
    for (const auto& [df, dh] : root_splits(beta.monic(), n)) {
      // Numerators by linear least squares: α̂ ≈ N_F D_H, then γ̂ ≈ N_F N_H.
      const Eigen::VectorXd nf = convolution_matrix(dh, n, q).colPivHouseholderQr().solve(av);
      const Polynomial nfp = Polynomial::trimmed(nf);
      Eigen::VectorXd nh = Eigen::VectorXd::Zero(m);
      if (!nfp.is_zero()) nh = convolution_matrix(nfp, m, q - 1).colPivHouseholderQr().solve(gv);
      Eigen::VectorXd p(2 * q);
      p << internal::padded(df, n), nf, internal::padded(dh, m), nh;
      starts.emplace_back("roots split " + std::to_string(index++), p);
    }
  }
  KroneckerSeparationResult best;
  best.cost = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_p;
  for (auto& [name, p] : starts) {
    if (!p.allFinite()) continue;
    ceres::Problem problem;
    auto* cost = new ceres::DynamicAutoDiffCostFunction<KroneckerResidual, 8>(
        new KroneckerResidual{av, bv, gv, n, m});
    cost->AddParameterBlock(2 * q);
    cost->SetNumResiduals(3 * q - 1);
    problem.AddResidualBlock(cost, nullptr, p.data());
    internal::LeastSquaresSettings settings;
    settings.max_iterations = options.max_iterations;
    settings.function_tolerance = 1e-15;
    settings.gradient_tolerance = 1e-16;
    settings.parameter_tolerance = 1e-14;
    const internal::LeastSquaresOutcome outcome = internal::solve_least_squares(problem, settings);
    ++best.starts;
    const double j = outcome.sum_of_squares;
    best.candidates.push_back({name, unpack(p, 0, n), unpack(p, 2 * n, m), j});
    if (j < best.cost) {
      best.cost = j;
      best.best_start = name;
      static_cast<Outcome&>(best) = outcome;
      best_p = p;
    }
  }
  if (best_p.size() == 0) {
    best.termination = Termination::no_solution;
    best.message = "separate_kronecker: no usable start (non-finite estimates?)";
    return best;
  }
  best.forward = unpack(best_p, 0, n);
  best.feedback = unpack(best_p, 2 * n, m);
  return best;
}

}  // namespace ctid
