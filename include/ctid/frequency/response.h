// Frequency responses of parametric models on a grid of angular frequencies omega [rad/s]:
// G(j omega) for continuous models (input delay included as e^{-j omega tau}), G(e^{j omega h})
// for discrete ones, and for additive models (González et al., eq. 1) the sum of the
// submodels' responses times the delay factor.
#pragma once

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/transfer_function.h"

namespace ctid {

/// `count` >= 2 frequencies from omega_min to omega_max (both included), equally spaced in
/// log10; 0 < omega_min < omega_max.
Eigen::VectorXd log_frequency_grid(double omega_min, double omega_max, int count);

/// G(j omega_i) for every omega_i of the grid (any real, finite values; negative ones give the
/// conjugate response).
Eigen::VectorXcd frequency_response(const TransferFunction& g, const Eigen::VectorXd& omegas);
/// G(e^{j omega_i h}), h the model's sample time.
Eigen::VectorXcd frequency_response(const DiscreteTransferFunction& g,
                                    const Eigen::VectorXd& omegas);
/// e^{-j omega tau} sum_i G_i(j omega).
Eigen::VectorXcd frequency_response(const AdditiveModel& g, const Eigen::VectorXd& omegas);
/// Column i is submodel i's response G_i(j omega) without the delay factor.
Eigen::MatrixXcd submodel_frequency_responses(const AdditiveModel& g,
                                              const Eigen::VectorXd& omegas);

}  // namespace ctid
