// Seeds, sizes, the index-ordered parallel loop and MSE summaries of monte_carlo.h.
#include "ctid/study/monte_carlo.h"

#include <algorithm>
#include <cmath>

#include "ctid/core/error.h"

namespace ctid {

std::uint64_t splitmix64(std::uint64_t x) {
  std::uint64_t z = x + 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

std::uint64_t run_seed(std::uint64_t study_seed, int size_index, int run_index) {
  require(size_index >= 0, "run_seed: size_index is ", size_index, "; it must be >= 0");
  require(run_index >= 0, "run_seed: run_index is ", run_index, "; it must be >= 0");
  const std::uint64_t per_size =
      splitmix64(splitmix64(study_seed) ^ static_cast<std::uint64_t>(size_index));
  return splitmix64(per_size ^ static_cast<std::uint64_t>(run_index));
}

std::uint64_t stream_seed(std::uint64_t seed, int stream) {
  require(stream >= 0, "stream_seed: stream is ", stream, "; it must be >= 0");
  return splitmix64(seed ^ (0xA0761D6478BD642FULL * (static_cast<std::uint64_t>(stream) + 1)));
}

std::vector<int> log_spaced_sizes(int first, int last, int count) {
  require(count >= 1, "log_spaced_sizes: count is ", count, "; it must be >= 1");
  require(first >= 1, "log_spaced_sizes: first is ", first, "; it must be >= 1");
  require(last >= first, "log_spaced_sizes: last is ", last, "; it must be >= first (", first, ")");
  std::vector<int> sizes(static_cast<size_t>(count));
  const double log_first = std::log(static_cast<double>(first));
  const double log_last = std::log(static_cast<double>(last));
  for (int k = 0; k < count; ++k) {
    if (k == 0) {
      sizes[0] = first;
    } else if (k == count - 1) {
      sizes[static_cast<size_t>(k)] = last;
    } else {
      const double t = static_cast<double>(k) / static_cast<double>(count - 1);
      sizes[static_cast<size_t>(k)] =
          static_cast<int>(std::lround(std::exp(log_first + t * (log_last - log_first))));
    }
  }
  return sizes;
}

ErrorSummary summarize_errors(const Eigen::VectorXd& estimates, double truth,
                              const Eigen::VectorXd& predicted_variances) {
  require(predicted_variances.size() == 0 || predicted_variances.size() == estimates.size(),
          "summarize_errors: predicted_variances has ", predicted_variances.size(),
          " entries; it must be empty or have one per estimate (", estimates.size(), ")");
  ErrorSummary summary;
  double sum = 0.0;
  double sum_squares = 0.0;
  double predicted_sum = 0.0;
  for (Eigen::Index r = 0; r < estimates.size(); ++r) {
    if (!std::isfinite(estimates[r])) continue;
    const double error = estimates[r] - truth;
    sum += error;
    sum_squares += error * error;
    ++summary.runs;
    if (predicted_variances.size() > 0 && std::isfinite(predicted_variances[r])) {
      predicted_sum += predicted_variances[r];
      ++summary.predicted_runs;
    }
  }
  if (summary.runs > 0) {
    summary.bias = sum / summary.runs;
    summary.mean_squared_error = sum_squares / summary.runs;
  }
  if (summary.predicted_runs > 0) {
    summary.predicted_mean_squared_error = predicted_sum / summary.predicted_runs;
  }
  return summary;
}

double log_log_slope(const std::vector<int>& samples, const std::vector<double>& mse) {
  require(samples.size() == mse.size(), "log_log_slope: ", samples.size(), " sizes but ",
          mse.size(), " MSE values; they must be equal");
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  int n = 0;
  for (size_t k = 0; k < samples.size(); ++k) {
    if (samples[k] <= 0 || !std::isfinite(mse[k]) || mse[k] <= 0.0) continue;
    const double x = std::log10(static_cast<double>(samples[k]));
    const double y = std::log10(mse[k]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++n;
  }
  const double denominator = n * sxx - sx * sx;
  if (n < 2 || denominator <= 0.0) return std::numeric_limits<double>::quiet_NaN();
  return (n * sxy - sx * sy) / denominator;
}

}  // namespace ctid
