// The replayable Monte Carlo engine behind ctid's studies: per-run seeds derived by a fixed
// hash (splitmix64) of (study seed, sample-size index, run index), so any run can be
// replayed alone; a parallel loop whose results are stored by index (core/parallel.h), so a
// parallel study equals the serial one bit for bit; log-spaced sample sizes; and the mean-square
// error summary of González et al., Section 6 (Figs. 3 and 4).
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/core/parallel.h"  // parallel_for, resolve_thread_count (the study's loop)

namespace ctid {

/// One step of the splitmix64 generator (Steele, Lea and Flood 2014): a bijective 64-bit
/// mixer, x + 0x9E3779B97F4A7C15 followed by two xor-shift-multiply rounds.
std::uint64_t splitmix64(std::uint64_t x);

/// The seed of run `run_index` at sample size `size_index` of a study seeded with
/// `study_seed`: splitmix64(splitmix64(splitmix64(study_seed) ^ size_index) ^ run_index).
/// Indices must be >= 0.
std::uint64_t run_seed(std::uint64_t study_seed, int size_index, int run_index);

/// An independent stream of a run for one purpose (input, noise, start...):
/// splitmix64(seed ^ (0xA0761D6478BD642F * (stream + 1))).
std::uint64_t stream_seed(std::uint64_t seed, int stream);

/// `count` integers rounded from a geometric sequence from `first` to `last` (both kept
/// exactly). count >= 1 (count == 1 gives {first}); 1 <= first <= last.
std::vector<int> log_spaced_sizes(int first, int last, int count);

/// Mean-square error of one parameter over the valid runs: errors e_r = estimate_r - truth.
struct ErrorSummary {
  int runs = 0;                                                          ///< finite estimates used
  double mean_squared_error = std::numeric_limits<double>::quiet_NaN();  ///< mean e_r^2
  double bias = std::numeric_limits<double>::quiet_NaN();                ///< mean e_r
  /// Mean of the finite predicted variances passed in (NaN if none): the asymptotic
  /// covariance prediction of the MSE, whose bias part vanishes asymptotically.
  double predicted_mean_squared_error = std::numeric_limits<double>::quiet_NaN();
  int predicted_runs = 0;  ///< finite predicted variances used

  static constexpr std::string_view type_name = "ErrorSummary";
  static constexpr auto fields() {
    using S = ErrorSummary;
    return std::tuple{
        field("runs", &S::runs, "Finite estimates used."),
        field("mean_squared_error", &S::mean_squared_error, "Mean e_r^2."),
        field("bias", &S::bias, "Mean e_r."),
        field("predicted_mean_squared_error", &S::predicted_mean_squared_error,
              "Mean of the finite predicted variances (NaN if none)."),
        field("predicted_runs", &S::predicted_runs, "Finite predicted variances used."),
    };
  }
};

/// Summary of `estimates` against `truth`; non-finite estimates are skipped, as are
/// non-finite entries of `predicted_variances` (which may be empty, or the size of
/// `estimates`).
ErrorSummary summarize_errors(const Eigen::VectorXd& estimates, double truth,
                              const Eigen::VectorXd& predicted_variances = Eigen::VectorXd());

/// Least-squares slope of log10(mse) against log10(samples) over the finite, positive
/// points (NaN if fewer than two): -1 for an estimator whose MSE decays as 1/N.
double log_log_slope(const std::vector<int>& samples, const std::vector<double>& mse);

}  // namespace ctid
