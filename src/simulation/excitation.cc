// Excitation signals. The multisine is synthesised by one inverse FFT of its line spectrum.
#include "ctid/simulation/excitation.h"

#include <array>
#include <bit>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include <unsupported/Eigen/FFT>

#include "ctid/core/error.h"

namespace ctid {
namespace {

// Feedback taps (1-based bit positions) of maximum-length Fibonacci shift registers; each
// was checked to cycle through all 2^n - 1 non-zero states (the PRBS period test repeats it).
constexpr std::array<std::array<int, 4>, 25> kTaps = {{
    {0, 0, 0, 0},   {0, 0, 0, 0},    {2, 1, 0, 0},   {3, 2, 0, 0},   {4, 3, 0, 0},
    {5, 3, 0, 0},   {6, 5, 0, 0},    {7, 6, 0, 0},   {8, 6, 5, 4},   {9, 5, 0, 0},
    {10, 7, 0, 0},  {11, 9, 0, 0},   {12, 6, 4, 1},  {13, 4, 3, 1},  {14, 5, 3, 1},
    {15, 14, 0, 0}, {16, 15, 13, 4}, {17, 14, 0, 0}, {18, 11, 0, 0}, {19, 6, 2, 1},
    {20, 17, 0, 0}, {21, 19, 0, 0},  {22, 21, 0, 0}, {23, 18, 0, 0}, {24, 23, 22, 17},
}};

void require_length(int length, const char* function) {
  require(length >= 0, function, ": length must be >= 0, got ", length);
}

}  // namespace

Eigen::VectorXd white_noise(int length, double standard_deviation, std::uint64_t seed) {
  require_length(length, "white_noise");
  require(std::isfinite(standard_deviation) && standard_deviation >= 0.0,
          "white_noise: standard_deviation must be finite and >= 0, got ", standard_deviation);
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd e(length);
  for (int k = 0; k < length; ++k) e(k) = standard_deviation * normal(engine);
  return e;
}

void PrbsOptions::check_relations(const std::string& path) const {
  const std::uint64_t states = std::uint64_t{1} << register_length;
  require(initial_state < states, path, ".initial_state is ", initial_state,
          "; it must be < 2^register_length = ", states, " (a non-zero ", register_length,
          "-bit state)");
  require((states - 1) * static_cast<std::uint64_t>(samples_per_bit) <= 0x7fffffffULL, path,
          ".samples_per_bit is ", samples_per_bit,
          "; it must keep the period (2^register_length - 1) * samples_per_bit <= 2^31 - 1");
}

int prbs_period(const PrbsOptions& options) {
  options.validate();
  return ((1 << options.register_length) - 1) * options.samples_per_bit;
}

Eigen::VectorXd prbs(int length, const PrbsOptions& options) {
  options.validate();
  require_length(length, "prbs");
  const int n = options.register_length;
  std::uint64_t mask = 0;
  for (int tap : kTaps[static_cast<std::size_t>(n)]) {
    if (tap > 0) mask |= std::uint64_t{1} << (tap - 1);
  }
  const std::uint64_t full = (std::uint64_t{1} << n) - 1;
  std::uint64_t state = options.initial_state;
  Eigen::VectorXd u(length);
  double level = 0.0;
  for (int k = 0; k < length; ++k) {
    if (k % options.samples_per_bit == 0) {
      const std::uint64_t bit = static_cast<std::uint64_t>(std::popcount(state & mask) & 1);
      state = ((state << 1) | bit) & full;
      level = bit != 0 ? options.amplitude : -options.amplitude;
    }
    u(k) = level;
  }
  return u;
}

void MultisineOptions::check_relations(const std::string& path) const {
  require(max_frequency == 0.0 || max_frequency >= min_frequency, path, ".max_frequency is ",
          max_frequency, "; it must be 0 (Nyquist) or >= min_frequency (", min_frequency, ")");
}

Multisine multisine(const MultisineOptions& options) {
  options.validate();
  const int n = options.period_length;
  const double resolution = 1.0 / (n * options.sample_time);
  const double upper =
      options.max_frequency > 0.0 ? options.max_frequency : 0.5 / options.sample_time;
  // Lines on the band edges count as inside despite rounding of k / (N h).
  const double slack = 1e-9 * resolution;
  Multisine result;
  result.period_length = n;
  for (int k = 1; 2 * k < n; ++k) {
    if (options.grid == FrequencyGrid::odd && k % 2 == 0) continue;
    const double f = k * resolution;
    if (f >= options.min_frequency - slack && f <= upper + slack) result.lines.push_back(k);
  }
  require(!result.lines.empty(), "multisine: no DFT line of ", resolution,
          " Hz spacing falls in the band [", options.min_frequency, ", ", upper,
          "] Hz; widen the band or lengthen period_length");
  const auto count = static_cast<Eigen::Index>(result.lines.size());
  result.amplitude = options.rms * std::sqrt(2.0 / static_cast<double>(count));
  std::mt19937_64 engine(options.seed);
  std::uniform_real_distribution<double> uniform(0.0, 2.0 * std::numbers::pi);
  result.phases.resize(count);
  // X_k = (N A / 2) e^{j phi_k} and its mirror X_{N-k}, so that the inverse DFT (which
  // divides by N) gives A cos(2 pi k n / N + phi_k).
  std::vector<std::complex<double>> spectrum(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < count; ++i) {
    result.phases(i) = uniform(engine);
    const auto k = static_cast<std::size_t>(result.lines[static_cast<std::size_t>(i)]);
    const std::complex<double> line = std::polar(0.5 * n * result.amplitude, result.phases(i));
    spectrum[k] = line;
    spectrum[static_cast<std::size_t>(n) - k] = std::conj(line);
  }
  std::vector<std::complex<double>> period;
  Eigen::FFT<double> fft;
  fft.inv(period, spectrum);
  Eigen::VectorXd one_period(n);
  for (int t = 0; t < n; ++t) one_period(t) = period[static_cast<std::size_t>(t)].real();
  result.signal = repeat_periodic(one_period, options.periods);
  return result;
}

Eigen::VectorXd repeat_periodic(const Eigen::VectorXd& period, int periods) {
  require(periods >= 1, "repeat_periodic: periods must be >= 1, got ", periods);
  return period.replicate(periods, 1);
}

OrthogonalMultisines orthogonal_multisines(const MultisineOptions& options, int inputs) {
  require(inputs >= 1 && inputs <= 64, "orthogonal_multisines: inputs is ", inputs,
          "; it must be in [1, 64]");
  int count = 1;
  while (count < inputs) count *= 2;
  OrthogonalMultisines result;
  result.hadamard.resize(count, count);
  for (int e = 0; e < count; ++e) {
    for (int i = 0; i < count; ++i) {
      result.hadamard(e, i) = std::popcount(static_cast<unsigned>(e & i)) % 2 == 0 ? 1.0 : -1.0;
    }
  }
  std::vector<Eigen::VectorXd> signals;
  for (int i = 0; i < inputs; ++i) {
    MultisineOptions own = options;
    own.seed = options.seed + static_cast<std::uint64_t>(i);
    Multisine s = multisine(own);
    if (i == 0) result.lines = s.lines;
    signals.push_back(std::move(s.signal));
  }
  for (int e = 0; e < count; ++e) {
    Eigen::MatrixXd u(signals.front().size(), inputs);
    for (int i = 0; i < inputs; ++i) {
      u.col(i) = result.hadamard(e, i) * signals[static_cast<std::size_t>(i)];
    }
    result.experiments.push_back(std::move(u));
  }
  return result;
}

}  // namespace ctid
