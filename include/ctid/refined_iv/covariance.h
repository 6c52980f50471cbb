// Asymptotic covariance of refined IV estimates (González et al., Theorem 3.2 and Corollary
// 3.3): with the optimal instrument psi (the model-output gradient, eqs. 10/15/20),
// Cov(beta) = R^-1 Q R^-1 / N-scaled sums, R = sum psi psi', Q = sum_k sum_s psi_k r_v(k-s) psi_s'.
// White noise gives Q = sigma^2 R; coloured noise is modelled by an AR fit of the residuals.
// Modal standard errors follow by the delta method.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

/// Covariance of the parameters (not scaled by N: it is the covariance of the estimate
/// itself). psi is N x p (the instrument at the estimate), residual the output error
/// y - G u. For NoiseAssumption::coloured an AR model of order <= max_ar_order chosen by AIC
/// whitens the residual and Q = sigma_e^2 sum psi~ psi~' with psi~ = H(q^-1)' psi.
Eigen::MatrixXd instrumental_variable_covariance(const Eigen::MatrixXd& psi,
                                                 const Eigen::VectorXd& residual,
                                                 int parameter_count, NoiseAssumption noise,
                                                 int max_ar_order = 20);

/// AR coefficients [1, alpha_1, ..., alpha_k] and innovation variance of x by Yule-Walker
/// (Levinson-Durbin), k <= max_order chosen by AIC. v = e / A(q^-1).
struct AutoregressiveModel {
  Eigen::VectorXd coefficients;
  double innovation_variance = 0.0;
};
AutoregressiveModel fit_autoregressive(const Eigen::VectorXd& x, int max_order);

/// H(q^-1)' x for the noise filter H = 1/A of `ar`, column by column (x is N x p), returned
/// transposed (p x N): with it sum_s x~_s x~_s' = g g' is the middle factor Q of the sandwich.
Eigen::MatrixXd adjoint_ar_filter(const Eigen::MatrixXd& x, const AutoregressiveModel& ar);

/// Delta-method standard errors of natural frequency, damping ratio and modal gain for
/// every second-order mode. For an additive model the covariance is that of its
/// parameters(); with `unfactored` the model is one submodel B/(p^l A) whose partial-fraction
/// split gives the modes, differentiated numerically. An empty covariance gives NaN errors.
std::vector<ModalEstimate> modal_estimates(const AdditiveModel& model,
                                           const Eigen::MatrixXd& covariance,
                                           bool unfactored = false);

}  // namespace ctid
