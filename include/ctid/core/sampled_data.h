// A uniformly sampled SISO record: input u_k, output y_k and optionally the reference r_k
// of a closed-loop experiment, at t_k = t_0 + k h, k = 0..N-1.
#pragma once

#include <optional>

#include <Eigen/Core>

#include "ctid/core/hold.h"

namespace ctid {

class SampledData {
 public:
  /// Throws InvalidArgument for a non-positive or non-finite sample time, unequal lengths,
  /// fewer than 2 samples or a non-finite value (naming the signal and the index).
  SampledData(double sample_time, Eigen::VectorXd input, Eigen::VectorXd output,
              std::optional<Eigen::VectorXd> reference = std::nullopt, double start_time = 0.0);

  /// From time stamps, checked by check_time_stamps (the stamp farthest off the grid is named,
  /// with the step found and the tolerance).
  static SampledData from_time_stamps(const Eigen::VectorXd& time, Eigen::VectorXd input,
                                      Eigen::VectorXd output,
                                      std::optional<Eigen::VectorXd> reference = std::nullopt,
                                      double relative_tolerance = 1e-6);

  int size() const { return static_cast<int>(input_.size()); }
  double sample_time() const { return sample_time_; }
  double start_time() const { return start_time_; }
  Eigen::VectorXd time() const;
  const Eigen::VectorXd& input() const { return input_; }
  const Eigen::VectorXd& output() const { return output_; }
  bool has_reference() const { return reference_.has_value(); }
  /// Throws InvalidArgument if there is no reference.
  const Eigen::VectorXd& reference() const;

  /// How the input is continued between samples (zero-order hold by default: a DAC output;
  /// first-order hold for multisine and band-limited experiments whose input is not held).
  /// Every estimator, simulator and validation that reads this record's input uses it.
  Hold input_hold() const { return input_hold_; }
  /// The same record with its input continued by `hold` (a temporary is moved, not copied:
  /// a long record is not held twice).
  SampledData with_input_hold(Hold hold) const&;
  SampledData with_input_hold(Hold hold) &&;

  /// Samples [begin, begin + count) (the input hold is kept).
  SampledData segment(int begin, int count) const;

 private:
  double sample_time_;
  double start_time_;
  Eigen::VectorXd input_;
  Eigen::VectorXd output_;
  std::optional<Eigen::VectorXd> reference_;
  Hold input_hold_ = Hold::zero_order_hold;
};

/// The uniformity rule for time stamps t_0..t_{N-1} (docs/decisions/0008): the step is
/// h = (t_{N-1} - t_0)/(N - 1), and every stamp must lie within a tolerance of the grid
/// t_0 + k h. Stamps are text printed to some number of significant digits P (the most any
/// stamp needs to read back exactly), so the tolerance is one unit in the P-th digit of the
/// largest |t_k| (half a unit of rounding on the stamp, half carried into the grid by the end
/// stamps), at most kMaxGridDeviation * h and at least relative_tolerance * h. Stamps that
/// cannot resolve a quarter step are thus refused, and so are gaps (a missing sample moves
/// some stamp by about h/2 or more) and jitter beyond the printed precision.
inline constexpr double kMaxGridDeviation = 0.25;

/// The most samples a record that ctid builds itself (resampling, simulation) may hold: 1e8,
/// 800 MB a signal. A request beyond it is refused before anything is allocated.
inline constexpr double kMaxRecordSamples = 1e8;

struct TimeStampCheck {
  double step = 0.0;                ///< h found from the first and last stamps [s]
  int digits = 1;                   ///< significant digits the stamps are printed with
  double tolerance = 0.0;           ///< allowed distance of a stamp from the grid [s]
  std::optional<int> worst_sample;  ///< the stamp farthest off the grid, if beyond tolerance
  double deviation = 0.0;           ///< its distance from the grid [s]
};

/// Applies the rule above; throws InvalidArgument for fewer than 2 stamps or a last stamp not
/// after the first. A stamp off the grid is reported, not thrown.
TimeStampCheck check_time_stamps(const Eigen::VectorXd& time, double relative_tolerance = 1e-6);

/// The grid t_0 + k h of uniform time stamps.
struct UniformGrid {
  double start_time = 0.0;   ///< t_0 [s]
  double sample_time = 0.0;  ///< h [s]
};

/// The grid time stamps lie on, checked as SampledData::from_time_stamps checks them, without
/// a record: at least 2 stamps, each finite, their largest magnitude within 1e-100..1e100 as
/// a signal's, and every stamp on the grid within check_time_stamps's tolerance. Throws
/// InvalidArgument naming the stamp at fault.
UniformGrid uniform_grid(const Eigen::VectorXd& time, double relative_tolerance = 1e-6);

}  // namespace ctid
