#include "ctid/oma/fdd.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <utility>

#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/FFT>

#include "ctid/core/error.h"
#include "ctid/oma/ssi_cov.h"
#include "frequency/internal/dft_blocks.h"

namespace ctid::oma_detail {

namespace {

constexpr double kNeighbourMac = 0.9;
constexpr int kPeakHalfWidth = 2;
constexpr double kSameModeMac = 0.8;

// A straight line's slope through (x_k, y_k), least squares.
double slope(const std::vector<double>& x, const std::vector<double>& y) {
  const auto n = static_cast<double>(x.size());
  double mx = 0.0, my = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    mx += x[k] / n;
    my += y[k] / n;
  }
  double sxy = 0.0, sxx = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sxy += (x[k] - mx) * (y[k] - my);
    sxx += (x[k] - mx) * (x[k] - mx);
  }
  return sxy / sxx;
}

// The bell's correlation function r(n), n = 0..L/2 - 1, normalised to r(0) = 1, with the
// Welch estimate's lag window (the Hann window's autocorrelation) divided out.
Eigen::VectorXd bell_correlation(const Eigen::VectorXd& bell, int length) {
  Eigen::VectorXcd full = Eigen::VectorXcd::Zero(length);
  for (int j = 0; j <= length / 2; ++j) {
    full(j) = bell(j);
    if (j > 0 && j < length - j) full(length - j) = bell(j);
  }
  Eigen::FFT<double> fft;
  Eigen::VectorXcd back(length);
  fft.inv(back, full);
  const Eigen::VectorXd w = internal::periodic_hann(length);
  const double w0 = w.squaredNorm();
  Eigen::VectorXd r(length / 2);
  for (int n = 0; n < length / 2; ++n) {
    const double lag = w.head(length - n).dot(w.tail(length - n)) / w0;
    r(n) = back(n).real() / lag;
  }
  return r / r(0);
}

// The lines next to `line` whose first singular vector has a MAC of at least `mac_limit` with
// line's: the first and last of them.
std::pair<int, int> bell_of(const SingularSpectrum& spectrum, int line, double mac_limit) {
  const auto lines = static_cast<int>(spectrum.values.rows());
  const auto& u = spectrum.first_vector;
  const auto at = [](int i) { return static_cast<std::size_t>(i); };
  int lo = line, hi = line;
  while (lo > 1 && modal_assurance(u[at(lo - 1)], u[at(line)]) >= mac_limit) --lo;
  while (hi < lines - 2 && modal_assurance(u[at(hi + 1)], u[at(line)]) >= mac_limit) ++hi;
  return {lo, hi};
}

// One peak per mode: a peak whose bell and a higher peak's bell hold each other's line (MAC
// >= 0.8; a noisy resonance seen at fine resolution has several local maxima) is that mode
// again. Close modes of different shapes keep their own peaks, as the MAC drops between them.
std::vector<int> distinct_bells(const SingularSpectrum& spectrum, std::vector<int> peaks) {
  std::sort(peaks.begin(), peaks.end(),
            [&](int a, int b) { return spectrum.values(a, 0) > spectrum.values(b, 0); });
  std::vector<int> kept;
  std::vector<std::pair<int, int>> bells;
  for (const int k : peaks) {
    const std::pair<int, int> own = bell_of(spectrum, k, kSameModeMac);
    bool same = false;
    for (std::size_t i = 0; i < kept.size() && !same; ++i) {
      same = (k >= bells[i].first && k <= bells[i].second) ||
             (kept[i] >= own.first && kept[i] <= own.second);
    }
    if (same) continue;
    kept.push_back(k);
    bells.push_back(own);
  }
  std::sort(kept.begin(), kept.end());
  return kept;
}

}  // namespace

SpectralMatrix output_spectral_matrix(const Eigen::MatrixXd& y, double sample_time,
                                      int segment_length) {
  const int n = static_cast<int>(y.rows());
  const int l = static_cast<int>(y.cols());
  const int length = segment_length;
  require(length >= 16 && length <= n, "the segment length is ", length,
          " samples; it must lie within 16..", n, " (the record)");
  const int step = internal::welch_step(length, 0.5);
  const int segments = (n - length) / step + 1;
  const Eigen::VectorXd window = internal::periodic_hann(length);
  const int lines = length / 2 + 1;
  SpectralMatrix s;
  s.segment_length = length;
  s.segments = segments;
  s.frequency_hz = Eigen::VectorXd::LinSpaced(lines, 0.0, lines - 1.0) / (length * sample_time);
  s.g.assign(static_cast<std::size_t>(lines), Eigen::MatrixXcd::Zero(l, l));
  Eigen::FFT<double> fft;
  Eigen::MatrixXcd spectra(lines, l);
  for (int q = 0; q < segments; ++q) {
    for (int j = 0; j < l; ++j) {
      Eigen::VectorXd block = y.col(j).segment(q * step, length);
      block.array() -= block.mean();
      spectra.col(j) = internal::dft(fft, block.cwiseProduct(window)).head(lines);
    }
    for (int k = 0; k < lines; ++k) {
      s.g[static_cast<std::size_t>(k)] += spectra.row(k).transpose() * spectra.row(k).conjugate();
    }
  }
  // One-sided density: 1 / (fs sum w^2) per segment, doubled except at DC and Nyquist.
  const double scale = sample_time / (window.squaredNorm() * segments);
  for (int k = 0; k < lines; ++k) {
    const bool edge = k == 0 || (length % 2 == 0 && k == lines - 1);
    s.g[static_cast<std::size_t>(k)] *= (edge ? 1.0 : 2.0) * scale;
  }
  return s;
}

SingularSpectrum singular_spectrum(const SpectralMatrix& spectral) {
  const auto lines = static_cast<Eigen::Index>(spectral.g.size());
  const Eigen::Index l = lines > 0 ? spectral.g.front().rows() : 0;
  SingularSpectrum s;
  s.values.resize(lines, l);
  s.first_vector.reserve(static_cast<std::size_t>(lines));
  for (Eigen::Index k = 0; k < lines; ++k) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> eig(
        spectral.g[static_cast<std::size_t>(k)]);
    s.values.row(k) = eig.eigenvalues().reverse().cwiseMax(0.0).transpose();
    s.first_vector.push_back(eig.eigenvectors().col(l - 1));
  }
  return s;
}

std::vector<int> singular_value_peaks(const SingularSpectrum& spectrum, double prominence_db) {
  const Eigen::VectorXd s1 = spectrum.values.col(0);
  const int lines = static_cast<int>(s1.size());
  const double ratio = std::pow(10.0, prominence_db / 10.0);
  Eigen::VectorXd smooth = s1;  // the mean over +-kPeakHalfWidth lines
  for (int k = kPeakHalfWidth; k < lines - kPeakHalfWidth; ++k) {
    smooth(k) = s1.segment(k - kPeakHalfWidth, 2 * kPeakHalfWidth + 1).mean();
  }
  std::vector<int> peaks;
  for (int k = kPeakHalfWidth; k < lines - kPeakHalfWidth; ++k) {
    if (!(s1(k) > 0.0)) continue;
    bool local_max = true;
    for (int d = 1; d <= kPeakHalfWidth && local_max; ++d) {
      local_max = s1(k) >= s1(k - d) && s1(k) > s1(k + d);
    }
    if (!local_max) continue;
    // The valley on each side: the lowest of the smoothed values before a higher line (or the
    // band's edge). Smoothed, as the deepest of many single lines is a dip of the estimate's
    // scatter, which would make noise bumps prominent.
    double left = s1(k), right = s1(k);
    for (int j = k - 1; j >= 1 && s1(j) <= s1(k); --j) left = std::min(left, smooth(j));
    for (int j = k + 1; j < lines - 1 && s1(j) <= s1(k); ++j) right = std::min(right, smooth(j));
    if (s1(k) < ratio * std::max(left, right)) continue;
    const auto& u = spectrum.first_vector;
    const auto at = [](int i) { return static_cast<std::size_t>(i); };
    if (modal_assurance(u[at(k)], u[at(k - 1)]) < kNeighbourMac ||
        modal_assurance(u[at(k)], u[at(k + 1)]) < kNeighbourMac) {
      continue;
    }
    peaks.push_back(k);
  }
  return distinct_bells(spectrum, peaks);
}

int peak_near(const SingularSpectrum& spectrum, const Eigen::VectorXd& frequency_hz,
              double target_hz) {
  int best = -1;
  for (Eigen::Index k = 1; k + 1 < frequency_hz.size(); ++k) {
    if (std::abs(frequency_hz(k) - target_hz) > 0.1 * target_hz) continue;
    if (best < 0 || spectrum.values(k, 0) > spectrum.values(best, 0)) best = static_cast<int>(k);
  }
  return best;
}

double interpolated_peak_hz(const SingularSpectrum& spectrum, const Eigen::VectorXd& frequency_hz,
                            int line) {
  const double a = std::log(spectrum.values(line - 1, 0));
  const double b = std::log(spectrum.values(line, 0));
  const double c = std::log(spectrum.values(line + 1, 0));
  const double curvature = a - 2.0 * b + c;
  const double offset = curvature < 0.0 ? std::clamp(0.5 * (a - c) / curvature, -0.5, 0.5) : 0.0;
  return frequency_hz(line) + offset * (frequency_hz(1) - frequency_hz(0));
}

BellEstimate efdd_bell(const SingularSpectrum& spectrum, const SpectralMatrix& spectral, int line,
                       double mac_limit, double sample_time) {
  const auto lines = static_cast<int>(spectrum.values.rows());
  const auto [lo, hi] = bell_of(spectrum, line, mac_limit);
  Eigen::VectorXd bell = Eigen::VectorXd::Zero(lines);
  bell.segment(lo, hi - lo + 1) = spectrum.values.col(0).segment(lo, hi - lo + 1);
  const Eigen::VectorXd r = bell_correlation(bell, spectral.segment_length);

  // Zero crossings (fractional samples) and the extremum of |r| between consecutive ones.
  std::vector<double> crossings, extrema;
  for (Eigen::Index n = 0; n + 1 < r.size(); ++n) {
    if ((r(n) > 0.0) != (r(n + 1) > 0.0)) {
      crossings.push_back(static_cast<double>(n) + r(n) / (r(n) - r(n + 1)));
    }
  }
  for (std::size_t c = 0; c + 1 < crossings.size(); ++c) {
    const auto from = static_cast<Eigen::Index>(std::ceil(crossings[c]));
    const auto to = static_cast<Eigen::Index>(std::floor(crossings[c + 1]));
    if (to < from) continue;
    extrema.push_back(r.segment(from, to - from + 1).cwiseAbs().maxCoeff());
  }
  // The extrema between 0.9 and 0.1 of r(0), with the crossings around them.
  std::vector<double> index, log_extremum, crossing_index, crossing_time;
  for (std::size_t e = 0; e < extrema.size(); ++e) {
    if (extrema[e] < 0.1) break;
    if (extrema[e] > 0.9) continue;
    index.push_back(static_cast<double>(e));
    log_extremum.push_back(std::log(extrema[e]));
    for (std::size_t c : {e, e + 1}) {
      if (crossing_index.empty() || crossing_index.back() < static_cast<double>(c)) {
        crossing_index.push_back(static_cast<double>(c));
        crossing_time.push_back(crossings[c]);
      }
    }
  }
  BellEstimate estimate;
  estimate.lines = hi - lo + 1;
  if (index.size() < 3) {
    estimate.frequency_hz = estimate.damping_ratio = std::numeric_limits<double>::quiet_NaN();
    return estimate;
  }
  const double decrement = -2.0 * slope(index, log_extremum);  // extrema every half cycle
  estimate.damping_ratio =
      decrement / std::sqrt(4.0 * std::numbers::pi * std::numbers::pi + decrement * decrement);
  const double half_period = slope(crossing_index, crossing_time) * sample_time;
  const double damped_hz = 1.0 / (2.0 * half_period);
  estimate.frequency_hz =
      damped_hz / std::sqrt(1.0 - estimate.damping_ratio * estimate.damping_ratio);
  return estimate;
}

}  // namespace ctid::oma_detail
