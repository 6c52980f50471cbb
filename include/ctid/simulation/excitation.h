// Excitation signals for identification experiments: seeded Gaussian white noise,
// maximum-length PRBS (period 2^n - 1 from an n-bit linear feedback shift register) and
// random-phase multisines with a flat amplitude spectrum on a band of DFT lines k / (N h) Hz
// (González et al. Section 7 uses one flat from 0.5 to 500 Hz). Every random signal takes a
// seed for std::mt19937_64, so the same seed gives the same signal.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"

namespace ctid {

/// `length` samples of zero-mean Gaussian white noise with the given standard deviation.
Eigen::VectorXd white_noise(int length, double standard_deviation, std::uint64_t seed);

struct PrbsOptions {
  int register_length = 10;         ///< n in [2, 24]; the bit sequence has period 2^n - 1
  double amplitude = 1.0;           ///< levels +amplitude (bit 1) and -amplitude (bit 0)
  int samples_per_bit = 1;          ///< each bit is held this many samples
  std::uint64_t initial_state = 1;  ///< register start, 1 <= state < 2^n; shifts the sequence

  static constexpr std::string_view type_name = "PrbsOptions";
  static constexpr auto fields() {
    using O = PrbsOptions;
    return std::tuple{
        field("register_length", &O::register_length, Between{2, 24, true, true},
              "n: the bit sequence has period 2^n - 1."),
        field("amplitude", &O::amplitude, Finite{GreaterThan{0}},
              "Levels +amplitude (bit 1) and -amplitude (bit 0)."),
        field("samples_per_bit", &O::samples_per_bit, AtLeast{1},
              "Each bit is held this many samples."),
        field("initial_state", &O::initial_state, AtLeast{1},
              "Register start, below 2^n; shifts the sequence."),
    };
  }
  /// initial_state < 2^register_length; the period fits in an int.
  void check_relations(const std::string& path) const;
  /// Throws InvalidArgument naming the first bad field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// Samples per period, (2^n - 1) * samples_per_bit.
int prbs_period(const PrbsOptions& options);
/// `length` samples of a maximum-length PRBS. Each period holds 2^(n-1) bits at +amplitude and
/// 2^(n-1) - 1 at -amplitude.
Eigen::VectorXd prbs(int length, const PrbsOptions& options = {});

enum class FrequencyGrid {
  full,  ///< every DFT line in the band
  odd,   ///< odd lines only (k = 1, 3, 5, ...), leaving even lines to detect nonlinearity
};

inline constexpr std::array<Enumerator<FrequencyGrid>, 2> frequency_grid_enumerators{{
    {FrequencyGrid::full, "full", "Every DFT line in the band."},
    {FrequencyGrid::odd, "odd", "Odd lines only, leaving even lines to detect nonlinearity."},
}};
constexpr std::span<const Enumerator<FrequencyGrid>> enumerators(FrequencyGrid) {
  return frequency_grid_enumerators;
}

struct MultisineOptions {
  int period_length = 1024;    ///< N, samples per period (>= 4)
  double sample_time = 1.0;    ///< h in seconds (> 0)
  double min_frequency = 0.0;  ///< band lower edge in Hz (inclusive, >= 0)
  double max_frequency = 0.0;  ///< band upper edge in Hz (inclusive); 0 means up to Nyquist
  FrequencyGrid grid = FrequencyGrid::full;
  int periods = 1;         ///< repetitions of the period (>= 1)
  double rms = 1.0;        ///< root mean square of the signal (> 0)
  std::uint64_t seed = 0;  ///< seeds the phases, uniform on [0, 2 pi)

  static constexpr std::string_view type_name = "MultisineOptions";
  static constexpr auto fields() {
    using O = MultisineOptions;
    return std::tuple{
        field("period_length", &O::period_length, AtLeast{4}, "N, samples per period."),
        field("sample_time", &O::sample_time, Finite{GreaterThan{0}}, "h [s]."),
        field("min_frequency", &O::min_frequency, Finite{AtLeast{0}},
              "Band lower edge [Hz], inclusive."),
        field("max_frequency", &O::max_frequency, Finite{AtLeast{0}},
              "Band upper edge [Hz], inclusive; 0: up to Nyquist."),
        field("grid", &O::grid, "Which DFT lines of the band are excited."),
        field("periods", &O::periods, AtLeast{1}, "Repetitions of the period."),
        field("rms", &O::rms, Finite{GreaterThan{0}}, "Root mean square of the signal."),
        field("seed", &O::seed, "Seeds the phases, uniform on [0, 2 pi)."),
    };
  }
  /// max_frequency is 0 or >= min_frequency.
  void check_relations(const std::string& path) const;
  /// Throws InvalidArgument naming the first bad field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

struct Multisine {
  Eigen::VectorXd signal;  ///< periods * period_length samples
  std::vector<int> lines;  ///< excited DFT lines k, 1 <= k < N/2, at k / (N h) Hz
  Eigen::VectorXd phases;  ///< phase of each line (radians)
  double amplitude = 0.0;  ///< amplitude of every line: u_n = sum A cos(2 pi k n / N + phi_k)
  int period_length = 0;   ///< N
};

/// Random-phase multisine with equal amplitudes on the lines in the band (DC and Nyquist
/// excluded). Throws InvalidArgument if no line falls in the band.
Multisine multisine(const MultisineOptions& options);

/// Orthogonal multisines for n_u inputs (Pintelon & Schoukens, System Identification, 2nd ed.,
/// Sec. 2.7): n_e experiments, n_e the smallest power of two >= n_u; in experiment e input i is
/// hadamard(e, i) s_i, with s_i the multisine of `options` seeded options.seed + i and
/// hadamard the n_e x n_e Sylvester matrix, entries (-1)^popcount(e & i). At every excited line
/// the n_u x n_e input matrix then has orthogonal rows, so that periodic_frf(experiments)
/// inverts it with condition 1.
struct OrthogonalMultisines {
  std::vector<Eigen::MatrixXd> experiments;  ///< n_e records of periods * N samples x n_u
  std::vector<int> lines;                    ///< excited DFT lines (those of every s_i)
  Eigen::MatrixXd hadamard;                  ///< n_e x n_e, entries +-1
};

/// Throws InvalidArgument for inputs < 1 (or > 64) and as multisine() does.
OrthogonalMultisines orthogonal_multisines(const MultisineOptions& options, int inputs);

/// `periods` copies of `period` one after another.
Eigen::VectorXd repeat_periodic(const Eigen::VectorXd& period, int periods);

}  // namespace ctid
