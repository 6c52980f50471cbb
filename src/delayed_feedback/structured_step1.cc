// Structured step 1 and the shared structured least squares (θ(ρ), nuisance projection).
#include "ctid/delayed_feedback/structured_step1.h"

#include <ceres/ceres.h>

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/QR>

#include "ctid/core/error.h"
#include "ctid/delayed_feedback/loop_parameters.h"
#include "delayed_feedback/internal/ceres_solve.h"
#include "delayed_feedback/internal/loop_polynomials.h"
#include "delayed_feedback/internal/structured_system.h"

namespace ctid {

using internal::project_nuisance;
using internal::ProjectedSystem;
using internal::structured_least_squares;
namespace {

// θ(ρ) in the paper's order [β_{q-1..0} | γ_{q-2..0} | α_{q-1..0}].
struct ThetaOfRho {
  int n, m;
  template <typename T>
  void operator()(const T* p, T* theta) const {
    const int q = n + m;
    const internal::LoopPolynomials<T> poly = internal::loop_polynomials(p, n, m);
    const std::vector<T>& a = poly.alpha;
    const std::vector<T>& b = poly.beta;
    const std::vector<T>& g = poly.gamma;
    for (int i = 0; i < q; ++i) theta[i] = b[q - 1 - i];
    for (int i = 0; i + 1 < q; ++i) theta[q + i] = g[q - 2 - i];
    for (int i = 0; i < q; ++i) theta[2 * q - 1 + i] = a[q - 1 - i];
  }
};

struct StructuredResidual {
  const Eigen::MatrixXd* c;
  const Eigen::VectorXd* y;
  int n, m;
  template <typename T>
  bool operator()(T const* const* parameters, T* residual) const {
    const int p = 3 * (n + m) - 1;
    std::vector<T> theta(static_cast<size_t>(p));
    ThetaOfRho{n, m}(parameters[0], theta.data());
    for (Eigen::Index k = 0; k < c->rows(); ++k) {
      T sum = T((*y)(k));
      for (int j = 0; j < p; ++j) sum -= (*c)(k, j) * theta[static_cast<size_t>(j)];
      residual[k] = sum;
    }
    return true;
  }
};

}  // namespace

namespace internal {

Eigen::VectorXd theta_of(const Eigen::VectorXd& rho, int n, int m) {
  Eigen::VectorXd theta(3 * (n + m) - 1);
  ThetaOfRho{n, m}(rho.data(), theta.data());
  return theta;
}

namespace {

// One alternating step: least squares in the block [offset, offset + size) of ρ, the rest fixed.
void solve_block(Eigen::VectorXd& rho, int offset, int size, int n, int m, const Eigen::MatrixXd& c,
                 const Eigen::VectorXd& y) {
  Eigen::VectorXd base = rho;
  base.segment(offset, size).setZero();
  const Eigen::VectorXd theta0 = theta_of(base, n, m);
  Eigen::MatrixXd map(theta0.size(), size);
  for (int i = 0; i < size; ++i) {
    Eigen::VectorXd unit = base;
    unit(offset + i) = 1.0;
    map.col(i) = theta_of(unit, n, m) - theta0;
  }
  const Eigen::MatrixXd a = c * map;
  const Eigen::VectorXd x = a.colPivHouseholderQr().solve(y - c * theta0);
  if (x.allFinite()) rho.segment(offset, size) = x;
}

}  // namespace

ProjectedSystem project_nuisance(const FeedbackRegression& reg) {
  ProjectedSystem s;
  s.c = reg.regressor.leftCols(reg.theta_size);
  s.y = reg.target;
  s.nuisance.resize(reg.regressor.rows(), 0);
  if (reg.nuisance_size > 0) {
    Eigen::MatrixXd nuis = reg.regressor.rightCols(reg.nuisance_size);
    for (Eigen::Index j = 0; j < nuis.cols(); ++j)
      if (nuis.col(j).norm() > 0.0) nuis.col(j) /= nuis.col(j).norm();
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(nuis);
    s.nuisance = qr.householderQ() * Eigen::MatrixXd::Identity(nuis.rows(), nuis.cols());
    s.c -= s.nuisance * (s.nuisance.transpose() * s.c);
    s.y -= s.nuisance * (s.nuisance.transpose() * s.y);
  }
  return s;
}

// Levenberg-Marquardt on |y - c θ(ρ)|² from rho (updated in place); returns the cost.
LeastSquaresOutcome structured_least_squares(const Eigen::MatrixXd& c, const Eigen::VectorXd& y,
                                             int n, int m, int max_iterations,
                                             Eigen::VectorXd& rho) {
  ceres::Problem problem;
  auto* cost = new ceres::DynamicAutoDiffCostFunction<StructuredResidual, 8>(
      new StructuredResidual{&c, &y, n, m});
  cost->AddParameterBlock(2 * (n + m));
  cost->SetNumResiduals(static_cast<int>(y.size()));
  problem.AddResidualBlock(cost, nullptr, rho.data());
  internal::LeastSquaresSettings settings;
  settings.max_iterations = max_iterations;
  settings.function_tolerance = 1e-14;
  settings.parameter_tolerance = 1e-14;
  return internal::solve_least_squares(problem, settings);
}

}  // namespace internal

void StructuredStep1Options::check_relations(const std::string& path) const {
  require(!start_frequencies.empty(), path,
          ".start_frequencies is empty; it must hold at least "
          "one frequency");
}

StructuredStep1Result estimate_structured_step1(const FeedbackRegression& reg,
                                                const StructuredStep1Options& options) {
  options.validate();
  const int n = reg.forward_order;
  const int m = reg.feedback_order;
  const ProjectedSystem sys = project_nuisance(reg);
  StructuredStep1Result best;
  best.cost = std::numeric_limits<double>::infinity();
  for (double w : options.start_frequencies) {
    Eigen::VectorXd rho = Eigen::VectorXd::Zero(2 * (n + m));
    // D_H = (s + w)^m, N_H = 0: the first F-step fits F as if there were no feedback.
    Eigen::VectorXd dh = Eigen::VectorXd::Zero(m + 1);
    for (int i = 0; i <= m; ++i)
      dh(i) = std::tgamma(m + 1.0) / (std::tgamma(i + 1.0) * std::tgamma(m - i + 1.0)) *
              std::pow(w, m - i);
    rho.segment(2 * n, m) = dh.head(m);
    for (int it = 0; it < options.alternating_iterations; ++it) {
      internal::solve_block(rho, 0, 2 * n, n, m, sys.c, sys.y);
      internal::solve_block(rho, 2 * n, 2 * m, n, m, sys.c, sys.y);
    }
    const internal::LeastSquaresOutcome outcome =
        structured_least_squares(sys.c, sys.y, n, m, options.max_iterations, rho);
    const double j = outcome.sum_of_squares;
    ++best.starts;
    if (rho.allFinite() && j < best.cost) {
      best.cost = j;
      static_cast<Outcome&>(best) = outcome;
      best.loop = loop_from_parameters(rho, n, m, reg.delay);
    }
  }
  if (!std::isfinite(best.cost)) {
    best.termination = Termination::no_solution;
    best.message = "no start of the structured step 1 ends finite";
  }
  return best;
}

}  // namespace ctid
