// Preprocessing of a measured record before identification, each step explicit and recorded:
// a row or time range, removal of the means or of a straight-line trend, decimation behind an
// anti-alias filter, and scaling. preprocess() returns the new record with a record of what was
// done (docs/decisions/0008-time-stamps-and-preprocessing.md states the order and the filter).
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"

namespace ctid {

enum class Detrend {
  none,    ///< signals kept as measured
  mean,    ///< each signal's mean removed
  linear,  ///< each signal's least-squares straight line in time removed
};

inline constexpr std::array<Enumerator<Detrend>, 3> detrend_enumerators{{
    {Detrend::none, "none", "Signals kept as measured."},
    {Detrend::mean, "mean", "Each signal's mean removed."},
    {Detrend::linear, "linear", "Each signal's least-squares straight line in time removed."},
}};
constexpr std::span<const Enumerator<Detrend>> enumerators(Detrend) { return detrend_enumerators; }

/// Applied in this order: range (rows or time), detrend, decimation, scaling. The reference of
/// a closed-loop record is treated as an output (detrended alike, scaled by output_scale).
struct PreprocessingOptions {
  std::optional<int> first_row;      ///< first sample kept (0-based); empty: 0
  std::optional<int> end_row;        ///< one past the last sample kept; empty: all
  std::optional<double> start_time;  ///< keep samples with t >= start_time [s]
  std::optional<double> end_time;    ///< keep samples with t < end_time [s]
  Detrend detrend = Detrend::none;
  /// Keep every decimate-th sample after a zero-phase anti-alias lowpass filter.
  int decimate = 1;
  double input_scale = 1.0;   ///< u is multiplied by this
  double output_scale = 1.0;  ///< y (and r) are multiplied by this
  /// Without detrending, warn when a signal's |mean| exceeds this many standard deviations.
  double large_mean_ratio = 2.0;

  static constexpr std::string_view type_name = "PreprocessingOptions";
  static constexpr auto fields() {
    using O = PreprocessingOptions;
    return std::tuple{
        field("first_row", &O::first_row, AtLeast{0}, "First sample kept (0-based); none: 0."),
        field("end_row", &O::end_row, AtLeast{1}, "One past the last sample kept; none: all."),
        field("start_time", &O::start_time, Finite{}, "Keep samples with t >= start_time [s]."),
        field("end_time", &O::end_time, Finite{}, "Keep samples with t < end_time [s]."),
        field("detrend", &O::detrend, "Remove nothing, the means, or straight lines."),
        field("decimate", &O::decimate, AtLeast{1},
              "Keep every decimate-th sample after a zero-phase anti-alias filter."),
        field("input_scale", &O::input_scale, Finite{GreaterThan{0}}, "Factor applied to u."),
        field("output_scale", &O::output_scale, Finite{GreaterThan{0}},
              "Factor applied to y and r."),
        field("large_mean_ratio", &O::large_mean_ratio, Finite{GreaterThan{0}},
              "Without detrending, warn when |mean| exceeds this many standard deviations."),
    };
  }
  /// A row range and a time range are not given together, and each range is not empty.
  void check_relations(const std::string& path) const;
  /// Throws InvalidArgument naming the field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// What preprocess() did, in the units of the original record.
struct PreprocessingRecord {
  int first_row = 0;  ///< first sample of the original record kept
  int end_row = 0;    ///< one past the last sample of the original record kept
  Detrend detrend = Detrend::none;
  /// Removed line a + b (t - t_first) per signal, t_first the first kept time stamp; the
  /// slopes are 0 for detrend mean, and everything is 0 for none.
  double input_offset = 0.0;
  double input_slope = 0.0;  ///< [1/s]
  double output_offset = 0.0;
  double output_slope = 0.0;  ///< [1/s]
  double reference_offset = 0.0;
  double reference_slope = 0.0;  ///< [1/s]
  int decimate = 1;
  double input_scale = 1.0;
  double output_scale = 1.0;
  int samples = 0;           ///< samples of the preprocessed record
  double sample_time = 0.0;  ///< its sample time [s]
  /// Advice: large means left in, an input no longer held after filtering.
  std::vector<std::string> warnings;

  static constexpr std::string_view type_name = "PreprocessingRecord";
  static constexpr auto fields() {
    using R = PreprocessingRecord;
    return std::tuple{
        field("first_row", &R::first_row, "First sample of the original record kept."),
        field("end_row", &R::end_row, "One past the last sample of the original record kept."),
        field("detrend", &R::detrend, "What was removed."),
        field("input_offset", &R::input_offset, "Removed offset of u (at the first kept time)."),
        field("input_slope", &R::input_slope, "Removed slope of u [1/s]."),
        field("output_offset", &R::output_offset, "Removed offset of y (at the first kept time)."),
        field("output_slope", &R::output_slope, "Removed slope of y [1/s]."),
        field("reference_offset", &R::reference_offset, "Removed offset of r."),
        field("reference_slope", &R::reference_slope, "Removed slope of r [1/s]."),
        field("decimate", &R::decimate, "Decimation factor (1: none)."),
        field("input_scale", &R::input_scale, "Factor applied to u."),
        field("output_scale", &R::output_scale, "Factor applied to y and r."),
        field("samples", &R::samples, "Samples of the preprocessed record."),
        field("sample_time", &R::sample_time, "Sample time of the preprocessed record [s]."),
        field("warnings", &R::warnings, "Advice about the record."),
    };
  }
  /// One line: "rows 0:1000, detrend mean (u 5, y 4.89), N = 1000, h = 0.08 s".
  std::string summary() const;
};

struct PreprocessedData {
  SampledData data;
  PreprocessingRecord record;
};

/// Throws InvalidArgument for invalid options, a range outside the record or keeping fewer
/// than 2 samples (3 for detrend linear), or a decimation leaving fewer than 2 samples.
PreprocessedData preprocess(const SampledData& data, const PreprocessingOptions& options = {});

/// Another record with the trend an earlier preprocess() removed (`trend`: its offsets and
/// slopes, in the original units) removed: each signal minus offset + slope (t - t_0), t_0 the
/// record's first sample (MATLAB's detrend(z, T) with a TrendInfo). The record's length, time
/// and hold are kept; scaling and decimation are not applied. Used to validate a model fitted
/// to detrended data on a record with the same operating point (`--detrend fit`).
SampledData remove_trend(const SampledData& data, const PreprocessingRecord& trend);

/// The output trend of `trend` put back onto an output sampled every h from t_0: the
/// simulated output of a model fitted to detrended data, in the record's own level.
Eigen::VectorXd add_output_trend(const Eigen::VectorXd& output, double h,
                                 const PreprocessingRecord& trend);

/// A record with irregular time stamps moved onto the uniform grid t_0 + k h (t_0 the first
/// stamp, up to the last one): the input as `input_hold` says it behaves between its
/// samples (zero-order hold: the last sample at or before each grid time, exact for a held
/// input; first-order hold: linear), the output and the reference linearly. The result has
/// `input_hold`. Throws InvalidArgument for stamps that are not finite and strictly
/// increasing (naming the first bad one), sizes that differ, h not positive, or fewer than 2
/// grid points.
SampledData resample(const Eigen::VectorXd& time, const Eigen::VectorXd& input,
                     const Eigen::VectorXd& output, const std::optional<Eigen::VectorXd>& reference,
                     double h, Hold input_hold = Hold::zero_order_hold);

/// The zero-phase anti-alias lowpass used by decimation by `factor`: a Hamming-windowed sinc
/// of 40 factor + 1 taps, cut off (-6 dB) at 0.9 of the new Nyquist frequency, unit DC gain;
/// its gain is within 0.3 % of 1 up to 0.8 of the new Nyquist frequency and at least 53 dB
/// down from the new Nyquist frequency up. Ends are continued by odd reflection about the end
/// samples. Returns x filtered, same length.
Eigen::VectorXd anti_alias_filter(const Eigen::VectorXd& x, int factor);

}  // namespace ctid
