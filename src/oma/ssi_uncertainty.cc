// First-order perturbation of SSI-cov modes (Reynders, Pintelon and De Roeck, MSSP 2008;
// Döhler and Mevel's square-root factor, MSSP 2013): the covariance factor of the Hankel
// matrix from blocks of the record, and each of its columns carried through the SVD, the
// observability matrix, A, the eigenvalue problem and the normalised shape. Decision 0036.
#include "ctid/oma/ssi_uncertainty.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include "ctid/core/error.h"
#include "ctid/oma/ssi_cov.h"

namespace ctid::oma_detail {

Eigen::MatrixXd hankel_covariance_factor(const Eigen::MatrixXd& y,
                                         const std::vector<int>& references, int block_rows,
                                         int blocks) {
  const Eigen::Index length = y.rows() / blocks;
  const Eigen::Index size =
      block_rows * y.cols() * block_rows * static_cast<Eigen::Index>(references.size());
  Eigen::MatrixXd t(size, blocks);
  for (int b = 0; b < blocks; ++b) {
    const Eigen::MatrixXd h = correlation_hankel(
        output_correlations(y.middleRows(b * length, length), references, 2 * block_rows - 1),
        block_rows);
    t.col(b) = Eigen::Map<const Eigen::VectorXd>(h.data(), size);
  }
  const Eigen::VectorXd mean = t.rowwise().mean();
  t.colwise() -= mean;
  return t / std::sqrt(static_cast<double>(blocks) * static_cast<double>(blocks - 1));
}

HankelSvd hankel_svd(const Eigen::MatrixXd& hankel) {
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(hankel, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return {svd.matrixU(), svd.matrixV(), svd.singularValues(), hankel.rows(), hankel.cols()};
}

std::optional<PoleSensitivity> pole_sensitivity(const Eigen::MatrixXd& hankel, int outputs,
                                                int order, double sample_time,
                                                std::complex<double> target,
                                                const Eigen::MatrixXd& directions) {
  return pole_sensitivity(hankel_svd(hankel), outputs, order, sample_time, target, directions);
}

int numerical_rank(const HankelSvd& svd) {
  const Eigen::VectorXd& sv = svd.singular_values;
  return static_cast<int>((sv.array() > 1e-12 * sv(0)).count());
}

std::vector<Eigen::MatrixXd> observability_changes(const HankelSvd& svd, int order,
                                                   const Eigen::MatrixXd& directions) {
  const Eigen::Index m1 = svd.rows;
  const Eigen::Index m2 = svd.cols;
  const Eigen::MatrixXd& u = svd.u;
  const Eigen::MatrixXd& v = svd.v;
  const Eigen::VectorXd& sv = svd.singular_values;
  const Eigen::Index n = std::min(order, numerical_rank(svd));
  std::vector<Eigen::MatrixXd> out;
  if (n < 1) return out;
  const Eigen::VectorXd root = sv.head(n).cwiseSqrt();
  const Eigen::MatrixXd vn = v.leftCols(n);
  const Eigen::MatrixXd un = u.leftCols(n);
  const Eigen::Index kmin = std::min(m1, m2);
  Eigen::MatrixXd coefficients(m1, n);
  Eigen::VectorXd d_sigma(n);
  for (Eigen::Index d = 0; d < directions.cols(); ++d) {
    const Eigen::Map<const Eigen::MatrixXd> dh(directions.col(d).data(), m1, m2);
    // E = U^T ΔH V, only the columns (E_ji) and rows (E_ij) of the n leading triplets.
    const Eigen::MatrixXd e_cols = u.transpose() * (dh * vn);  // m1 x n
    const Eigen::MatrixXd e_rows = (un.transpose() * dh) * v;  // n x m2
    // Δu_i = Σ_{j≠i} u_j (σ_i E_ji + σ_j E_ij) / (σ_i² − σ_j²), σ_j = 0 and E_ij = 0 beyond
    // the matrix's singular values; Δσ_i = E_ii. Column i depends on i alone, not on n.
    for (Eigen::Index i = 0; i < n; ++i) {
      const double si = sv(i);
      d_sigma(i) = e_rows(i, i);
      for (Eigen::Index j = 0; j < m1; ++j) {
        if (j == i) {
          coefficients(j, i) = 0.0;
          continue;
        }
        const double sj = j < kmin ? sv(j) : 0.0;
        const double eij = j < m2 ? e_rows(i, j) : 0.0;
        coefficients(j, i) = (si * e_cols(j, i) + sj * eij) / (si * si - sj * sj);
      }
    }
    out.push_back((u * coefficients) * root.asDiagonal() +
                  un * (0.5 * d_sigma.cwiseQuotient(root)).asDiagonal());
  }
  return out;
}

std::optional<PoleSensitivity> pole_sensitivity(const HankelSvd& svd, int outputs, int order,
                                                double sample_time, std::complex<double> target,
                                                const Eigen::MatrixXd& directions) {
  return pole_sensitivity(svd, outputs, order, sample_time, target,
                          observability_changes(svd, order, directions));
}

std::optional<PoleSensitivity> pole_sensitivity(const HankelSvd& svd, int outputs, int order,
                                                double sample_time, std::complex<double> target,
                                                const std::vector<Eigen::MatrixXd>& changes) {
  using Complex = std::complex<double>;
  const Eigen::Index m1 = svd.rows;
  const Eigen::Index l = outputs;
  const Eigen::MatrixXd& u = svd.u;
  const Eigen::VectorXd& sv = svd.singular_values;
  const Eigen::Index n = std::min(order, numerical_rank(svd));
  if (n < 1) return std::nullopt;
  for (const Eigen::MatrixXd& change : changes) {
    require(change.rows() == m1 && change.cols() >= n, "pole_sensitivity: a change of O has ",
            change.rows(), " x ", change.cols(), " entries; the order needs ", m1, " x ", n);
  }
  // The point of linearisation: O = U_n S_n^{1/2}, A = O_up^† O_down, as ssi_poles computes it.
  const Eigen::VectorXd root = sv.head(n).cwiseSqrt();
  const Eigen::MatrixXd o = u.leftCols(n) * root.asDiagonal();
  const Eigen::Index rows = m1 - l;
  const Eigen::MatrixXd up = o.topRows(rows);
  const Eigen::MatrixXd down = o.bottomRows(rows);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(up);
  const Eigen::MatrixXd a = qr.solve(down);
  const Eigen::MatrixXd residual = down - up * a;
  const Eigen::MatrixXd gram = up.transpose() * up;
  const Eigen::LLT<Eigen::MatrixXd> gram_llt(gram);
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(a);
  const Eigen::VectorXcd lambdas = eig.eigenvalues();
  const Eigen::MatrixXcd vectors = eig.eigenvectors();
  Eigen::Index k = -1;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(lambdas(i).imag() > 0.0)) continue;
    if (k < 0 || std::abs(lambdas(i) - target) < std::abs(lambdas(k) - target)) k = i;
  }
  if (k < 0) return std::nullopt;
  const Eigen::MatrixXcd inverse = vectors.inverse();
  const Complex lambda = lambdas(k);
  const Eigen::VectorXcd psi = vectors.col(k);
  const Eigen::MatrixXd c = o.topRows(l);
  const Eigen::VectorXcd phi = c * psi;
  Eigen::Index largest = 0;
  phi.cwiseAbs().maxCoeff(&largest);
  const Complex phi_m = phi(largest);
  const Complex s = std::log(lambda) / sample_time;
  const double wn = std::abs(s);

  PoleSensitivity out;
  out.lambda = lambda;
  out.frequency_hz = wn / (2.0 * std::numbers::pi);
  out.damping_ratio = -s.real() / wn;
  out.shape = normalise_shape(phi);
  const auto count = static_cast<Eigen::Index>(changes.size());
  out.frequency.resize(count);
  out.damping.resize(count);
  out.shape_change.resize(l, count);

  for (Eigen::Index d = 0; d < count; ++d) {
    const auto d_o = changes[static_cast<std::size_t>(d)].leftCols(n);
    const Eigen::MatrixXd d_up = d_o.topRows(rows);
    const Eigen::MatrixXd d_down = d_o.bottomRows(rows);
    // A = (O_up^T O_up)^{-1} O_up^T O_down: both the fit and the residual terms.
    const Eigen::MatrixXd d_a = qr.solve(Eigen::MatrixXd(d_down - d_up * a)) +
                                gram_llt.solve(Eigen::MatrixXd(d_up.transpose() * residual));
    const Eigen::VectorXcd m = inverse * (d_a.cast<Complex>() * psi);
    const Complex d_lambda = m(k);
    Eigen::VectorXcd d_psi = Eigen::VectorXcd::Zero(n);
    for (Eigen::Index j = 0; j < n; ++j) {
      if (j != k) d_psi += vectors.col(j) * (m(j) / (lambda - lambdas(j)));
    }
    const Eigen::VectorXcd d_phi = d_o.topRows(l).cast<Complex>() * psi + c * d_psi;
    out.shape_change.col(d) = (d_phi - out.shape * d_phi(largest)) / phi_m;
    out.shape_change(largest, d) = 0.0;
    const Complex ds = d_lambda / (lambda * sample_time);
    const double d_wn = (std::conj(s) * ds).real() / wn;
    out.frequency(d) = d_wn / (2.0 * std::numbers::pi);
    out.damping(d) = -ds.real() / wn + s.real() * d_wn / (wn * wn);
  }
  return out;
}

}  // namespace ctid::oma_detail
