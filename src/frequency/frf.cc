#include "ctid/frequency/frf.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <string>

#include "ctid/core/error.h"
#include "ctid/frequency/peaks.h"
#include "frequency/internal/dft_blocks.h"

namespace ctid {
namespace {

using Complex = std::complex<double>;

using internal::dft;
using internal::line_frequency;

// At most `max_peaks` (0: all) of the most prominent peaks, in the order of their index.
void keep_most_prominent(std::vector<ResonancePeak>& peaks, int max_peaks) {
  if (max_peaks <= 0 || static_cast<int>(peaks.size()) <= max_peaks) return;
  std::stable_sort(peaks.begin(), peaks.end(),
                   [](const auto& a, const auto& b) { return a.prominence_db > b.prominence_db; });
  peaks.resize(static_cast<size_t>(max_peaks));
  std::sort(peaks.begin(), peaks.end(),
            [](const auto& a, const auto& b) { return a.index < b.index; });
}

}  // namespace

void PeriodicFrfOptions::check_relations(const std::string& path) const {
  for (std::size_t i = 0; i < lines.size(); ++i) {
    require(lines[i] <= period_length / 2, path, ".lines[", i, "] is ", lines[i],
            "; it must be <= period_length/2 = ", period_length / 2);
  }
}

Frf periodic_frf(const SampledData& data, const PeriodicFrfOptions& options) {
  options.validate();
  const int n = options.period_length;
  const int total = data.size();
  require(total % n == 0, "periodic_frf: the record length ", total,
          " is not a multiple of period_length ", n);
  const int periods = total / n - options.transient_periods;
  require(periods >= 2, "periodic_frf: too few samples: ", total, " samples hold ", total / n,
          " periods of ", n, "; after dropping transient_periods = ", options.transient_periods,
          " at least 2 must remain");

  Eigen::FFT<double> fft;
  std::vector<Eigen::VectorXcd> u_spectra;
  std::vector<Eigen::VectorXcd> y_spectra;
  Eigen::VectorXcd u_mean = Eigen::VectorXcd::Zero(n);
  for (int p = 0; p < periods; ++p) {
    const int begin = (options.transient_periods + p) * n;
    u_spectra.push_back(dft(fft, data.input().segment(begin, n)));
    y_spectra.push_back(dft(fft, data.output().segment(begin, n)));
    u_mean += u_spectra.back();
  }
  u_mean /= periods;

  const int half = n / 2;
  double largest = 0.0;
  for (int k = 1; k <= half; ++k) largest = std::max(largest, std::abs(u_mean(k)));
  require(largest > 0.0, "periodic_frf: the input has no power at any line 1..", half);
  const double threshold = options.line_threshold * largest;
  const auto excited = [&](int k) {
    if (std::abs(u_mean(k)) <= threshold) return false;
    for (const auto& u : u_spectra) {
      if (std::abs(u(k)) == 0.0) return false;
    }
    return true;
  };

  Frf result;
  result.averages = periods;
  result.block_length = n;
  result.lines = internal::periodic_lines(options.lines, half, excited, [&](int k) {
    throw InvalidArgument(internal::concat(
        "periodic_frf: line ", k,
        " requested in PeriodicFrfOptions.lines is not excited by the input (|U| = ",
        std::abs(u_mean(k)), ", threshold ", threshold, ")"));
  });

  const auto count = static_cast<Eigen::Index>(result.lines.size());
  result.frequencies.resize(count);
  result.response.resize(count);
  result.variance.resize(count);
  result.coherence.resize(count);
  result.input_level.resize(count);
  Eigen::VectorXcd per_period(periods);
  for (Eigen::Index i = 0; i < count; ++i) {
    const int k = result.lines[static_cast<size_t>(i)];
    double suu = 0.0;
    double syy = 0.0;
    Complex syu = 0.0;
    for (int p = 0; p < periods; ++p) {
      const auto q = static_cast<size_t>(p);
      const Complex u = u_spectra[q](k);
      const Complex y = y_spectra[q](k);
      per_period(p) = y / u;
      suu += std::norm(u);
      syy += std::norm(y);
      syu += y * std::conj(u);
    }
    const Complex mean = per_period.mean();
    result.frequencies(i) = line_frequency(k, n, data.sample_time());
    result.response(i) = mean;
    // Sample variance over periods, divided by P for the variance of the mean.
    result.variance(i) = (per_period.array() - mean).abs2().sum() / (periods - 1) / periods;
    // Over the periods of a periodic input this is |mean Y|^2 / mean |Y|^2: the share of the
    // output's power at the line that repeats with the input.
    result.coherence(i) = syy == 0.0 ? 0.0 : std::min(std::norm(syu) / (suu * syy), 1.0);
    result.input_level(i) = std::abs(u_mean(k)) / largest;
  }
  return result;
}

int default_segment_length(int samples) {
  int length = 8;
  while (length * 2 <= samples / 8 && length < 4096) length *= 2;
  return std::min(length, samples);
}

Frf welch_frf(const SampledData& data, const WelchOptions& options) {
  options.validate();
  const int length = options.segment_length;
  const int total = data.size();
  require(total >= length, "welch_frf: too few samples: the record has ", total,
          " samples, fewer than WelchOptions.segment_length = ", length);
  const int step = internal::welch_step(length, options.overlap);
  const Eigen::VectorXd window = internal::periodic_hann(length);

  const int half = length / 2;
  Eigen::VectorXd suu = Eigen::VectorXd::Zero(half + 1);
  Eigen::VectorXd syy = Eigen::VectorXd::Zero(half + 1);
  Eigen::VectorXcd syu = Eigen::VectorXcd::Zero(half + 1);
  Eigen::FFT<double> fft;
  int segments = 0;
  for (int begin = 0; begin + length <= total; begin += step) {
    const Eigen::VectorXcd u =
        dft(fft, data.input().segment(begin, length).cwiseProduct(window).eval());
    const Eigen::VectorXcd y =
        dft(fft, data.output().segment(begin, length).cwiseProduct(window).eval());
    for (int k = 1; k <= half; ++k) {
      suu(k) += std::norm(u(k));
      syy(k) += std::norm(y(k));
      syu(k) += y(k) * std::conj(u(k));
    }
    ++segments;
  }

  Frf result;
  result.averages = segments;
  result.block_length = length;
  result.frequencies.resize(half);
  result.response.resize(half);
  result.variance.resize(half);
  result.coherence.resize(half);
  result.input_level.resize(half);
  const double largest = suu.tail(half).maxCoeff();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 1; k <= half; ++k) {
    const int i = k - 1;
    result.lines.push_back(k);
    result.frequencies(i) = line_frequency(k, length, data.sample_time());
    result.input_level(i) = largest > 0.0 ? std::sqrt(suu(k) / largest) : 0.0;
    if (suu(k) == 0.0) {
      result.response(i) = Complex(nan, nan);
      result.coherence(i) = 0.0;
      result.variance(i) = nan;
      continue;
    }
    result.response(i) = syu(k) / suu(k);
    const double coherence = syy(k) == 0.0 ? 0.0 : std::norm(syu(k)) / (suu(k) * syy(k));
    result.coherence(i) = std::min(coherence, 1.0);
    result.variance(i) = coherence == 0.0 ? std::numeric_limits<double>::infinity()
                                          : (1.0 - result.coherence(i)) / (coherence * segments) *
                                                std::norm(result.response(i));
  }
  return result;
}

std::vector<ResonancePeak> resonance_peaks(const Eigen::VectorXd& frequencies,
                                           const Eigen::VectorXcd& response,
                                           const PeakOptions& options) {
  options.validate();
  const auto size = frequencies.size();
  require(size == response.size(), "resonance_peaks: ", size, " frequencies but ", response.size(),
          " response values");
  require(size >= 3, "resonance_peaks: needs at least 3 points, got ", size);
  for (Eigen::Index i = 0; i < size; ++i) {
    require(std::isfinite(frequencies(i)), "resonance_peaks: frequencies[", i,
            "] = ", frequencies(i), " is not finite");
    require(i == 0 || frequencies(i) > frequencies(i - 1), "resonance_peaks: frequencies[", i,
            "] = ", frequencies(i), " does not exceed the one before; they must increase");
    require(std::isfinite(response(i).real()) && std::isfinite(response(i).imag()),
            "resonance_peaks: response[", i, "] is not finite");
  }
  const Eigen::VectorXd magnitude = response.cwiseAbs();
  Eigen::VectorXd db(size);
  for (Eigen::Index i = 0; i < size; ++i) {
    db(i) = 20.0 * std::log10(std::max(magnitude(i), std::numeric_limits<double>::min()));
  }

  std::vector<ResonancePeak> peaks;
  for (Eigen::Index i = 1; i + 1 < size; ++i) {
    if (!is_local_maximum(db, i)) continue;
    ResonancePeak peak;
    peak.index = static_cast<int>(i);
    peak.magnitude = magnitude(i);
    peak.prominence_db = prominence(db, i);
    if (peak.prominence_db < options.min_prominence_db) continue;
    // Vertex of the parabola through the three points (w, dB) around the maximum.
    peak.frequency = parabolic_vertex(frequencies(i - 1), frequencies(i), frequencies(i + 1),
                                      db(i - 1), db(i), db(i + 1));

    // Half-power points, linearly interpolated in frequency.
    const double half_power = magnitude(i) / std::sqrt(2.0);
    double lower = std::numeric_limits<double>::quiet_NaN();
    for (Eigen::Index j = i - 1; j >= 0; --j) {
      if (magnitude(j) < half_power) {
        const double t = (half_power - magnitude(j)) / (magnitude(j + 1) - magnitude(j));
        lower = frequencies(j) + t * (frequencies(j + 1) - frequencies(j));
        break;
      }
    }
    double upper = std::numeric_limits<double>::quiet_NaN();
    for (Eigen::Index j = i + 1; j < size; ++j) {
      if (magnitude(j) < half_power) {
        const double t = (magnitude(j - 1) - half_power) / (magnitude(j - 1) - magnitude(j));
        upper = frequencies(j - 1) + t * (frequencies(j) - frequencies(j - 1));
        break;
      }
    }
    peak.damping_ratio = (upper - lower) / (2.0 * peak.frequency);
    peaks.push_back(peak);
  }

  keep_most_prominent(peaks, options.max_peaks);
  return peaks;
}

namespace {

// Positions of the lines of `frf` whose input_level exceeds `line_threshold` (every line when
// it has none), after checking that its vectors agree in size; `caller` names the function.
std::vector<Eigen::Index> excited_positions(const Frf& frf, double line_threshold,
                                            const char* caller) {
  require(line_threshold >= 0.0 && line_threshold < 1.0, caller, ": line_threshold is ",
          line_threshold, "; it must be in [0, 1)");
  const Eigen::Index size = frf.frequencies.size();
  const auto check_size = [&](Eigen::Index other, const char* name, bool optional) {
    require(other == size || (optional && other == 0), caller, ": the FRF has ", size,
            " frequencies but ", other, " ", name);
  };
  check_size(static_cast<Eigen::Index>(frf.lines.size()), "lines", false);
  check_size(frf.response.size(), "response values", false);
  check_size(frf.variance.size(), "variances", false);
  check_size(frf.coherence.size(), "coherences", true);
  check_size(frf.input_level.size(), "input levels", true);
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < size; ++i) {
    if (frf.input_level.size() == 0 || frf.input_level(i) > line_threshold) kept.push_back(i);
  }
  return kept;
}

}  // namespace

Frf excited_lines(const Frf& frf, double line_threshold) {
  const std::vector<Eigen::Index> kept = excited_positions(frf, line_threshold, "excited_lines");
  if (frf.input_level.size() == 0) return frf;
  const auto count = static_cast<Eigen::Index>(kept.size());
  Frf result;
  result.averages = frf.averages;
  result.block_length = frf.block_length;
  result.frequencies.resize(count);
  result.response.resize(count);
  result.variance.resize(count);
  result.input_level.resize(count);
  if (frf.coherence.size() > 0) result.coherence.resize(count);
  for (Eigen::Index j = 0; j < count; ++j) {
    const Eigen::Index i = kept[static_cast<size_t>(j)];
    result.lines.push_back(frf.lines[static_cast<size_t>(i)]);
    result.frequencies(j) = frf.frequencies(i);
    result.response(j) = frf.response(i);
    result.variance(j) = frf.variance(i);
    result.input_level(j) = frf.input_level(i);
    if (frf.coherence.size() > 0) result.coherence(j) = frf.coherence(i);
  }
  return result;
}

std::vector<ResonancePeak> resonance_peaks(const Frf& frf, const PeakOptions& options) {
  options.validate();
  // The excited lines, less those where Y/U could not be formed (no input power at all).
  std::vector<Eigen::Index> searched;
  for (Eigen::Index i : excited_positions(frf, options.line_threshold, "resonance_peaks")) {
    if (std::isfinite(frf.response(i).real()) && std::isfinite(frf.response(i).imag())) {
      searched.push_back(i);
    }
  }
  const auto count = static_cast<Eigen::Index>(searched.size());
  if (count < 3) return {};
  Eigen::VectorXd frequencies(count);
  Eigen::VectorXcd response(count);
  for (Eigen::Index j = 0; j < count; ++j) {
    frequencies(j) = frf.frequencies(searched[static_cast<size_t>(j)]);
    response(j) = frf.response(searched[static_cast<size_t>(j)]);
  }
  PeakOptions all = options;
  all.max_peaks = 0;
  std::vector<ResonancePeak> peaks;
  for (ResonancePeak peak : resonance_peaks(frequencies, response, all)) {
    const Eigen::Index i = searched[static_cast<size_t>(peak.index)];
    if (frf.coherence.size() > 0) {
      peak.coherence = frf.coherence(i);
      if (peak.coherence < options.min_coherence) continue;
    }
    if (frf.input_level.size() > 0) peak.input_level = frf.input_level(i);
    peak.index = static_cast<int>(i);  // the position in the caller's FRF
    peaks.push_back(peak);
  }
  keep_most_prominent(peaks, options.max_peaks);
  return peaks;
}

}  // namespace ctid
