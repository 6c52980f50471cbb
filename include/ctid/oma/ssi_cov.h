// The numerical core of covariance-driven SSI (Peeters and De Roeck, MSSP 1999): output
// correlations R_i = E[y_{k+i} y_ref,k^T] for every lag by blocked (overlap-save) FFT, the block
// Hankel matrix H_ij = R_{i+j-1} (from lag 1: R_0 carries the sensor noise), its SVD once, and
// the system matrix of every order from one QR of the largest O_up (Döhler and Mevel, CEP
// 2012, section 3: A_n = R_n^{-1} (Q^T O_down)_n). Poles s = ln(λ)/h, shapes φ = C ψ normalised
// by decision 0030.
#pragma once

#include <complex>
#include <numbers>
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace ctid {
struct OmaMode;  // oma.h
}  // namespace ctid

namespace ctid::oma_detail {

/// R_1..R_max_lag (each l x r) of the mean-removed N x l record, biased estimate (sum / N).
std::vector<Eigen::MatrixXd> output_correlations(const Eigen::MatrixXd& y,
                                                 const std::vector<int>& references, int max_lag);

/// O_up = Q R of the largest order and S = Q^T O_down, from which every order follows.
struct SsiFactor {
  int outputs = 0;
  Eigen::MatrixXd observability;  ///< U S^{1/2}, pl x n_max
  Eigen::MatrixXd r;              ///< n_max x n_max upper triangle of the QR of O_up
  Eigen::MatrixXd s;              ///< Q^T O_down, n_max x n_max
  /// Singular values of H above 1e-12 times the largest: orders beyond this numerical rank
  /// (exact correlations of a low-order model) are identified at the rank instead.
  int rank = 0;
};

/// The p-block-row, p-block-column Hankel matrix H_ij = R_{i+j-1} of R_1..R_{2p-1}.
Eigen::MatrixXd correlation_hankel(const std::vector<Eigen::MatrixXd>& correlations,
                                   int block_rows);

/// Hankel matrix of R_1..R_{2p-1} (p block rows, p block columns), its SVD and the QR.
SsiFactor ssi_factor(const std::vector<Eigen::MatrixXd>& correlations, int block_rows,
                     int max_order);

/// The same from the Hankel matrix itself (pl x pr, `outputs` = l).
SsiFactor hankel_factor(const Eigen::MatrixXd& hankel, int outputs, int max_order);

/// What every SSI variant shares once it has a matrix whose column space is that of the
/// observability matrix (pl rows): from its left singular vectors and singular values,
/// O = U_n S_n^{1/2} of order max_order, the numerical rank and the QR of O_up.
SsiFactor observability_factor(const Eigen::MatrixXd& left_vectors,
                               const Eigen::VectorXd& singular_values, int outputs, int max_order);
/// The QR of O_up and S = Q^T O_down of `f.observability` (f.outputs rows per block), into f.
void shift_factor(SsiFactor& f);

/// One continuous-time mode of one order.
struct ModalPole {
  std::complex<double> s;
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  Eigen::VectorXcd shape;  ///< decision 0030: largest |entry| is exactly 1
  double mpc = 0.0;
  double mpd = 0.0;
};

/// The modes of order n (Im λ > 0, |λ| < 1, 0 < ζ < max_damping), by frequency.
std::vector<ModalPole> ssi_poles(const SsiFactor& factor, int order, double sample_time,
                                 double max_damping);

/// Decision 0030: rotate and scale so the entry of largest modulus is exactly 1.
Eigen::VectorXcd normalise_shape(const Eigen::VectorXcd& shape);
/// A mode's shape as one complex vector, shape_real + i shape_imag.
Eigen::VectorXcd shape_of(const OmaMode& mode);
/// |a^H b|^2 / (|a|^2 |b|^2).
double modal_assurance(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b);
/// Modal phase collinearity (1 for a real shape).
double modal_phase_collinearity(const Eigen::VectorXcd& shape);
/// Mean phase deviation [deg] from the best straight line through the entries.
double mean_phase_deviation(const Eigen::VectorXcd& shape);

/// The continuous pole s with its natural frequency and damping ratio, and the shape `shape()`
/// gives (called only inside the bounds) normalised with its MPC and MPD; none unless
/// 0 < zeta < max_damping and the shape is finite. What every method's poles share.
template <class Shape>
std::optional<ModalPole> modal_pole(std::complex<double> s, double max_damping,
                                    const Shape& shape) {
  ModalPole pole;
  pole.s = s;
  const double wn = std::abs(s);
  pole.damping_ratio = -s.real() / wn;
  if (!(pole.damping_ratio > 0.0 && pole.damping_ratio < max_damping)) return std::nullopt;
  pole.frequency_hz = wn / (2.0 * std::numbers::pi);
  pole.shape = normalise_shape(shape());
  if (!pole.shape.allFinite()) return std::nullopt;
  pole.mpc = modal_phase_collinearity(pole.shape);
  pole.mpd = mean_phase_deviation(pole.shape);
  return pole;
}

/// Sorts poles by natural frequency.
void sort_by_frequency(std::vector<ModalPole>& poles);

}  // namespace ctid::oma_detail
