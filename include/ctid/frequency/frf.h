// Nonparametric frequency response functions (FRF) from sampled input/output data, and
// resonance peaks picked from them (for choosing orders and initial modes). Periodic data:
// the DFT of each steady-state period, G_p(k) = Y_p(k) / U_p(k), averaged over the P periods,
// with variance s^2 / P (Pintelon & Schoukens, System Identification, Ch. 2). Non-periodic
// data: the H1 estimate S_yu / S_uu with Hann-windowed, overlapping Welch segments. Both give
// the squared coherence |S_yu|^2 / (S_uu S_yy) (over periods or segments) and the input's
// relative amplitude at each line, so that peaks are picked only where the input excites the
// system and the output follows it. Frequencies in rad/s; DFT line k of a block of L samples
// sits at 2 pi k / (L h). Peaks are picked with the kernels of peaks.h.
#pragma once

#include <limits>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"

namespace ctid {

/// An FRF on a set of DFT lines. `variance` is E|G_hat - G|^2 of the complex estimate.
struct Frf {
  std::vector<int> lines;       ///< DFT line k of each frequency (of one period / segment)
  Eigen::VectorXd frequencies;  ///< 2 pi k / (L h) [rad/s], increasing
  Eigen::VectorXcd response;    ///< G_hat at each frequency
  Eigen::VectorXd variance;     ///< estimated variance of G_hat per line
  Eigen::VectorXd coherence;    ///< squared coherence in [0, 1] per line; empty if unknown
  /// Input amplitude at each line relative to the largest line of the record (periodic:
  /// |mean U(k)|; Welch: sqrt(S_uu(k))), in [0, 1]; empty if unknown.
  Eigen::VectorXd input_level;
  int averages = 0;      ///< periods (periodic) or segments (Welch) averaged
  int block_length = 0;  ///< L: samples per period or per segment

  static constexpr std::string_view type_name = "Frf";
  static constexpr auto fields() {
    return std::tuple{
        field("lines", &Frf::lines, "DFT line k of each frequency (of one period / segment)."),
        field("frequencies", &Frf::frequencies, "2 pi k / (L h) [rad/s], increasing."),
        field("response", &Frf::response, "G_hat at each frequency (complex)."),
        field("variance", &Frf::variance, "Estimated variance E|G_hat - G|^2 per line."),
        field("coherence", &Frf::coherence, "Squared coherence per line; empty if unknown."),
        field("input_level", &Frf::input_level,
              "Input amplitude per line over the largest line's; empty if unknown."),
        field("averages", &Frf::averages, "Periods (periodic) or segments (Welch) averaged."),
        field("block_length", &Frf::block_length, "L: samples per period or per segment."),
    };
  }
};

struct PeriodicFrfOptions {
  /// N, samples per period of the excitation (>= 4). The record must hold a whole number of
  /// periods.
  int period_length = 0;
  /// Periods dropped at the start so that the transient has died out (>= 0); at least two
  /// periods must remain for the variance.
  int transient_periods = 1;
  /// DFT lines (1 <= k <= N/2) to estimate; empty: every line where the input's averaged
  /// spectrum exceeds line_threshold times its largest line (the excited lines).
  std::vector<int> lines;
  /// Relative amplitude that makes a line count as excited, in (0, 1). The default, 1 % of
  /// the largest line (-40 dB), drops the leakage and the gaps of a multisine's spectrum,
  /// where Y/U is noise over almost nothing.
  double line_threshold = 0.01;

  static constexpr std::string_view type_name = "PeriodicFrfOptions";
  static constexpr auto fields() {
    using O = PeriodicFrfOptions;
    return std::tuple{
        field("period_length", &O::period_length, AtLeast{4},
              "N, samples per period; the record holds whole periods."),
        field("transient_periods", &O::transient_periods, AtLeast{0},
              "Periods dropped at the start (transient)."),
        field("lines", &O::lines, Each{AtLeast{1}},
              "DFT lines (<= N/2) to estimate; empty: the excited ones."),
        field("line_threshold", &O::line_threshold, Between{0, 1},
              "Relative input amplitude that makes a line excited."),
    };
  }
  /// Every line <= period_length / 2.
  void check_relations(const std::string& path) const;
  /// Throws InvalidArgument naming the field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// FRF from a periodic experiment (a multisine repeated P + transient_periods times). Throws
/// InvalidArgument when the record length is not a multiple of N, when fewer than two
/// periods remain after the transient, or when a requested line is not excited.
Frf periodic_frf(const SampledData& data, const PeriodicFrfOptions& options);

struct WelchOptions {
  /// L, samples per segment (>= 8, <= record length).
  int segment_length = 256;
  /// Fraction of a segment shared with the next one, in [0, 1).
  double overlap = 0.5;

  static constexpr std::string_view type_name = "WelchOptions";
  static constexpr auto fields() {
    using O = WelchOptions;
    return std::tuple{
        field("segment_length", &O::segment_length, AtLeast{8},
              "L, samples per segment (<= record length)."),
        field("overlap", &O::overlap, Between{0, 1, true, false},
              "Fraction of a segment shared with the next one."),
    };
  }
  /// Throws InvalidArgument naming the field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// Samples per Welch segment ctid uses for a record of n samples when none is given: the
/// largest power of two <= n/8, within [8, 4096] and at most n.
int default_segment_length(int samples);

/// H1 estimate with periodic-Hann-windowed segments starting every L - round(overlap L)
/// samples (as many as fit), on lines k = 1..L/2 (every line; see excited_lines). The variance is
/// the usual first-order approximation (1 - coh) / (coh n) |G|^2 with n segments, which ignores the
/// correlation between overlapping segments. Throws InvalidArgument when the record is shorter than
/// L.
Frf welch_frf(const SampledData& data, const WelchOptions& options = {});

/// The lines of `frf` whose input_level exceeds `line_threshold` (all of them when the FRF
/// has no input_level). Throws InvalidArgument for a threshold outside [0, 1) or an FRF whose
/// vectors disagree in size.
Frf excited_lines(const Frf& frf, double line_threshold);

/// A local maximum of |G| and what it says about a lightly damped mode.
struct ResonancePeak {
  int index = 0;               ///< position in the FRF's vectors
  double frequency = 0.0;      ///< rad/s (parabolic interpolation of log|G| around the maximum)
  double magnitude = 0.0;      ///< |G| at the grid maximum
  double prominence_db = 0.0;  ///< height above the higher of the two surrounding minima
  /// Half-power bandwidth estimate (w2 - w1) / (2 w_peak); NaN when |G| does not fall to
  /// |G_peak| / sqrt(2) on both sides within the grid.
  double damping_ratio = 0.0;
  /// Squared coherence at the peak's line (NaN when the FRF has none).
  double coherence = std::numeric_limits<double>::quiet_NaN();
  /// The FRF's input_level at the peak's line (NaN when the FRF has none).
  double input_level = std::numeric_limits<double>::quiet_NaN();

  static constexpr std::string_view type_name = "ResonancePeak";
  static constexpr auto fields() {
    using S = ResonancePeak;
    return std::tuple{
        field("index", &S::index, "Position in the FRF's vectors."),
        field("frequency", &S::frequency, "Interpolated peak frequency [rad/s]."),
        field("magnitude", &S::magnitude, "|G| at the grid maximum."),
        field("prominence_db", &S::prominence_db,
              "Height above the higher of the two surrounding minima [dB]."),
        field("damping_ratio", &S::damping_ratio,
              "Half-power bandwidth estimate (NaN if not measurable)."),
        field("coherence", &S::coherence, "Squared coherence at the peak (NaN if unknown)."),
        field("input_level", &S::input_level,
              "Relative input amplitude at the peak (NaN if unknown)."),
    };
  }
};

struct PeakOptions {
  /// Keep peaks at least this many dB above the surrounding minima (>= 0).
  double min_prominence_db = 3.0;
  /// Keep at most this many peaks, the most prominent ones (0: all).
  int max_peaks = 0;
  /// Frf overload: look for peaks only on lines whose input_level exceeds this, in [0, 1).
  double line_threshold = 0.01;
  /// Frf overload: drop peaks whose squared coherence is below this, in [0, 1]. Off by
  /// default: a Welch FRF's coherence at a lightly damped resonance is low from leakage when
  /// the mode outlasts a segment (0.17-0.48 noise-free for zeta 2e-3..5e-3 and 10-s segments).
  double min_coherence = 0.0;

  static constexpr std::string_view type_name = "PeakOptions";
  static constexpr auto fields() {
    using O = PeakOptions;
    return std::tuple{
        field("min_prominence_db", &O::min_prominence_db, Finite{AtLeast{0}},
              "Smallest height above the surrounding minima [dB]."),
        field("max_peaks", &O::max_peaks, AtLeast{0}, "Keep the most prominent (0: all)."),
        field("line_threshold", &O::line_threshold, Between{0, 1, true, false},
              "Frf overload: relative input amplitude of a line searched for peaks."),
        field("min_coherence", &O::min_coherence, Between{0, 1, true, true},
              "Frf overload: smallest squared coherence of a peak."),
    };
  }
  /// Throws InvalidArgument naming the field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// Resonance peaks of |G| in increasing frequency. Frequencies must be finite and strictly
/// increasing, of the size of `response` (>= 3).
std::vector<ResonancePeak> resonance_peaks(const Eigen::VectorXd& frequencies,
                                           const Eigen::VectorXcd& response,
                                           const PeakOptions& options = {});

/// Resonance peaks of a measured FRF that are modes, not artefacts of the test signal: picked
/// on the excited lines only (excited_lines with options.line_threshold; the gaps and the
/// out-of-band leakage of the input, where Y/U divides by almost nothing, are not searched),
/// then those whose coherence is below options.min_coherence dropped (when the FRF has
/// coherence), then at most options.max_peaks of the most prominent kept. Each peak's index
/// refers to `frf`'s vectors. Empty when fewer than 3 excited lines remain.
std::vector<ResonancePeak> resonance_peaks(const Frf& frf, const PeakOptions& options = {});

}  // namespace ctid
