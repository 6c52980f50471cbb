// What the nonparametric FRFs (SISO frf.cc, MIMO mimo_frf.cc) share: the unnormalised DFT
// of a block, the frequency of a DFT line, the periodic Hann window, the Welch segment
// step and the periodic estimate's choice of lines, so that the MIMO estimate with one input and
// one output is the SISO one.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

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

// The lines of a periodic FRF: without `requested`, every line 1..half that `excited(k)`
// accepts; otherwise the requested lines, sorted and without repeats, each of which must be
// excited (`refuse(k)` throws, naming why it is not).
template <class Excited, class Refuse>
std::vector<int> periodic_lines(std::vector<int> requested, int half, const Excited& excited,
                                const Refuse& refuse) {
  if (requested.empty()) {
    for (int k = 1; k <= half; ++k) {
      if (excited(k)) requested.push_back(k);
    }
    return requested;
  }
  std::sort(requested.begin(), requested.end());
  requested.erase(std::unique(requested.begin(), requested.end()), requested.end());
  for (int k : requested) {
    if (!excited(k)) refuse(k);
  }
  return requested;
}

}  // namespace ctid::internal
