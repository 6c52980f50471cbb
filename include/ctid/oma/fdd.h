// The numerical core of frequency-domain decomposition (Brincker, Zhang and Andersen, IMAC
// 2000) and its enhanced form (Brincker, Ventura and Andersen, IMAC 2001): the output spectral
// matrix G(f) = E[Y(f) Y(f)^H] by Welch averaging (periodic Hann window, half overlap, each
// segment's mean removed, one-sided density scaling: scipy.signal.csd's conventions), its
// singular values and first singular vector at every line, the peaks of the first singular
// value, and the single-degree-of-freedom bell whose correlation function gives EFDD's
// frequency and damping.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace ctid::oma_detail {

/// G(f_k) at the lines f_k = k / (L h), k = 0..L/2, of the N x l record.
struct SpectralMatrix {
  Eigen::VectorXd frequency_hz;
  std::vector<Eigen::MatrixXcd> g;  ///< l x l, Hermitian, positive semi-definite
  int segment_length = 0;
  int segments = 0;
};
SpectralMatrix output_spectral_matrix(const Eigen::MatrixXd& y, double sample_time,
                                      int segment_length);

/// Singular values (lines x l, largest first) and the first singular vector at every line.
struct SingularSpectrum {
  Eigen::MatrixXd values;
  std::vector<Eigen::VectorXcd> first_vector;
};
SingularSpectrum singular_spectrum(const SpectralMatrix& spectral);

/// Lines where the first singular value peaks: a local maximum over +-2 lines that stands
/// at least `prominence_db` above the higher of the valleys that separate it from a higher
/// line on either side, with a first singular vector coherent with both neighbours (MAC >= 0.9),
/// away from DC and Nyquist; valleys are taken on the mean over +-2 lines. One peak per bell
/// (MAC >= 0.8 both ways with a higher peak). By frequency.
std::vector<int> singular_value_peaks(const SingularSpectrum& spectrum, double prominence_db);

/// The line of largest first singular value within +-10 % of `frequency_hz`, or -1.
int peak_near(const SingularSpectrum& spectrum, const Eigen::VectorXd& frequency_hz,
              double target_hz);

/// A peak's frequency between lines: a parabola through the log first singular value of the
/// peak line and its neighbours.
double interpolated_peak_hz(const SingularSpectrum& spectrum, const Eigen::VectorXd& frequency_hz,
                            int line);

/// EFDD on the bell around `line`: the lines next to it whose first singular vector has a MAC
/// of at least `mac_limit` with the peak's, their first singular values taken back to the time
/// domain (the window's lag window divided out), the natural frequency from its zero crossings
/// and the damping ratio from the logarithmic decrement of its extrema. NaN when the bell
/// holds fewer than three extrema between 0.9 and 0.1 of its start.
struct BellEstimate {
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  int lines = 0;  ///< lines in the bell
};
BellEstimate efdd_bell(const SingularSpectrum& spectrum, const SpectralMatrix& spectral, int line,
                       double mac_limit, double sample_time);

}  // namespace ctid::oma_detail
