// Frequency responses of parametric models on a grid of angular frequencies omega [rad/s]:
// G(j omega) for continuous models (input delay included as e^{-j omega tau}), G(e^{j omega h})
// for discrete ones, and for additive models (González et al., eq. 1) the sum of the
// submodels' responses times the delay factor.
#pragma once

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/hold.h"
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

/// The response from the samples u_k to the samples y_k of the model fed with u held as
/// `hold` says between samples of period h: the exact discrete equivalent (ZOH or FOH, the
/// input delay with its fraction of a sample included) at z = e^{j omega h}. What a
/// nonparametric FRF of sampled data estimates, to compare a continuous-time fit with it:
/// for a band-limited input sampled without aliasing it is close to G(j omega) only for the
/// FOH, and the ZOH adds its half-sample lag. Requires h > 0 and a proper model.
Eigen::VectorXcd sampled_frequency_response(const AdditiveModel& g, const Eigen::VectorXd& omegas,
                                            double h, Hold hold);

}  // namespace ctid
