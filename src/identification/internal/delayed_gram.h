// Gram matrices of delayed copies of sampled signals, as the FIR fit of stage 1 and the
// two-stage covariance form them (decisions 0043, 0072). Private to the identification layer.
#pragma once

#include <Eigen/Core>

namespace ctid::internal {

/// G(i, j) = sum_t x(t - dx - i) y(t - dy - j) over the record's samples t, both signals zero
/// before it, for i < rows and j < cols (x and y of the same length). The first row and
/// column are correlations; each step down the diagonal drops the product of the samples that
/// leave at the record's end, so G is exact in O(N (rows + cols) + rows cols). With the same
/// signal, delay and size it is symmetric to the last bit and its first column is its first
/// row.
Eigen::MatrixXd delayed_gram(const Eigen::VectorXd& x, Eigen::Index dx, Eigen::Index rows,
                             const Eigen::VectorXd& y, Eigen::Index dy, Eigen::Index cols);

}  // namespace ctid::internal
