// Batch (QR / SVD / GCV ridge) and recursive (eq. 13) least squares for step 1.
#include "ctid/delayed_feedback/least_squares.h"

#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "ctid/core/error.h"

namespace ctid {
namespace {

const char* column_name(int j, int q) {
  if (j < q) return "beta";
  if (j < 2 * q - 1) return "gamma";
  if (j < 3 * q - 1) return "alpha";
  return "nuisance";
}

void finish(ClosedLoopEstimate& r, const FeedbackRegression& reg, const Eigen::VectorXd& all) {
  const int q = reg.forward_order + reg.feedback_order;
  const ClosedLoopEstimate polys = closed_loop_polynomials(all.head(reg.theta_size), q);
  r.alpha = polys.alpha;
  r.beta = polys.beta;
  r.gamma = polys.gamma;
  r.theta = all.head(reg.theta_size);
  r.nuisance = all.tail(reg.nuisance_size);
  r.equations = static_cast<int>(reg.target.size());
  const Eigen::VectorXd residual = reg.target - reg.regressor * all;
  r.residual_rms = std::sqrt(residual.squaredNorm() / static_cast<double>(residual.size()));
  if (all.allFinite()) {
    r.termination = Termination::converged;
  } else {
    r.termination = Termination::non_finite;
    r.message = "the least-squares solution is not finite";
  }
}

}  // namespace

ClosedLoopEstimate closed_loop_polynomials(const Eigen::VectorXd& theta, int q) {
  require(q >= 2 && theta.size() == 3 * q - 1,
          "closed_loop_polynomials: theta must have 3q - 1 = ", 3 * q - 1, " entries, got ",
          theta.size());
  Eigen::VectorXd beta(q + 1), gamma(q - 1), alpha(q);
  beta(q) = 1.0;
  for (int i = 0; i < q; ++i) beta(q - 1 - i) = theta(i);
  for (int i = 0; i + 1 < q; ++i) gamma(q - 2 - i) = theta(q + i);
  for (int i = 0; i < q; ++i) alpha(q - 1 - i) = theta(2 * q - 1 + i);
  ClosedLoopEstimate r;
  r.beta = Polynomial(beta);
  r.gamma = Polynomial::trimmed(gamma);
  r.alpha = Polynomial::trimmed(alpha);
  r.theta = theta;
  return r;
}

Eigen::VectorXd closed_loop_theta(const Polynomial& alpha, const Polynomial& beta,
                                  const Polynomial& gamma) {
  const int q = beta.degree();
  require(q >= 2 && std::abs(beta.leading() - 1.0) < 1e-12,
          "closed_loop_theta: beta must be monic of degree >= 2, got degree ", q);
  require(alpha.degree() < q && gamma.degree() < q - 1, "closed_loop_theta: need deg alpha < ", q,
          " and deg gamma < ", q - 1);
  Eigen::VectorXd theta(3 * q - 1);
  for (int i = 0; i < q; ++i) theta(i) = beta.coefficient(q - 1 - i);
  for (int i = 0; i + 1 < q; ++i) theta(q + i) = gamma.coefficient(q - 2 - i);
  for (int i = 0; i < q; ++i) theta(2 * q - 1 + i) = alpha.coefficient(q - 1 - i);
  return theta;
}

void BatchLeastSquaresOptions::check_relations(const std::string& path) const {
  require(gcv_max > gcv_min, path, ".gcv_max is ", gcv_max, "; it must be > gcv_min (", gcv_min,
          ")");
}

ClosedLoopEstimate estimate_closed_loop_batch(const FeedbackRegression& reg,
                                              const BatchLeastSquaresOptions& options) {
  options.validate();
  const int q = reg.forward_order + reg.feedback_order;
  const int p = reg.theta_size;
  const int nn = reg.nuisance_size;
  const Eigen::Index rows = reg.regressor.rows();
  require(rows > p + nn, "estimate_closed_loop_batch: too few equations (", rows, ") for ", p + nn,
          " unknowns");
  ClosedLoopEstimate result;
  result.equations = static_cast<int>(reg.target.size());
  auto fail = [&](Termination why, std::string message) {
    result.termination = why;
    result.message = std::move(message);
    return result;
  };
  if (!reg.regressor.allFinite() || !reg.target.allFinite())
    return fail(Termination::non_finite,
                "estimate_closed_loop_batch: the regression has non-finite entries");

  // Project the nuisance columns out so that they are estimated but never penalised.
  Eigen::MatrixXd c = reg.regressor.leftCols(p);
  Eigen::VectorXd y = reg.target;
  Eigen::MatrixXd q_nuisance;
  if (nn > 0) {
    Eigen::MatrixXd nuis = reg.regressor.rightCols(nn);
    for (int j = 0; j < nn; ++j) {
      const double norm = nuis.col(j).norm();
      if (norm > 0.0) nuis.col(j) /= norm;
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(nuis);
    qr.setThreshold(1e-13);
    if (qr.rank() != nn)
      return fail(Termination::singular_equations,
                  internal::concat("estimate_closed_loop_batch: the initial-condition columns are ",
                                   "singular (rank ", qr.rank(), " < ", nn,
                                   "); the record is too short for them"));
    q_nuisance = qr.householderQ() * Eigen::MatrixXd::Identity(rows, nn);
    c -= q_nuisance * (q_nuisance.transpose() * c);
    y -= q_nuisance * (q_nuisance.transpose() * y);
  }
  Eigen::VectorXd scale = c.colwise().norm().transpose();
  for (int j = 0; j < p; ++j) {
    if (!(scale(j) > 0.0 || options.regularisation != Regularisation::none))
      return fail(Termination::singular_equations,
                  internal::concat("estimate_closed_loop_batch: singular regressor: column ", j,
                                   " (", column_name(j, q),
                                   ") is identically zero; is the input or output zero?"));
    if (scale(j) == 0.0) scale(j) = 1.0;
  }
  const Eigen::MatrixXd cs = c * scale.cwiseInverse().asDiagonal();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(cs, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd s = svd.singularValues();
  result.condition_number =
      s(s.size() - 1) > 0.0 ? s(0) / s(s.size() - 1) : std::numeric_limits<double>::infinity();
  Eigen::VectorXd theta_scaled;
  if (options.regularisation == Regularisation::none) {
    if (!(s(s.size() - 1) > options.rank_tolerance * s(0)))
      return fail(
          Termination::singular_equations,
          internal::concat("estimate_closed_loop_batch: singular regressor (scaled condition ",
                           "number ", result.condition_number, " beyond 1/rank_tolerance); the ",
                           "input is not rich enough or the orders are too high; use ",
                           "regularisation"));
    if (options.solver == LeastSquaresSolver::qr) {
      theta_scaled = cs.colPivHouseholderQr().solve(y);
    } else {
      theta_scaled = svd.solve(y);
    }
  } else {
    const Eigen::VectorXd uty = svd.matrixU().transpose() * y;
    const double outside = std::max(0.0, y.squaredNorm() - uty.squaredNorm());
    const double dof = static_cast<double>(rows - nn);
    auto gcv = [&](double lambda) {
      double rss = outside;
      double trace = dof;
      for (Eigen::Index i = 0; i < s.size(); ++i) {
        const double f = s(i) * s(i) / (s(i) * s(i) + lambda);
        rss += (1.0 - f) * (1.0 - f) * uty(i) * uty(i);
        trace -= f;
      }
      return dof * rss / (trace * trace);
    };
    double rho = options.ridge;
    if (options.regularisation == Regularisation::gcv) {
      double best = std::numeric_limits<double>::infinity();
      for (int i = 0; i < options.gcv_points; ++i) {
        const double r =
            options.gcv_min * std::pow(options.gcv_max / options.gcv_min,
                                       static_cast<double>(i) / (options.gcv_points - 1));
        const double v = gcv(r * s(0) * s(0));
        if (v < best) {
          best = v;
          rho = r;
        }
      }
    }
    const double lambda = rho * s(0) * s(0);
    Eigen::VectorXd w(s.size());
    for (Eigen::Index i = 0; i < s.size(); ++i) w(i) = s(i) / (s(i) * s(i) + lambda) * uty(i);
    theta_scaled = svd.matrixV() * w;
    result.ridge = rho;
  }
  Eigen::VectorXd all(p + nn);
  all.head(p) = theta_scaled.cwiseQuotient(scale);
  if (nn > 0) {
    const Eigen::VectorXd rest = reg.target - reg.regressor.leftCols(p) * all.head(p);
    all.tail(nn) = reg.regressor.rightCols(nn).colPivHouseholderQr().solve(rest);
  }
  finish(result, reg, all);
  result.iterations = 1;
  return result;
}

RecursiveLeastSquares::RecursiveLeastSquares(Eigen::VectorXd theta0, Eigen::MatrixXd p0,
                                             double forgetting)
    : theta_(std::move(theta0)), p_(std::move(p0)), forgetting_(forgetting) {
  require(p_.rows() == theta_.size() && p_.cols() == theta_.size(),
          "RecursiveLeastSquares: P(0) must be ", theta_.size(), " x ", theta_.size());
  require(forgetting > 0.0 && forgetting <= 1.0,
          "RecursiveLeastSquares: forgetting must be in (0, 1], got ", forgetting);
}

void RecursiveLeastSquares::update(const Eigen::RowVectorXd& c, double y) {
  const Eigen::VectorXd pc = p_ * c.transpose();
  const double denom = c.dot(pc) + forgetting_;
  const Eigen::VectorXd gain = pc / denom;
  theta_ += gain * (y - c.dot(theta_));
  p_ = (p_ - gain * pc.transpose()) / forgetting_;
  p_ = 0.5 * (p_ + p_.transpose()).eval();
}

ClosedLoopEstimate estimate_closed_loop_recursive(const FeedbackRegression& reg,
                                                  const RecursiveLeastSquaresOptions& options) {
  options.validate();
  const Eigen::Index cols = reg.regressor.cols();
  Eigen::VectorXd theta0 = Eigen::VectorXd::Zero(cols);
  if (options.initial_theta) {
    require(options.initial_theta->size() == cols, "RecursiveLeastSquaresOptions: initial_theta ",
            "must have ", cols, " entries, got ", options.initial_theta->size());
    theta0 = *options.initial_theta;
  }
  Eigen::MatrixXd p0 = options.initial_covariance * Eigen::MatrixXd::Identity(cols, cols);
  if (options.initial_covariance_matrix) p0 = *options.initial_covariance_matrix;
  RecursiveLeastSquares rls(theta0, p0, options.forgetting);
  ClosedLoopEstimate result;
  for (Eigen::Index k = 0; k < reg.regressor.rows(); ++k) {
    rls.update(reg.regressor.row(k), reg.target(k));
    if (options.keep_history) result.theta_history.push_back(rls.theta().head(reg.theta_size));
  }
  const Eigen::VectorXd d = reg.regressor.leftCols(reg.theta_size).colwise().norm().transpose();
  const Eigen::VectorXd s =
      (reg.regressor.leftCols(reg.theta_size) *
       d.unaryExpr([](double v) { return v > 0.0 ? 1.0 / v : 1.0; }).asDiagonal())
          .jacobiSvd()
          .singularValues();
  result.condition_number =
      s(s.size() - 1) > 0.0 ? s(0) / s(s.size() - 1) : std::numeric_limits<double>::infinity();
  finish(result, reg, rls.theta());
  result.iterations = static_cast<int>(reg.regressor.rows());
  return result;
}

}  // namespace ctid
