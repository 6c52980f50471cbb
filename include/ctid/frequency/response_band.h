// The first-order uncertainty of an additive model's frequency response: the magnitude and
// phase standard deviations of G(j omega) propagated from the covariance P of the model's
// parameters() (the estimator's covariance, Theorem 3.2 of González et al. for refined IV).
// With J = dG/dtheta (central differences, relative step 1e-6), the magnitude's gradient is
// Re(conj(G) J) / |G| and the phase's is Im(J / G); each sigma is sqrt(g P g^T). The Bode
// plots draw |G| +- z sigma (z from two_sided_normal_quantile in simulation/time_response.h).
#pragma once

#include <Eigen/Core>

#include "ctid/core/additive_model.h"

namespace ctid {

struct FrequencyResponseBand {
  Eigen::VectorXcd response;        ///< G(j omega_i), delay factor included
  Eigen::VectorXd magnitude_sigma;  ///< standard deviation of |G(j omega_i)|
  Eigen::VectorXd phase_sigma;      ///< standard deviation of arg G(j omega_i) [rad]
};

/// The band of `model` on `omegas` for the covariance of model.parameters(); throws
/// InvalidArgument when the covariance is not square of the parameters' size or not finite.
FrequencyResponseBand frequency_response_band(const AdditiveModel& model,
                                              const Eigen::VectorXd& omegas,
                                              const Eigen::MatrixXd& covariance);

}  // namespace ctid
