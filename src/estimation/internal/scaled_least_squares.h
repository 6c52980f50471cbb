// Least squares on regressors with columns scaled to unit norm first (column-pivoted QR), so
// that columns of very different size (filtered derivatives of different order) do not spoil
// the rank decision. Private to the estimator modules: refined_iv's initialisation, mode
// relocation and covariance, and frf_fit's numerator fits use the same scaling.
#pragma once

#include <optional>

#include <Eigen/Dense>

namespace ctid::internal {

/// The square roots of squared column norms, with 1 where the norm is not positive (or NaN),
/// so that dividing by it is always defined: column_scales from sums already formed (the
/// diagonal of x' x, when x is streamed and never held).
inline Eigen::VectorXd scales_from_squared_norms(const Eigen::VectorXd& squares) {
  Eigen::VectorXd s = squares.cwiseSqrt();
  for (Eigen::Index j = 0; j < s.size(); ++j) {
    if (!(s(j) > 0.0)) s(j) = 1.0;
  }
  return s;
}

/// The Euclidean norm of each column of x, with 1 for a column whose norm is not positive
/// (or NaN), so that dividing by it is always defined.
inline Eigen::VectorXd column_scales(const Eigen::MatrixXd& x) {
  return scales_from_squared_norms(x.colwise().squaredNorm().transpose());
}

struct ScaledLeastSquares {
  Eigen::VectorXd coefficients;  ///< minimising |y - x coefficients|
  Eigen::VectorXd residual;      ///< y - x coefficients (formed on the scaled columns)
};

/// Least squares of y on the columns of x, each scaled by column_scales first.
inline ScaledLeastSquares scaled_least_squares(const Eigen::MatrixXd& x, const Eigen::VectorXd& y) {
  const Eigen::VectorXd s = column_scales(x);
  const Eigen::MatrixXd scaled = x * s.cwiseInverse().asDiagonal();
  const Eigen::VectorXd z = scaled.colPivHouseholderQr().solve(y);
  return {z.cwiseQuotient(s), y - scaled * z};
}

/// The instrument equations (sum z phi') theta = sum z upsilon of one refined IV step, with
/// the columns of z and phi scaled by column_scales first; `rcond` gets the reciprocal
/// condition of the scaled matrix. None when a signal is not finite, the matrix is
/// numerically singular (rcond <= 1e-14) or the solution is not finite.
inline std::optional<Eigen::VectorXd> solve_scaled_instrument_equations(
    const Eigen::MatrixXd& z, const Eigen::MatrixXd& phi, const Eigen::VectorXd& upsilon,
    double& rcond) {
  if (!z.allFinite() || !phi.allFinite() || !upsilon.allFinite()) return std::nullopt;
  const Eigen::VectorXd sz = column_scales(z);
  const Eigen::VectorXd sp = column_scales(phi);
  const Eigen::MatrixXd m =
      sz.cwiseInverse().asDiagonal() * (z.transpose() * phi) * sp.cwiseInverse().asDiagonal();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(m);
  const Eigen::VectorXd& sv = svd.singularValues();
  rcond = sv(sv.size() - 1) / sv(0);
  if (!(rcond > 1e-14)) return std::nullopt;
  const Eigen::VectorXd rhs = sz.cwiseInverse().asDiagonal() * (z.transpose() * upsilon);
  Eigen::VectorXd next = sp.cwiseInverse().asDiagonal() * Eigen::VectorXd(m.fullPivLu().solve(rhs));
  if (!next.allFinite()) return std::nullopt;
  return next;
}

}  // namespace ctid::internal
