// Stage 1 of the two-stage method (decision 0043): the model of r -> u, an FIR by least
// squares or a discrete output-error model by simplified refined IV, its order by AIC.
#include "ctid/identification/two_stage.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <optional>
#include <string>

#include "ctid/core/error.h"
#include "ctid/core/polynomial.h"
#include "ctid/estimation/validation.h"
#include "internal/delayed_gram.h"

namespace ctid {
namespace {

constexpr int kSensitivityIterations = 20;
constexpr double kSensitivityTolerance = 1e-10;
// Below this reciprocal condition (of the column-scaled equations) the reference does not
// determine the parameters.
constexpr double kSensitivityReciprocalCondition = 1e-12;

// y = B(q^-1)/A(q^-1) x from rest, a = [1, a_1..a_n], b = [b_0..b_n].
Eigen::VectorXd filter_from_rest(const Eigen::VectorXd& b, const Eigen::VectorXd& a,
                                 const Eigen::VectorXd& x) {
  const Eigen::Index n = x.size();
  Eigen::VectorXd y(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    double v = 0.0;
    for (Eigen::Index i = 0; i < b.size() && i <= k; ++i) v += b(i) * x(k - i);
    for (Eigen::Index i = 1; i < a.size() && i <= k; ++i) v -= a(i) * y(k - i);
    y(k) = v;
  }
  return y;
}

// The normal equations of u_k = sum_{i<L} g_i r_{k-i} over k = 0..N-1, r = 0 before the
// record: the Gram matrix (L x L, exact in O(N L + L^2): delayed_gram) and the right-hand
// side.
struct FirNormalEquations {
  Eigen::MatrixXd gram;
  Eigen::VectorXd rhs;
  double output_energy = 0.0;
};

FirNormalEquations fir_normal_equations(const Eigen::VectorXd& r, const Eigen::VectorXd& u,
                                        int taps) {
  const Eigen::Index n = r.size();
  FirNormalEquations e;
  e.gram = internal::delayed_gram(r, 0, taps, r, 0, taps);
  e.rhs.resize(taps);
  for (Eigen::Index j = 0; j < taps; ++j) e.rhs(j) = u.segment(j, n - j).dot(r.head(n - j));
  e.output_energy = u.squaredNorm();
  return e;
}

// The taps of the leading taps x taps block, or empty when it is singular.
std::optional<Eigen::VectorXd> solve_fir(const FirNormalEquations& e, int taps) {
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(e.gram.topLeftCorner(taps, taps));
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > kSensitivityReciprocalCondition)) {
    return std::nullopt;
  }
  return Eigen::VectorXd(ldlt.solve(e.rhs.head(taps)));
}

// AIC N ln(RSS/N) + 2k; residuals below 1e-20 of the energy u^T u count as zero, so that
// noise-free records compare by the parameters alone.
double sensitivity_aic(double residual, double energy, double samples, int parameters) {
  if (!std::isfinite(residual)) return std::numeric_limits<double>::infinity();
  const double floor = energy * 1e-20 + std::numeric_limits<double>::min();
  return samples * std::log(std::max(residual, floor) / samples) + 2.0 * parameters;
}

SensitivityFit finished_fit(const SampledData& record, SensitivityModel model, int order,
                            Eigen::VectorXd a, Eigen::VectorXd b, bool converged) {
  SensitivityFit fit;
  fit.model = model;
  fit.order = order;
  fit.denominator = std::move(a);
  fit.numerator = std::move(b);
  fit.simulated_input = filter_from_rest(fit.numerator, fit.denominator, record.reference());
  fit.fit_percent = fit_percent(record.input(), fit.simulated_input);
  fit.aic = sensitivity_aic((record.input() - fit.simulated_input).squaredNorm(),
                            record.input().squaredNorm(), static_cast<double>(record.size()),
                            static_cast<int>(fit.numerator.size() + fit.denominator.size() - 1));
  fit.converged = converged;
  return fit;
}

std::optional<SensitivityFit> fir_fit(const SampledData& record, const FirNormalEquations& e,
                                      int taps) {
  std::optional<Eigen::VectorXd> g = solve_fir(e, taps);
  if (!g) return std::nullopt;
  return finished_fit(record, SensitivityModel::fir, taps, Eigen::VectorXd::Ones(1), std::move(*g),
                      true);
}

// The taps AIC prefers among 4, 8, 16, ... up to `largest` (scored on the same equations).
std::optional<SensitivityFit> fir_by_aic(const SampledData& record, int largest) {
  const FirNormalEquations e = fir_normal_equations(record.reference(), record.input(), largest);
  int best = 0;
  double best_score = std::numeric_limits<double>::infinity();
  for (int taps = std::min(4, largest);; taps = std::min(2 * taps, largest)) {
    if (const std::optional<Eigen::VectorXd> g = solve_fir(e, taps)) {
      const double score = sensitivity_aic(e.output_energy - e.rhs.head(taps).dot(*g),
                                           e.output_energy, record.size(), taps);
      if (score < best_score) {
        best_score = score;
        best = taps;
      }
    }
    if (taps == largest) break;
  }
  if (best == 0) return std::nullopt;
  return fir_fit(record, e, best);
}

// A(q^-1) with every root of q^n A(q^-1) outside the unit circle moved to 1/conj(z), so that
// 1/A can filter.
Eigen::VectorXd stable_denominator(const Eigen::VectorXd& a) {
  const Eigen::Index n = a.size() - 1;
  if (n == 0) return a;
  const Polynomial in_q(a.reverse().eval());  // ascending powers of q: a_n, ..., a_1, 1
  Eigen::VectorXcd roots = in_q.roots();
  bool moved = false;
  for (std::complex<double>& z : roots) {
    if (std::abs(z) > 1.0) {
      z = 1.0 / std::conj(z);
      moved = true;
    }
  }
  if (!moved) return a;
  return Polynomial::from_roots(roots).coefficients().reverse();
}

// Columns [-s(k-1) .. -s(k-n), r(k) .. r(k-n)] over k = 0..N-1 (zero before the record).
Eigen::MatrixXd lagged_columns(const Eigen::VectorXd& s, const Eigen::VectorXd& r, int n) {
  const Eigen::Index samples = s.size();
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(samples, 2 * n + 1);
  for (int i = 1; i <= n && i < samples; ++i) m.col(i - 1).tail(samples - i) = -s.head(samples - i);
  for (int i = 0; i <= n && i < samples; ++i) m.col(n + i).tail(samples - i) = r.head(samples - i);
  return m;
}

// One IV solve of uf = phi^T theta with instruments built from xf in place of uf, through the
// QR factor of the instruments (zeta^T phi theta = zeta^T uf with zeta = Q R is
// Q^T phi theta = Q^T uf), so that the condition of phi is not squared as in the normal
// equations: lightly damped maps at fast sampling need it.
std::optional<Eigen::VectorXd> iv_step(const Eigen::VectorXd& uf, const Eigen::VectorXd& rf,
                                       const Eigen::VectorXd& xf, int n) {
  const Eigen::MatrixXd phi = lagged_columns(uf, rf, n);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(lagged_columns(xf, rf, n));
  const Eigen::Index p = phi.cols();
  Eigen::MatrixXd both(phi.rows(), p + 1);
  both << phi, uf;
  both.applyOnTheLeft(qr.householderQ().transpose());
  const Eigen::MatrixXd projected = both.topLeftCorner(p, p);
  if (!projected.allFinite()) return std::nullopt;
  Eigen::VectorXd scale = projected.colwise().norm().transpose();
  if (!(scale.minCoeff() > 0.0)) return std::nullopt;
  scale = scale.cwiseInverse();
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(projected * scale.asDiagonal());
  if (!(lu.rcond() > kSensitivityReciprocalCondition)) return std::nullopt;
  return Eigen::VectorXd(scale.asDiagonal() * lu.solve(both.col(p).head(p)));
}

bool stable_denominator_roots(const Eigen::VectorXd& a) {
  return a.size() == 1 || Polynomial(a.reverse().eval()).roots().cwiseAbs().maxCoeff() < 1.0;
}

// The iterate with the smallest output error among those with a stable A (the iteration can
// wander on short or very noisy records), or empty when the equations are singular or no
// iterate is stable.
std::optional<SensitivityFit> rational_fit(const SampledData& record, int n) {
  const Eigen::VectorXd& r = record.reference();
  const Eigen::VectorXd& u = record.input();
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(1);
  // The ARX start: least squares, the regressors their own instruments.
  std::optional<Eigen::VectorXd> theta = iv_step(u, r, u, n);
  std::optional<Eigen::VectorXd> best;
  double best_residual = std::numeric_limits<double>::infinity();
  bool converged = false;
  for (int iteration = 0; theta && iteration <= kSensitivityIterations; ++iteration) {
    Eigen::VectorXd a(n + 1);
    a << 1.0, theta->head(n);
    const Eigen::VectorXd b = theta->tail(n + 1);
    if (stable_denominator_roots(a)) {
      const double residual = (u - filter_from_rest(b, a, r)).squaredNorm();
      if (residual < best_residual) {
        best_residual = residual;
        best = theta;
      }
    }
    if (converged || iteration == kSensitivityIterations) break;
    const Eigen::VectorXd prefilter = stable_denominator(a);
    const Eigen::VectorXd x = filter_from_rest(b, prefilter, r);
    const std::optional<Eigen::VectorXd> next =
        iv_step(filter_from_rest(one, prefilter, u), filter_from_rest(one, prefilter, r),
                filter_from_rest(one, prefilter, x), n);
    if (next) converged = (*next - *theta).norm() < kSensitivityTolerance * next->norm();
    theta = next;
  }
  if (!best) return std::nullopt;
  Eigen::VectorXd a(n + 1);
  a << 1.0, best->head(n);
  return finished_fit(record, SensitivityModel::rational, n, std::move(a), best->tail(n + 1),
                      converged);
}

std::optional<SensitivityFit> rational_by_aic(const SampledData& record, int largest) {
  std::optional<SensitivityFit> best;
  for (int n = 1; n <= largest && record.size() >= 10 * (2 * n + 1); ++n) {
    std::optional<SensitivityFit> fit = rational_fit(record, n);
    if (fit && std::isfinite(fit->aic) && (!best || fit->aic < best->aic)) best = std::move(fit);
  }
  return best;
}

std::optional<SensitivityFit> better(std::optional<SensitivityFit> a,
                                     std::optional<SensitivityFit> b) {
  if (!a) return b;
  if (!b) return a;
  return b->aic < a->aic ? b : a;
}

}  // namespace

void TwoStageOptions::check_relations(const std::string& path) const {
  require(sensitivity_model != SensitivityModel::automatic || sensitivity_order == 0, path,
          ".sensitivity_order is ", sensitivity_order,
          " but sensitivity_model is automatic; an order goes with sensitivity_model fir or "
          "rational (0 lets AIC choose)");
}

Eigen::VectorXd sensitivity_output(const SensitivityFit& fit, const Eigen::VectorXd& reference) {
  require(fit.denominator.size() >= 1 && fit.denominator(0) == 1.0,
          "sensitivity_output: the denominator must start with 1, got ",
          fit.denominator.size() == 0 ? std::string("none") : internal::concat(fit.denominator(0)));
  require(reference.allFinite(), "sensitivity_output: the reference has non-finite samples");
  return filter_from_rest(fit.numerator, fit.denominator, reference);
}

SensitivityFit fit_sensitivity(const SampledData& record, const TwoStageOptions& options) {
  options.validate();
  require(record.has_reference(),
          "the two-stage method fits the map from the reference r to the input u, but the record "
          "has no reference (give its column: --reference-column)");
  const int n = options.sensitivity_order;
  const int samples = record.size();
  std::optional<SensitivityFit> fit;
  switch (options.sensitivity_model) {
    case SensitivityModel::fir:
      require(n <= samples / 2, "TwoStageOptions.sensitivity_order is ", n, " FIR taps; the ",
              samples, "-sample record takes at most ", samples / 2);
      fit = n > 0 ? fir_fit(record, fir_normal_equations(record.reference(), record.input(), n), n)
                  : fir_by_aic(record, std::clamp(samples / 10, 1, kMaxAutomaticFirTaps));
      break;
    case SensitivityModel::rational:
      require(samples >= 10 * (2 * n + 1), "TwoStageOptions.sensitivity_order is ", n, "; its ",
              2 * n + 1, " parameters need at least ", 10 * (2 * n + 1),
              " samples and the record has ", samples);
      fit = n > 0 ? rational_fit(record, n) : rational_by_aic(record, kMaxAutomaticRationalOrder);
      break;
    case SensitivityModel::automatic:
      fit = better(fir_by_aic(record, std::clamp(samples / 10, 1, kMaxAutomaticFirTaps)),
                   rational_by_aic(record, kMaxAutomaticRationalOrder));
      break;
  }
  if (!fit) {
    throw InvalidArgument(internal::concat(
        "the ", enum_name(options.sensitivity_model), " model of r -> u",
        n > 0 ? internal::concat(" of order ", n) : std::string(),
        " cannot be fitted: its equations are singular, because the reference does not excite "
        "it (the two-stage method needs one that varies enough, e.g. noise, a PRBS or a "
        "multisine) or the order is higher than the map's (try a lower one)"));
  }
  return std::move(*fit);
}

namespace internal {

Eigen::MatrixXd delayed_gram(const Eigen::VectorXd& x, Eigen::Index dx, Eigen::Index rows,
                             const Eigen::VectorXd& y, Eigen::Index dy, Eigen::Index cols) {
  const Eigen::Index n = x.size();
  // sum_t x(t - a) y(t - b) over the samples where both are inside the record.
  const auto dot = [&](Eigen::Index a, Eigen::Index b) {
    const Eigen::Index m = std::max(a, b);
    return m >= n ? 0.0 : x.segment(m - a, n - m).dot(y.segment(m - b, n - m));
  };
  const bool symmetric = &x == &y && dx == dy && rows == cols;
  Eigen::MatrixXd g(rows, cols);
  for (Eigen::Index j = 0; j < cols; ++j) g(0, j) = dot(dx, dy + j);
  for (Eigen::Index i = 1; i < rows; ++i) g(i, 0) = symmetric ? g(0, i) : dot(dx + i, dy);
  for (Eigen::Index i = 1; i < rows; ++i) {
    for (Eigen::Index j = 1; j < cols; ++j) {
      const Eigen::Index a = dx + i;
      const Eigen::Index b = dy + j;
      g(i, j) = g(i - 1, j - 1) - (a <= n && b <= n ? x(n - a) * y(n - b) : 0.0);
    }
  }
  return g;
}

}  // namespace internal
}  // namespace ctid
