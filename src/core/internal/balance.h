// Diagonal similarity balancing (Parlett & Reinsch, 1969): find D = diag(2^k) so that the
// rows and columns of D^{-1} A D have comparable norms. Exact in floating point (powers of
// two), it shrinks the spread of companion matrices before eigenvalue computations.
#pragma once

#include <Eigen/Core>

namespace ctid::internal {

/// Returns the diagonal of D; `a` is replaced by D^{-1} A D.
Eigen::VectorXd balance_in_place(Eigen::MatrixXd& a);

}  // namespace ctid::internal
