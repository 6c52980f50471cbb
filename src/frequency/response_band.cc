#include "ctid/frequency/response_band.h"

#include <cmath>

#include "ctid/core/error.h"
#include "ctid/frequency/response.h"

namespace ctid {

namespace {

// dG/dtheta_i by a central difference with step 1e-6 |theta_i| (1e-9 where theta_i = 0).
Eigen::MatrixXcd response_jacobian(const AdditiveModel& model, const Eigen::VectorXd& omegas) {
  const Eigen::VectorXd theta = model.parameters();
  Eigen::MatrixXcd jacobian(omegas.size(), theta.size());
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    const double step = theta(i) != 0.0 ? 1e-6 * std::abs(theta(i)) : 1e-9;
    Eigen::VectorXd up = theta;
    Eigen::VectorXd down = theta;
    up(i) += step;
    down(i) -= step;
    jacobian.col(i) = (frequency_response(model.with_parameters(up), omegas) -
                       frequency_response(model.with_parameters(down), omegas)) /
                      (2.0 * step);
  }
  return jacobian;
}

// sqrt(max(g P g^T, 0)) for every row g of `gradients`.
Eigen::VectorXd row_sigmas(const Eigen::MatrixXd& gradients, const Eigen::MatrixXd& covariance) {
  const Eigen::VectorXd variance = (gradients * covariance).cwiseProduct(gradients).rowwise().sum();
  return variance.cwiseMax(0.0).cwiseSqrt();
}

}  // namespace

FrequencyResponseBand frequency_response_band(const AdditiveModel& model,
                                              const Eigen::VectorXd& omegas,
                                              const Eigen::MatrixXd& covariance) {
  const Eigen::Index p = model.parameters().size();
  require(covariance.rows() == p && covariance.cols() == p,
          "frequency_response_band: the covariance is ", covariance.rows(), "x", covariance.cols(),
          " but the model has ", p, " parameters");
  require(covariance.allFinite(), "frequency_response_band: the covariance is not finite");
  FrequencyResponseBand band;
  band.response = frequency_response(model, omegas);
  const Eigen::MatrixXcd jacobian = response_jacobian(model, omegas);
  const Eigen::VectorXd magnitude = band.response.cwiseAbs();
  const Eigen::MatrixXd magnitude_gradient =
      (band.response.conjugate().asDiagonal() * jacobian).real().array().colwise() /
      magnitude.array();
  const Eigen::MatrixXd phase_gradient =
      (jacobian.array().colwise() / band.response.array()).imag();
  band.magnitude_sigma = row_sigmas(magnitude_gradient, covariance);
  band.phase_sigma = row_sigmas(phase_gradient, covariance);
  return band;
}

}  // namespace ctid
