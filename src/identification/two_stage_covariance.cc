// The covariance of the two-stage estimate with stage 1's error in it (decision 0072).
//
// To first order, stage 2's output-error estimate moves by
//   d theta = R^-1 sum_t psi(t) [w(t) - (G d u_hat)(t)],   R = sum_t psi psi',
// psi the gradient of G(theta) u_hat, w = y - G u_hat. Stage 1's output-error fit of r -> u
// moves u_hat = B/A r by d u_hat = Phi d eta, d eta = (Phi'Phi)^+ sum_t Phi(t) e(t), Phi its
// own output gradient (shifted copies of r/A and of -u_hat/A) and e = u - u_hat. So
//   d theta = R^-1 sum_t [psi(t) w(t) - d(t) e(t)],   d(t)' = Phi(t)' (Phi'Phi)^+ M',
// M = sum_t psi(t) (G Phi)(t)'. w and e are the same noise seen twice (in closed loop
// e = -C w), so the sum is taken with one vector AR model of (w, e): its adjoint filter
// whitens the sum, as the scalar AR does for one estimate (refined_iv/covariance.h).
#include "internal/two_stage_covariance.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "ctid/estimation/verdict.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/refined_iv.h"
#include "ctid/simulation/simulate.h"
#include "internal/delayed_gram.h"

namespace ctid::internal {
namespace {

// Relative step of the central differences of the output gradient.
constexpr double kGradientStep = 1e-6;
// A residual below this fraction of its signal's RMS is no noise: it leaves the AR model.
constexpr double kNoiseFloor = 1e-9;
// Directions of stage 1's scaled Gram matrix below this fraction of its largest eigenvalue do
// not move u_hat (a richer model than the map): they are left out of its inverse.
constexpr double kGramFloor = 1e-10;

// d/d theta of G(theta) u simulated from rest, by central differences (N x p).
Eigen::MatrixXd output_gradient(const AdditiveModel& model, const Eigen::VectorXd& u, double h) {
  const Eigen::VectorXd theta = model.parameters();
  const double floor =
      std::max(1e-6 * theta.cwiseAbs().maxCoeff(), std::numeric_limits<double>::min());
  Eigen::MatrixXd psi(u.size(), theta.size());
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    const double step = kGradientStep * std::max(std::abs(theta(i)), floor);
    Eigen::VectorXd up = theta;
    Eigen::VectorXd down = theta;
    up(i) += step;
    down(i) -= step;
    psi.col(i) =
        (simulate(model.with_parameters(up), u, h) - simulate(model.with_parameters(down), u, h)) /
        (2.0 * step);
  }
  return psi;
}

// Columns sign * base delayed by first, first + 1, ..., first + count - 1 samples (zero
// before the record): a block of stage 1's output gradient; `modelled` is G base.
struct ShiftedBlock {
  Eigen::VectorXd base;
  Eigen::VectorXd modelled;
  Eigen::Index first = 0;
  Eigen::Index count = 0;
  double sign = 1.0;
};

// x / A(q^-1) from rest.
Eigen::VectorXd over_denominator(const SensitivityFit& fit, const Eigen::VectorXd& x) {
  SensitivityFit denominator_only;
  denominator_only.denominator = fit.denominator;
  denominator_only.numerator = Eigen::VectorXd::Ones(1);
  return sensitivity_output(denominator_only, x);
}

// d u_hat / d eta for eta = [a_1..a_n, b_0..b_m] of u_hat = B/A r: -u_hat/A delayed 1..n and
// r/A delayed 0..m (an FIR: r delayed 0..L-1).
std::vector<ShiftedBlock> stage_one_gradient(const SensitivityFit& fit, const Eigen::VectorXd& r,
                                             const AdditiveModel& model, double h) {
  std::vector<ShiftedBlock> blocks;
  const Eigen::Index n = fit.denominator.size() - 1;
  if (n > 0) blocks.push_back({over_denominator(fit, fit.simulated_input), {}, 1, n, -1.0});
  blocks.push_back({n > 0 ? over_denominator(fit, r) : r, {}, 0, fit.numerator.size(), 1.0});
  for (ShiftedBlock& block : blocks) block.modelled = simulate(model, block.base, h);
  return blocks;
}

// Phi_x' Phi_y of two blocks (delayed_gram).
Eigen::MatrixXd block_gram(const ShiftedBlock& x, const ShiftedBlock& y) {
  return x.sign * y.sign * delayed_gram(x.base, x.first, x.count, y.base, y.first, y.count);
}

// The pseudo-inverse of a Gram matrix, its directions below kGramFloor of the largest
// (scaled by its diagonal) left out: a stage-1 model richer than the map (AIC may choose
// one, e.g. a pole that nearly cancels a zero) has a direction that does not move u_hat, and
// only the projection of e on the directions that do counts. Empty if it is not finite.
std::optional<Eigen::MatrixXd> projection_inverse(const Eigen::MatrixXd& gram) {
  const Eigen::VectorXd diagonal = gram.diagonal();
  if (!gram.allFinite() || !(diagonal.minCoeff() > 0.0)) return std::nullopt;
  const Eigen::VectorXd scale = diagonal.cwiseSqrt().cwiseInverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scale.asDiagonal() * gram *
                                                             scale.asDiagonal());
  if (eigen.info() != Eigen::Success) return std::nullopt;
  const Eigen::VectorXd& values = eigen.eigenvalues();
  const double floor = kGramFloor * values.maxCoeff();
  const Eigen::VectorXd inverted =
      values.unaryExpr([floor](double x) { return x > floor ? 1.0 / x : 0.0; });
  return Eigen::MatrixXd(scale.asDiagonal() * eigen.eigenvectors() * inverted.asDiagonal() *
                         eigen.eigenvectors().transpose() * scale.asDiagonal());
}

// d(t) of the header comment (N x p), or empty when stage 1's gradient is not finite.
Eigen::MatrixXd stage_one_influence(const std::vector<ShiftedBlock>& blocks,
                                    const Eigen::MatrixXd& psi) {
  Eigen::Index columns = 0;
  for (const ShiftedBlock& block : blocks) columns += block.count;
  const Eigen::Index n = psi.rows();
  Eigen::MatrixXd gram(columns, columns);
  Eigen::MatrixXd m(psi.cols(), columns);  // sum_t psi(t) (G Phi)(t)'
  Eigen::Index row = 0;
  for (const ShiftedBlock& x : blocks) {
    Eigen::Index column = 0;
    for (const ShiftedBlock& y : blocks) {
      gram.block(row, column, x.count, y.count) = block_gram(x, y);
      column += y.count;
    }
    for (Eigen::Index i = 0; i < x.count; ++i) {
      const Eigen::Index d = std::min(x.first + i, n);
      m.col(row + i) = x.sign * psi.bottomRows(n - d).transpose() * x.modelled.head(n - d);
    }
    row += x.count;
  }
  const std::optional<Eigen::MatrixXd> inverse = projection_inverse(gram);
  if (!inverse) return {};
  const Eigen::MatrixXd v = *inverse * m.transpose();  // columns x p
  Eigen::MatrixXd influence = Eigen::MatrixXd::Zero(n, psi.cols());
  row = 0;
  for (const ShiftedBlock& x : blocks) {
    for (Eigen::Index i = 0; i < x.count; ++i) {
      const Eigen::Index d = std::min(x.first + i, n);
      influence.bottomRows(n - d).noalias() += x.sign * x.base.head(n - d) * v.row(row + i);
    }
    row += x.count;
  }
  return influence;
}

// x(t) + sum_j a_j x(t - j) = eps(t), Cov(eps) = innovation, by Yule-Walker, the order in
// 0..max_order by AIC: with one component, fit_autoregressive's model.
struct VectorAutoregression {
  std::vector<Eigen::MatrixXd> a;
  Eigen::MatrixXd innovation;
};

VectorAutoregression fit_vector_autoregression(const Eigen::MatrixXd& x, int max_order) {
  const Eigen::Index n = x.rows();
  const Eigen::Index m = x.cols();
  const int largest = static_cast<int>(std::min<Eigen::Index>(max_order, n / 4));
  const Eigen::MatrixXd c = x.rowwise() - x.colwise().mean();
  std::vector<Eigen::MatrixXd> gamma;  // E[x(t + tau) x(t)'], as fit_autoregressive forms it
  for (int tau = 0; tau <= largest; ++tau) {
    gamma.push_back(c.bottomRows(n - tau).transpose() * c.topRows(n - tau) /
                    static_cast<double>(n));
  }
  VectorAutoregression best{{}, gamma[0]};
  double best_aic = static_cast<double>(n) * std::log(gamma[0].determinant());
  for (int k = 1; k <= largest; ++k) {
    Eigen::MatrixXd toeplitz(m * k, m * k);
    Eigen::MatrixXd rhs(m, m * k);
    for (int j = 0; j < k; ++j) {
      rhs.middleCols(m * j, m) = -gamma[static_cast<std::size_t>(j + 1)];
      for (int i = 0; i < k; ++i) {
        toeplitz.block(m * j, m * i, m, m) =
            i >= j ? gamma[static_cast<std::size_t>(i - j)]
                   : gamma[static_cast<std::size_t>(j - i)].transpose();
      }
    }
    const Eigen::MatrixXd coefficients =
        toeplitz.transpose().partialPivLu().solve(rhs.transpose()).transpose();
    VectorAutoregression fit{{}, gamma[0]};
    for (int j = 0; j < k; ++j) {
      fit.a.push_back(coefficients.middleCols(m * j, m));
      fit.innovation += fit.a.back() * gamma[static_cast<std::size_t>(j + 1)].transpose();
    }
    const double aic = static_cast<double>(n) * std::log(fit.innovation.determinant()) +
                       2.0 * static_cast<double>(m * m * k);
    if (std::isfinite(aic) && aic < best_aic) {
      best_aic = aic;
      best = std::move(fit);
    }
  }
  return best;
}

// sum_s z(s) Cov(eps) z(s)' for the sum sum_t g(t) x(t), g(t) = [g_0(t) .. g_{m-1}(t)] (one
// N x p matrix per component of x): with x = A(q)^-1 eps the sum is sum_s z(s) eps(s), z
// the adjoint filter z(s) = g(s) - sum_j z(s + j) a_j run backwards.
Eigen::MatrixXd whitened_sum(const std::vector<Eigen::MatrixXd>& g,
                             const VectorAutoregression& ar) {
  const std::size_t m = g.size();
  const Eigen::Index n = g[0].rows();
  // Time runs along the columns (p x N), so each step touches contiguous memory.
  std::vector<Eigen::MatrixXd> z;
  for (const Eigen::MatrixXd& factor : g) z.push_back(factor.transpose());
  for (Eigen::Index s = n - 1; s >= 0; --s) {
    for (std::size_t j = 1; j <= ar.a.size() && s + static_cast<Eigen::Index>(j) < n; ++j) {
      const Eigen::MatrixXd& a = ar.a[j - 1];
      const Eigen::Index later = s + static_cast<Eigen::Index>(j);
      for (std::size_t c = 0; c < m; ++c) {
        for (std::size_t d = 0; d < m; ++d) {
          z[c].col(s) -=
              a(static_cast<Eigen::Index>(d), static_cast<Eigen::Index>(c)) * z[d].col(later);
        }
      }
    }
  }
  const Eigen::Index p = g[0].cols();
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(p, p);
  for (std::size_t c = 0; c < m; ++c) {
    for (std::size_t d = 0; d < m; ++d) {
      q.noalias() += ar.innovation(static_cast<Eigen::Index>(c), static_cast<Eigen::Index>(d)) *
                     z[c] * z[d].transpose();
    }
  }
  return q;
}

double rms(const Eigen::VectorXd& x) {
  return x.size() > 0 ? x.norm() / std::sqrt(static_cast<double>(x.size())) : 0.0;
}

}  // namespace

std::optional<Eigen::MatrixXd> two_stage_covariance(const AdditiveModel& model,
                                                    const StageOne& stage_one,
                                                    int max_noise_order) {
  const Eigen::Index p = model.parameters().size();
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(p, p);
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(p, p);
  for (std::size_t k = 0; k < stage_one.fits.size(); ++k) {
    const SampledData& record = stage_one.simulated[k];
    const SensitivityFit& fit = stage_one.fits[k];
    const double h = record.sample_time();
    const Eigen::MatrixXd psi = output_gradient(model, record.input(), h);
    const Eigen::MatrixXd influence =
        stage_one_influence(stage_one_gradient(fit, stage_one.references[k], model, h), psi);
    if (influence.size() == 0) return std::nullopt;
    // The noise components, each with its factor of the sum; one without noise is left out.
    const Eigen::VectorXd w = record.output() - simulate(model, record.input(), h);
    const Eigen::VectorXd& e = stage_one.input_errors[k];
    std::vector<Eigen::MatrixXd> g;
    std::vector<const Eigen::VectorXd*> x;
    if (rms(w) > kNoiseFloor * rms(record.output())) {
      g.push_back(psi);
      x.push_back(&w);
    }
    if (rms(e) > kNoiseFloor * rms(fit.simulated_input)) {
      g.push_back(-influence);
      x.push_back(&e);
    }
    r.noalias() += psi.transpose() * psi;
    if (g.empty()) continue;
    // Each component scaled to unit RMS for the AR fit; its factor carries the scale.
    Eigen::MatrixXd scaled(record.size(), static_cast<Eigen::Index>(x.size()));
    for (std::size_t c = 0; c < x.size(); ++c) {
      const double scale = rms(*x[c]);
      scaled.col(static_cast<Eigen::Index>(c)) = *x[c] / scale;
      g[c] *= scale;
    }
    // With refined IV's correction of the innovations' variance for the fitted parameters.
    const double samples = static_cast<double>(record.size());
    q += whitened_sum(g, fit_vector_autoregression(scaled, max_noise_order)) * samples /
         (samples - static_cast<double>(p));
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(r);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-15)) return std::nullopt;
  const Eigen::MatrixXd half = ldlt.solve(q);
  const Eigen::MatrixXd covariance = ldlt.solve(half.transpose());
  if (!covariance.allFinite()) return std::nullopt;
  return Eigen::MatrixXd(0.5 * (covariance + covariance.transpose()));
}

namespace {

bool stage_two_is_output_error_srivc(const IdentificationResult& result,
                                     const IdentificationOptions& options,
                                     const StageOne& stage_one) {
  const RefinedIvOptions& iv = options.refined_iv;
  bool zero_order_hold = true;
  for (const SampledData& record : stage_one.simulated) {
    zero_order_hold = zero_order_hold && record.input_hold() == Hold::zero_order_hold;
  }
  const bool output_error_srivc = result.estimator == RefinedIvEstimator::srivc ||
                                  result.estimator == RefinedIvEstimator::additive_srivc;
  return zero_order_hold && output_error_srivc && !iv.noise_model &&
         iv.initial_conditions == InitialConditions::zero && !options.delay_range &&
         iv.record_delay_samples.empty() && options.constraints.empty() &&
         !result.mode_relocation && result.estimate.covariance.size() > 0 &&
         result.estimate.parameters.allFinite();
}

}  // namespace

bool include_stage_one_error(IdentificationResult& result, const ModelStructure& structure,
                             const IdentificationOptions& options, const StageOne& stage_one) {
  if (!stage_two_is_output_error_srivc(result, options, stage_one)) return false;
  EstimationResult& estimate = result.estimate;
  const std::optional<Eigen::MatrixXd> covariance =
      two_stage_covariance(estimate.model, stage_one, options.refined_iv.noise_model_max_order);
  if (!covariance || covariance->rows() != estimate.covariance.rows()) return false;
  // Only the judgement is redone with the new errors: a failure the estimator added after
  // judging (a stop before a degenerate iterate, decision 0050) and the constraints that acted
  // stay as they were.
  const Verdict judged = refined_iv_verdict(estimate, false, false);
  estimate.covariance = *covariance;
  estimate.standard_errors = covariance->diagonal().cwiseMax(0.0).cwiseSqrt();
  estimate.modes =
      modal_estimates(estimate.model, estimate.covariance, structure.kind == ModelKind::unfactored);
  Verdict verdict = refined_iv_verdict(estimate, false, false);
  for (const std::string& reason : estimate.verdict.reasons) {
    if (std::ranges::find(judged.reasons, reason) == judged.reasons.end()) {
      verdict.fail(reason, {estimate.verdict.advice});
    }
  }
  verdict.active_constraints = std::move(estimate.verdict.active_constraints);
  estimate.verdict = std::move(verdict);
  return true;
}

}  // namespace ctid::internal
