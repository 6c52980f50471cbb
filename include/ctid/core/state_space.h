// Single-input single-output state-space models  dx = A x + B u,  y = C x + D u
// (continuous time, dx = dx/dt) or x_{k+1} = A x_k + B u_k (discrete time).
#pragma once

#include <Eigen/Core>

namespace ctid {

struct StateSpace {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::RowVectorXd c;
  double d = 0.0;

  int order() const { return static_cast<int>(a.rows()); }
  /// Throws InvalidArgument if the dimensions disagree or any entry is not finite.
  void validate() const;
};

}  // namespace ctid
