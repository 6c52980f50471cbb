// Peak picking on spectra: the local-maximum test, the prominence of a maximum, parabolic
// interpolation of its position, and the peaks of a record's periodogram that stand above
// its local floor (a running median). `resonance_peaks` (frf.h) picks an FRF's peaks by
// prominence with these; mode relocation (refined_iv/mode_relocation.h) picks a residual's
// peaks above its floor with `periodogram_peaks`.
#pragma once

#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"

namespace ctid {

/// values(i) rises from the point before and does not fall to the point after (a flat top
/// counts once, at its left end). Needs 1 <= i <= values.size() - 2.
inline bool is_local_maximum(const Eigen::VectorXd& values, Eigen::Index i) {
  return values(i) > values(i - 1) && values(i) >= values(i + 1);
}

/// Height of values(i) above the higher of the two lowest points reached on either side
/// before a higher value (or the end of the grid). Needs 0 <= i < values.size().
double prominence(const Eigen::VectorXd& values, Eigen::Index i);

/// Abscissa of the vertex of the parabola through (x0, y0), (x1, y1), (x2, y2) (any grid,
/// x0 < x1 < x2), clamped to [x0, x2]; x1 when the parabola does not open downwards.
double parabolic_vertex(double x0, double x1, double x2, double y0, double y1, double y2);

/// On an equally spaced grid: the vertex's offset from the middle point, in grid steps,
/// clamped to [-1/2, 1/2]; 0 when the parabola does not open downwards (or a value is not
/// finite).
double parabolic_vertex_offset(double y0, double y1, double y2);

/// A peak of a periodogram above its local floor.
struct PeriodogramPeak {
  double frequency = 0.0;  ///< rad/s, by parabolic interpolation of log power
  double ratio = 0.0;      ///< periodogram over the local floor at the grid maximum
};

struct PeriodogramPeakOptions {
  /// The DFT is taken over this multiple of the record length, so that peaks between the
  /// record's lines are located. >= 1.
  int zero_padding = 4;
  /// Half-width of the running median that gives the local floor, in lines of the record.
  /// >= 1.
  int floor_half_width = 64;
  /// A local maximum counts if it is at least this many times its local floor. > 0.
  double min_peak_to_floor = 8.0;
  /// A peak closer than this (in lines of the record) to a higher one is dropped. >= 0.
  double min_separation = 1.0;
  /// Keep at most this many peaks, the highest above their floor (0: all).
  int max_peaks = 0;

  static constexpr std::string_view type_name = "PeriodogramPeakOptions";
  static constexpr auto fields() {
    using O = PeriodogramPeakOptions;
    return std::tuple{
        field("zero_padding", &O::zero_padding, AtLeast{1}, "DFT length over record length."),
        field("floor_half_width", &O::floor_half_width, AtLeast{1},
              "Half-width of the local floor's running median [lines]."),
        field("min_peak_to_floor", &O::min_peak_to_floor, GreaterThan{0},
              "Smallest ratio of a peak to its local floor."),
        field("min_separation", &O::min_separation, AtLeast{0},
              "Smallest distance to a higher peak [lines]."),
        field("max_peaks", &O::max_peaks, AtLeast{0}, "Most peaks kept (0: all).")};
  }
  /// Throws InvalidArgument naming the first bad field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// Local maxima of the zero-padded periodogram of x (bins 2 .. L/2 - 2) on the lines of the
/// record where `allowed` is true (empty: every line; otherwise max(x.size()/2, 1) entries,
/// e.g. from excited_band), at least min_peak_to_floor times the running median of the
/// periodogram on the record's lines (0 where that floor is not positive: no peak), highest
/// ratio first (ties: lower frequency first), each at least min_separation lines from every
/// higher one kept, at most max_peaks. A bin belongs to the nearest line (clamped to
/// 1 .. lines - 1). Empty when x has fewer than 4 samples or its padded length fewer than 6.
/// Throws InvalidArgument for bad
/// options, a sample time that is not positive or an `allowed` of the wrong size.
std::vector<PeriodogramPeak> periodogram_peaks(const Eigen::VectorXd& x, double sample_time,
                                               const PeriodogramPeakOptions& options = {},
                                               const std::vector<bool>& allowed = {});

}  // namespace ctid
