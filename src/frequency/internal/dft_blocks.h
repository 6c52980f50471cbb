// What the nonparametric FRFs (SISO frf.cc, MIMO mimo_frf.cc) share: the unnormalised DFT
// of a block, the frequency of a DFT line, the periodic Hann window and the Welch segment
// step, so that the MIMO estimate with one input and one output is the SISO one.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Core>
#include <unsupported/Eigen/FFT>

namespace ctid::internal {

// Unnormalised DFT X(k) = sum_n x_n e^{-j 2 pi k n / L} of one block (kissfft backend).
inline Eigen::VectorXcd dft(Eigen::FFT<double>& fft, const Eigen::VectorXd& block) {
  Eigen::VectorXcd spectrum(block.size());
  fft.fwd(spectrum, block);
  return spectrum;
}

inline double line_frequency(int k, int block_length, double sample_time) {
  return 2.0 * std::numbers::pi * k / (block_length * sample_time);
}

// Periodic Hann window: w_n = (1 - cos(2 pi n / L)) / 2.
inline Eigen::VectorXd periodic_hann(int length) {
  Eigen::VectorXd window(length);
  for (int i = 0; i < length; ++i) {
    window(i) = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * i / length);
  }
  return window;
}

// Samples between the starts of consecutive Welch segments.
inline int welch_step(int length, double overlap) {
  const int shared = static_cast<int>(std::lround(overlap * length));
  return std::max(1, length - shared);
}

}  // namespace ctid::internal
