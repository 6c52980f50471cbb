// Exact sampled response of continuous-time models to a zero-order-hold input: u(t) = u_k
// on [t_k, t_{k+1}), zero state at t_0, output y_k = y(t_k) (so a biproper model's y_k
// includes D u_k). An input delay tau = (d + f) h shifts the input by d samples and the
// fraction f is discretised exactly (discretize_zoh with a fraction: one more state).
// Additive models (González et al., eq. 1) are simulated as the sum of their submodels.
#pragma once

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/state_space.h"
#include "ctid/core/transfer_function.h"

namespace ctid {

/// An input delay tau = (samples + fraction) h, 0 <= fraction < 1.
struct DelaySplit {
  int samples = 0;
  double fraction = 0.0;
};

/// tau / h split into whole samples and a fraction; a ratio within 1e-9 (relative) of an
/// integer is that integer with fraction 0. Throws InvalidArgument for a negative or
/// non-finite tau, h <= 0, or tau / h > 1e9.
DelaySplit split_delay(double tau, double h);

/// The input delay tau as a whole number of samples of period h. Throws InvalidArgument
/// (naming tau, h and tau/h) unless tau/h is within 1e-9 of an integer.
int delay_in_samples(double tau, double h);

/// Response from rest of a discrete realisation x_{k+1} = A x_k + B u_k, y_k = C x_k + D u_k.
Eigen::VectorXd simulate_discrete(const StateSpace& discrete, const Eigen::VectorXd& u);

/// ZOH equivalent of a proper model sampled with period h, the input delay (d + f) h
/// realised as d extra states (a shift register in front of the plant) and one more for a
/// fraction f > 0, so the result is the exact discrete model from u_k to y_k.
StateSpace zoh_equivalent(const TransferFunction& g, double h);
/// ZOH equivalent of an additive model: the submodels' equivalents side by side
/// (block-diagonal A), then the input delay as in the TransferFunction overload.
StateSpace zoh_equivalent(const AdditiveModel& g, double h);

/// Samples y_k of the response of G to the ZOH input u (one value per u_k); h > 0.
/// Requires a proper model and finite input.
Eigen::VectorXd simulate(const TransferFunction& g, const Eigen::VectorXd& u, double h);
Eigen::VectorXd simulate(const AdditiveModel& g, const Eigen::VectorXd& u, double h);

/// Column i holds the response of submodel i (with the model's input delay); the row sums
/// are simulate(g, u, h).
Eigen::MatrixXd simulate_submodels(const AdditiveModel& g, const Eigen::VectorXd& u, double h);

}  // namespace ctid
