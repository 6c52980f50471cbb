// First-order perturbation standard errors of SSI-cov modes (Reynders, Pintelon and De Roeck,
// MSSP 2008; in the square-root form of Döhler and Mevel, MSSP 2013): the covariance of the
// Hankel matrix of correlations from n_b blocks of the record, kept as its factor T (one column
// per block, Σ_H = T T^T), and each column of T carried through the SVD, O = U_n S_n^{1/2},
// A = O_up^† O_down, the eigenvalue and eigenvector of the mode, s = ln(λ)/h, f, ζ and the
// normalised shape φ = C ψ / (C ψ)_m (decision 0030). The variance of a quantity q is
// Σ_k (∂q · T_k)². Decision 0036.
#pragma once

#include <complex>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "ctid/oma/ssi_cov.h"

namespace ctid::oma_detail {

/// T = [vec(H_1 - H̄) ... vec(H_nb - H̄)] / sqrt(n_b (n_b - 1)), H_k the Hankel matrix of the
/// k-th of n_b equal consecutive blocks of the record (same references, p and lags as the full
/// estimate), vec column-major: T T^T estimates the covariance of vec H of the whole record.
Eigen::MatrixXd hankel_covariance_factor(const Eigen::MatrixXd& y,
                                         const std::vector<int>& references, int block_rows,
                                         int blocks);

/// A mode of the SSI-cov model of order `order` identified from `hankel`, and the first-order
/// change of its frequency, damping ratio and normalised shape along each direction
/// (column k of `directions` is vec(ΔH_k), column-major).
struct PoleSensitivity {
  std::complex<double> lambda;  ///< discrete pole
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  Eigen::VectorXcd shape;         ///< normalised (decision 0030)
  Eigen::RowVectorXd frequency;   ///< ∂f · ΔH_k, one entry per direction
  Eigen::RowVectorXd damping;     ///< ∂ζ · ΔH_k
  Eigen::MatrixXcd shape_change;  ///< l x directions: ∂φ · ΔH_k (largest entry's row is 0)
};

/// The full SVD of the Hankel matrix (U, S and V), shared by every mode's sensitivities.
struct HankelSvd {
  Eigen::MatrixXd u, v;
  Eigen::VectorXd singular_values;
  Eigen::Index rows = 0, cols = 0;
};
HankelSvd hankel_svd(const Eigen::MatrixXd& hankel);

/// Singular values above 1e-12 times the largest.
int numerical_rank(const HankelSvd& svd);

/// ΔO = ΔU_n S_n^{1/2} + U_n ΔS_n / (2 S_n^{1/2}) (p l x n, n = `order` capped at the numerical
/// rank) along each direction. Column i depends on the i-th triplet alone, so the changes for
/// the largest order serve every lower order (its leading columns): computed once for all the
/// modes of a record.
std::vector<Eigen::MatrixXd> observability_changes(const HankelSvd& svd, int order,
                                                   const Eigen::MatrixXd& directions);

/// The eigenvalue of A (order `order`, capped at the numerical rank as ssi_poles does) with
/// Im λ > 0 nearest `target` (a discrete pole), and its sensitivities; nullopt when A has no
/// such eigenvalue.
std::optional<PoleSensitivity> pole_sensitivity(const HankelSvd& svd, int outputs, int order,
                                                double sample_time, std::complex<double> target,
                                                const Eigen::MatrixXd& directions);
/// The same from the changes of O (observability_changes of this or a higher order).
std::optional<PoleSensitivity> pole_sensitivity(const HankelSvd& svd, int outputs, int order,
                                                double sample_time, std::complex<double> target,
                                                const std::vector<Eigen::MatrixXd>& changes);
/// The same from the Hankel matrix itself.
std::optional<PoleSensitivity> pole_sensitivity(const Eigen::MatrixXd& hankel, int outputs,
                                                int order, double sample_time,
                                                std::complex<double> target,
                                                const Eigen::MatrixXd& directions);

}  // namespace ctid::oma_detail
