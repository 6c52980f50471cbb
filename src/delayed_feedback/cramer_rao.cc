// Cramér-Rao bound of the loop parameters and the separability verdict.
#include "ctid/delayed_feedback/cramer_rao.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/SVD>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/delayed_feedback/loop_parameters.h"
#include "delayed_feedback/internal/loop_simulation.h"

namespace ctid {

using internal::report_from_jacobian;
using internal::sensitivity;
namespace internal {

SeparabilityReport report_from_jacobian(const Eigen::MatrixXd& jac, const Eigen::VectorXd& rho,
                                        double variance, double threshold) {
  SeparabilityReport r;
  r.parameters = rho;
  r.noise_variance = variance;
  Eigen::VectorXd scale = jac.colwise().norm().transpose();
  for (Eigen::Index i = 0; i < scale.size(); ++i)
    if (scale(i) == 0.0) scale(i) = 1.0;
  const Eigen::MatrixXd js = jac * scale.cwiseInverse().asDiagonal();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(js, Eigen::ComputeThinV);
  const Eigen::VectorXd s = svd.singularValues();
  const double smin = s(s.size() - 1);
  r.condition_number = smin > 0.0 ? s(0) / smin : std::numeric_limits<double>::infinity();
  Eigen::VectorXd inv2(s.size());
  for (Eigen::Index i = 0; i < s.size(); ++i)
    inv2(i) = s(i) > 1e-14 * s(0) ? 1.0 / (s(i) * s(i)) : std::numeric_limits<double>::infinity();
  if (!inv2.allFinite()) {
    const double inf = std::numeric_limits<double>::infinity();
    r.covariance = Eigen::MatrixXd::Constant(rho.size(), rho.size(), inf);
  } else {
    const Eigen::MatrixXd cov_s = svd.matrixV() * inv2.asDiagonal() * svd.matrixV().transpose();
    r.covariance =
        variance * scale.cwiseInverse().asDiagonal() * cov_s * scale.cwiseInverse().asDiagonal();
  }
  r.standard_deviations = r.covariance.diagonal().cwiseSqrt();
  r.relative_standard_deviations.resize(rho.size());
  for (Eigen::Index i = 0; i < rho.size(); ++i)
    r.relative_standard_deviations(i) = r.standard_deviations(i) / std::max(std::abs(rho(i)), 1e-3);
  const double worst = r.relative_standard_deviations.maxCoeff();
  r.separable = std::isfinite(worst) && worst < threshold;
  r.message = r.separable
                  ? "F and H are separable from this experiment: the largest relative standard "
                    "deviation is " +
                        format_brief(worst)
                  : "F and H are NOT reliably separable from this experiment: the largest "
                    "relative standard deviation is " +
                        format_brief(worst) + " (threshold " + format_brief(threshold) +
                        "); any estimate reflects the prior or the start";
  return r;
}

Eigen::MatrixXd sensitivity(const Eigen::VectorXd& rho, int n, int m, double delay,
                            const Eigen::VectorXd& input, double delta, Hold hold, int substeps) {
  Eigen::MatrixXd jac(input.size(), rho.size());
  for (Eigen::Index i = 0; i < rho.size(); ++i) {
    const double h = 1e-6 * std::max(1.0, std::abs(rho(i)));
    Eigen::VectorXd up = rho, down = rho;
    up(i) += h;
    down(i) -= h;
    jac.col(i) = (simulate_rho(up, n, m, delay, input, delta, hold, substeps) -
                  simulate_rho(down, n, m, delay, input, delta, hold, substeps)) /
                 (2 * h);
  }
  return jac;
}

}  // namespace internal

SeparabilityReport cramer_rao_bound(const DelayedFeedbackLoop& loop, const Eigen::VectorXd& input,
                                    double sample_time, Hold hold, double noise_sd,
                                    double relative_threshold, int substeps) {
  loop.validate();
  require(std::isfinite(noise_sd) && noise_sd > 0.0,
          "cramer_rao_bound: noise_sd must be positive, got ", noise_sd);
  require(relative_threshold > 0.0, "cramer_rao_bound: relative_threshold must be positive");
  const int n = loop.forward.denominator().degree();
  const int m = loop.feedback.denominator().degree();
  const Eigen::VectorXd rho = loop_parameters(loop);
  require(input.size() > rho.size(), "cramer_rao_bound: too few samples (", input.size(), ") for ",
          rho.size(), " parameters");
  const Eigen::MatrixXd jac =
      sensitivity(rho, n, m, loop.delay, input, sample_time, hold, substeps);
  return report_from_jacobian(jac, rho, noise_sd * noise_sd, relative_threshold);
}

}  // namespace ctid
