// The magnitudes a signal's samples may have: sums of squares over any record ctid takes
// (at most 1e8 samples) stay finite and normal from 1e-100 to 1e100, so no statistic,
// excitation test or estimate overflows or underflows into a misleading message.
#pragma once

#include <Eigen/Core>
#include <string_view>

#include "ctid/core/error.h"

namespace ctid::internal {

inline constexpr double kLargestSampleMagnitude = 1e100;
inline constexpr double kSmallestSampleMagnitude = 1e-100;

/// Refuses a signal whose largest magnitude lies outside [1e-100, 1e100] (an all-zero signal
/// passes: other checks judge it), naming `what`, the magnitude and the way out.
inline void require_magnitude_in_range(const Eigen::Ref<const Eigen::VectorXd>& v,
                                       std::string_view what) {
  if (v.size() == 0) return;
  Eigen::Index at = 0;
  const double largest = v.cwiseAbs().maxCoeff(&at);
  if (largest == 0.0 ||
      (largest >= kSmallestSampleMagnitude && largest <= kLargestSampleMagnitude)) {
    return;
  }
  require(false, what, " reaches a magnitude of ", largest, " (sample ", at,
          "); ctid takes signals whose largest magnitude lies within 1e-100..1e+100, so that "
          "their sums of squares stay finite: rescale it (give it other units)");
}

}  // namespace ctid::internal
