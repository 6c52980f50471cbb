#include "ctid/frequency/periodogram.h"

#include <algorithm>
#include <complex>
#include <cstddef>

#include <unsupported/Eigen/FFT>

#include "ctid/core/error.h"

namespace ctid {

Eigen::VectorXd periodogram(const Eigen::VectorXd& x, int zero_padding) {
  require(zero_padding >= 1, "periodogram: zero_padding is ", zero_padding, "; it must be >= 1");
  const Eigen::Index n = x.size();
  const Eigen::Index length = n * zero_padding;
  if (length < 2) return Eigen::VectorXd(0);  // no bin below Nyquist (and kissfft needs 2)
  Eigen::VectorXd padded = Eigen::VectorXd::Zero(length);
  padded.head(n) = x;
  Eigen::FFT<double> fft;
  Eigen::VectorXcd spectrum;
  fft.fwd(spectrum, padded);
  const Eigen::Index half = length / 2;
  Eigen::VectorXd power(half);
  for (Eigen::Index k = 0; k < half; ++k) power(k) = std::norm(spectrum(k));
  return power;
}

Eigen::VectorXd running_median(const Eigen::VectorXd& power, Eigen::Index lines,
                               Eigen::Index half_width, Eigen::Index stride) {
  require(half_width >= 1, "running_median: half_width is ", half_width, "; it must be >= 1");
  require(stride >= 1, "running_median: stride is ", stride, "; it must be >= 1");
  require(lines <= 1 || (lines - 1) * stride < power.size(), "running_median: ", lines,
          " lines at stride ", stride, " need ", (lines - 1) * stride + 1, " bins; power has ",
          power.size());
  Eigen::VectorXd out = Eigen::VectorXd::Zero(std::max<Eigen::Index>(lines, 1));
  std::vector<double> window;
  for (Eigen::Index j = 1; j < lines; ++j) {
    window.clear();
    const Eigen::Index lo = std::max<Eigen::Index>(1, j - half_width);
    const Eigen::Index hi = std::min<Eigen::Index>(lines - 1, j + half_width);
    for (Eigen::Index i = lo; i <= hi; ++i) window.push_back(power(i * stride));
    const auto mid = window.begin() + static_cast<std::ptrdiff_t>(window.size() / 2);
    std::nth_element(window.begin(), mid, window.end());
    out(j) = *mid;
  }
  return out;
}

std::vector<bool> excited_band(const Eigen::VectorXd& x, Eigen::Index half_width,
                               double min_level) {
  require(min_level >= 0.0 && min_level <= 1.0, "excited_band: min_level is ", min_level,
          "; it must be in [0, 1]");
  const Eigen::Index lines = x.size() / 2;
  const Eigen::VectorXd level = running_median(periodogram(x), lines, half_width);
  const double top = level.maxCoeff();
  std::vector<bool> out(static_cast<std::size_t>(std::max<Eigen::Index>(lines, 1)), false);
  for (Eigen::Index j = 1; j < lines; ++j) {
    out[static_cast<std::size_t>(j)] = top > 0.0 && level(j) >= min_level * top;
  }
  return out;
}

}  // namespace ctid
