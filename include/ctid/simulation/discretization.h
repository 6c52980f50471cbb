// Exact discretisation of continuous-time state equations dx/dt = A x + B u over one
// sample period h, through the matrix exponential of an augmented matrix, so that it holds
// for singular A (integrators) and stiff models alike (never A^{-1}(e^{Ah} - I)B).
//  ZOH (u constant on [t_k, t_k+1)):  x_{k+1} = Phi x_k + Gamma u_k
//  FOH (u linear on [t_k, t_k+1]):    x_{k+1} = Phi x_k + Gamma0 u_k + Gamma1 u_{k+1}
#pragma once

#include <Eigen/Core>

#include "ctid/core/hold.h"
#include "ctid/core/state_space.h"

namespace ctid {

struct ZohDiscretization {
  Eigen::MatrixXd phi;    ///< e^{A h}
  Eigen::MatrixXd gamma;  ///< int_0^h e^{A s} ds B
};

struct FohDiscretization {
  Eigen::MatrixXd phi;     ///< e^{A h}
  Eigen::MatrixXd gamma0;  ///< weight of u_k
  Eigen::MatrixXd gamma1;  ///< weight of u_{k+1}
};

/// A held input delayed by a fraction f of a sample, u(t - f h) with 0 <= f < 1: over
/// [t_k, t_k+1] it is u_{k-1} then u_k (ZOH), or the lines through u_{k-1}, u_k, u_{k+1}
/// (FOH), so  x_{k+1} = Phi x_k + previous u_{k-1} + current u_k + next u_{k+1}  (the
/// delayed input at t_k itself is delayed_sample()).  Exact: the period is split at
/// t_k + f h and each part discretised as above. f = 0 gives the plain ZOH / FOH weights
/// (previous = 0).
struct DelayedHoldDiscretization {
  Eigen::MatrixXd phi;       ///< e^{A h}
  Eigen::MatrixXd previous;  ///< weight of u_{k-1}
  Eigen::MatrixXd current;   ///< weight of u_k
  Eigen::MatrixXd next;      ///< weight of u_{k+1} (zero for the ZOH)
};

/// The held input delayed by fraction * h at the sample time t_k: previous u_{k-1} +
/// current u_k (u_k itself for f = 0; u_{k-1} for the ZOH; the line between them for the FOH).
struct DelayedSample {
  double previous = 0.0;
  double current = 1.0;
};
DelayedSample delayed_sample(double fraction, Hold hold);

/// A is n x n, B is n x m (any m >= 1); h > 0. Throws InvalidArgument otherwise.
ZohDiscretization discretize_zoh(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double h);
FohDiscretization discretize_foh(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double h);
/// As above, for the input delayed by fraction * h; throws unless 0 <= fraction < 1.
DelayedHoldDiscretization discretize_delayed(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                             double h, double fraction, Hold hold);

/// ZOH equivalent of a SISO realisation: discrete (Phi, Gamma, C, D).
StateSpace discretize_zoh(const StateSpace& model, double h);
/// ZOH equivalent of e^{-f h s} G(s), 0 <= f < 1: for f > 0 one more state holds u_{k-1}
/// (x_{k+1} = Phi x_k + previous u_{k-1} + current u_k, y_k = C x_k + D u_{k-1}).
StateSpace discretize_zoh(const StateSpace& model, double h, double fraction);

}  // namespace ctid
