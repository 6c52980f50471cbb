#include "ctid/frequency/peaks.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>

#include "ctid/core/error.h"
#include "ctid/frequency/periodogram.h"

namespace ctid {

double prominence(const Eigen::VectorXd& values, Eigen::Index i) {
  const Eigen::Index size = values.size();
  double left_min = values(i);
  for (Eigen::Index j = i - 1; j >= 0 && values(j) <= values(i); --j) {
    left_min = std::min(left_min, values(j));
  }
  double right_min = values(i);
  for (Eigen::Index j = i + 1; j < size && values(j) <= values(i); ++j) {
    right_min = std::min(right_min, values(j));
  }
  return values(i) - std::max(left_min, right_min);
}

double parabolic_vertex(double x0, double x1, double x2, double y0, double y1, double y2) {
  const double denominator = (x0 - x1) * (x0 - x2) * (x1 - x2);
  const double a = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / denominator;
  const double b = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / denominator;
  return a < 0.0 ? std::clamp(-b / (2.0 * a), x0, x2) : x1;
}

double parabolic_vertex_offset(double y0, double y1, double y2) {
  const double curvature = y0 - 2.0 * y1 + y2;
  if (!(std::isfinite(curvature) && curvature < 0.0)) return 0.0;
  return std::clamp(0.5 * (y0 - y2) / curvature, -0.5, 0.5);
}

std::vector<PeriodogramPeak> periodogram_peaks(const Eigen::VectorXd& x, double sample_time,
                                               const PeriodogramPeakOptions& options,
                                               const std::vector<bool>& allowed) {
  options.validate();
  require(std::isfinite(sample_time) && sample_time > 0.0, "periodogram_peaks: sample_time is ",
          sample_time, "; it must be finite and > 0");
  const Eigen::Index n = x.size();
  const Eigen::Index lines = n / 2;  // the record's own lines below Nyquist
  const auto line_count = static_cast<std::size_t>(std::max<Eigen::Index>(lines, 1));
  require(allowed.empty() || allowed.size() == line_count, "periodogram_peaks: allowed has ",
          allowed.size(), " entries; it must be empty or have one per line (", line_count, ")");
  const int padding = options.zero_padding;
  const Eigen::VectorXd power = periodogram(x, padding);
  const Eigen::Index half = power.size();  // bins 1..half-1 are inside (0, Nyquist)
  if (half < 3 || n < 4) return {};
  const Eigen::VectorXd floor_line =
      running_median(power, lines, options.floor_half_width, padding);
  const double bin = 2.0 * std::numbers::pi / (static_cast<double>(n * padding) * sample_time);
  std::vector<PeriodogramPeak> peaks;
  for (Eigen::Index k = 2; k + 1 < half; ++k) {
    if (!is_local_maximum(power, k)) continue;
    const Eigen::Index j = std::clamp<Eigen::Index>((k + padding / 2) / padding, 1,
                                                    std::max<Eigen::Index>(lines - 1, 1));
    if (!allowed.empty() && !allowed[static_cast<std::size_t>(j)]) continue;
    const double floor = floor_line(j);
    if (!(floor > 0.0)) continue;
    const double ratio = power(k) / floor;
    if (ratio < options.min_peak_to_floor) continue;
    const double offset =
        parabolic_vertex_offset(std::log(power(k - 1)), std::log(power(k)), std::log(power(k + 1)));
    peaks.push_back({(static_cast<double>(k) + offset) * bin, ratio});
  }
  std::sort(peaks.begin(), peaks.end(), [](const PeriodogramPeak& a, const PeriodogramPeak& b) {
    return a.ratio > b.ratio || (a.ratio == b.ratio && a.frequency < b.frequency);
  });
  const double separation =
      options.min_separation * 2.0 * std::numbers::pi / (static_cast<double>(n) * sample_time);
  std::vector<PeriodogramPeak> kept;
  for (const PeriodogramPeak& p : peaks) {
    bool near = false;
    for (const PeriodogramPeak& q : kept) {
      near = near || std::abs(p.frequency - q.frequency) < separation;
    }
    if (!near) kept.push_back(p);
    if (options.max_peaks > 0 && static_cast<int>(kept.size()) >= options.max_peaks) break;
  }
  return kept;
}

}  // namespace ctid
