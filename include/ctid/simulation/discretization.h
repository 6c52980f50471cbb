// Exact discretisation of continuous-time state equations dx/dt = A x + B u over one
// sample period h, through the matrix exponential of an augmented matrix, so that it holds
// for singular A (integrators) and stiff models alike (never A^{-1}(e^{Ah} - I)B).
//  ZOH (u constant on [t_k, t_k+1)):  x_{k+1} = Phi x_k + Gamma u_k
//  FOH (u linear on [t_k, t_k+1]):    x_{k+1} = Phi x_k + Gamma0 u_k + Gamma1 u_{k+1}
#pragma once

#include <Eigen/Core>

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

/// A is n x n, B is n x m (any m >= 1); h > 0. Throws InvalidArgument otherwise.
ZohDiscretization discretize_zoh(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double h);
FohDiscretization discretize_foh(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double h);

/// ZOH equivalent of a SISO realisation: discrete (Phi, Gamma, C, D).
StateSpace discretize_zoh(const StateSpace& model, double h);

}  // namespace ctid
