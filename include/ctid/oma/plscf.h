// Poly-reference least-squares complex frequency-domain estimation (pLSCF, "PolyMAX": Guillaume,
// Verboven, Vanlanduit, Van der Auweraer and Peeters, IMAC 2003; Peeters, Van der Auweraer,
// Guillaume and Leuridan, Shock and Vibration 2004) on output-only half-spectra (Cauberghe,
// PhD thesis, VUB 2004): the modes of oma() with OmaMethod::plscf (decision 0066).
//
// The half-spectra are the one-sided transforms of the positive-lag correlations R_1..R_M
// (l outputs x r references), weighted by an exponential window w_k = exp(-beta k h): a sum of
// damped exponentials stays one, every pole moved by -beta, which is added back exactly. A right
// matrix-fraction model S+(z) = B(z) A(z)^{-1}, A(z) = sum_j alpha_j z^j (r x r, alpha_p = I),
// is fitted by linear least squares (the numerators projected out, the denominator's equations
// solved by QR rather than PolyMAX's reduced normal equations, which square their condition
// number); the poles
// are the eigenvalues of A's block companion matrix, s = ln(z)/h + beta; the shapes come from the
// residues of the half-spectra at the poles (least squares with the poles fixed, "LSFD"), each
// residue's leading left singular vector.
#pragma once

#include <complex>
#include <vector>

#include <Eigen/Core>

#include "ctid/oma/ssi_cov.h"

namespace ctid::oma_detail {

/// The windowed half-spectra on lines from 0 to Nyquist, and the basis of the numerators that
/// every polynomial order up to max_order projects out.
struct HalfSpectra {
  double sample_time = 0.0;
  double window_decay = 0.0;  ///< beta [1/s], w_k = exp(-beta k h); removed from every pole
  int references = 0;         ///< r
  int max_order = 0;          ///< largest polynomial order P the sums below serve
  Eigen::VectorXcd z;         ///< e^{i omega h} of every line
  std::vector<Eigen::MatrixXcd> values;  ///< S+(z) per line, l x r
  /// Orthonormal basis of the polynomial columns z^0..z^P over the lines (real parts above
  /// imaginary), 2 lines x (P + 1): its leading columns span those of every lower order.
  Eigen::MatrixXd basis;
};

/// The half-spectra of the correlations R_1..R_M (l x r each) on the M-point grid's lines
/// 0..M/2 (z^M = 1, where the truncated, windowed sum of damped exponentials is exactly
/// rational), and the numerator basis up to polynomial order `max_order`.
HalfSpectra half_spectra(const std::vector<Eigen::MatrixXd>& correlations, double sample_time,
                         int max_order);
/// The same from the mean-removed N x l record `y` against the reference channels `refs`, lags
/// 1..lags (output_correlations).
HalfSpectra half_spectra(const Eigen::MatrixXd& y, const std::vector<int>& refs, int lags,
                         double sample_time, int max_order);

/// The modes of polynomial order `order` (Im z > 0, |z| < 1, 0 < zeta < max_damping after the
/// window's decay is removed), by frequency; shapes normalised as ssi_poles' (decision 0030).
std::vector<ModalPole> plscf_poles(const HalfSpectra& spectra, int order, double max_damping);

}  // namespace ctid::oma_detail
