// Recursive SRIVC: the refined instrumental-variable estimate of one unfactored model
// B(p)/A(p) (A anti-monic, as srivc.h) advanced one sample at a time, to follow a slowly
// varying system, with exponential forgetting and/or a random-walk parameter model and the
// parameter covariance at every step (issue 17; the recursive form of eq. (30) of González
// et al.; docs/algorithms/recursive-srivc.md, decision 0025).
//
// Per sample k the prefilter 1/Â(p) runs on u (zero-order or first-order hold as the record
// says) and on y (first-order hold), and the auxiliary model x̂ = B̂/Â u through the same
// prefilter, all as exact discretisations of the current estimate Â, B̂. With the filtered
// derivatives (p^j/Â) u, (p^k/Â) y and (p^k/Â) x̂ the equation of sample k is
//   y_f = φᵀθ + ε,  φ = [-p y_f … -p^n y_f, u_f … p^m u_f],  θ = [a_1 … a_n, b_0 … b_m],
// (anti-monic A: the dependent variable is y_f itself, not p^n y_f) with the instrument
// ζ = [-p x̂_f … -p^n x̂_f, u_f … p^m u_f], and
//   k = P ζ / (λ + φᵀ P ζ),  θ ← θ + k (y_f − φᵀθ),  P ← (P − k φᵀ P) / λ + Q.
// The covariance of θ is σ̂² (P + Pᵀ)/2 with σ̂² the exponentially weighted variance of the
// output error y − x̂.
#pragma once

#include <array>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/hold.h"
#include "ctid/core/sampled_data.h"
#include "ctid/core/transfer_function.h"

namespace ctid {

/// How much of the covariance RecursiveSrivcResult keeps per sample.
enum class CovarianceHistory {
  diagonal,  ///< N x np: the variances (standard_errors is their square root)
  full,      ///< N x np^2: the whole np x np matrix of every sample (column-major)
};

inline constexpr std::array<Enumerator<CovarianceHistory>, 2> covariance_history_enumerators{{
    {CovarianceHistory::diagonal, "diagonal", "Keep the variances only (N x np doubles)."},
    {CovarianceHistory::full, "full",
     "Keep every np x np covariance (N x np^2 doubles, each row column-major)."},
}};
constexpr std::span<const Enumerator<CovarianceHistory>> enumerators(CovarianceHistory) {
  return covariance_history_enumerators;
}

struct RecursiveSrivcOptions {
  /// Exponential forgetting factor λ in (0, 1]: the equation of sample k - j weighs λ^j, an
  /// effective memory of 1/(1 - λ) samples. 1: no forgetting (the recursion tends to the
  /// batch SRIVC solution).
  double forgetting_factor = 1.0;
  /// Random-walk parameter model θ_k = θ_{k-1} + w_k with cov w_k = σ² Q (Q as a ratio to the
  /// noise variance, Young's NVR): empty = no random walk, one value = Q is that value times
  /// the identity, np values = diagonal Q, one per parameter in θ order. Each >= 0.
  std::vector<double> random_walk;
  /// P0 = initial_covariance · diag(θ0_i²) (each |θ0_i| floored at 1e-3 ||θ0||): the start
  /// enters as a prior with covariance σ̂² P0, i.e. a relative standard error of
  /// σ̂ sqrt(initial_covariance) per parameter. Large (default 1e6): the data overrule the
  /// start within a few dozen samples and its weight in the final estimate falls as 1/N. > 0.
  double initial_covariance = 1e6;
  /// The prefilter 1/Â and the auxiliary model B̂/Â are re-discretised from the current
  /// estimate every refresh_interval samples. 1 is the textbook rule; the default 10 moved
  /// the final estimate of a 2000-sample record by 0.01 standard errors at a ninth of the
  /// cost (decision 0025). >= 1.
  int refresh_interval = 10;
  /// At a refresh the new filters are run from rest over the last refilter_samples samples
  /// (kept in a ring buffer: 2 refilter_samples doubles), so their state is what they would
  /// have reached on the whole record up to the decay of their slowest mode over that window,
  /// and the equations after the refresh stay exact on noise-free data. 0: no buffer; the
  /// filtered signals and their first n - 1 derivatives are carried into the new filters,
  /// and each change of Â leaves a transient in the following equations (a bias that decays
  /// only as 1/N with forgetting_factor = 1; decision 0025). >= 0.
  int refilter_samples = 2000;
  /// No refresh during the first warmup_samples samples: the filters stay those of the start
  /// while the first equations, which determine θ poorly, pass. Refreshing from those noisy
  /// early estimates was measured to spoil the instruments of a whole record (30 seeded
  /// records, N = 1000, SNR ~ 8 dB: mean squared error 50-5000 times the reported variance
  /// without a warm-up, 0.8-1.5 times with 100 or 300 samples; decision 0025). Take at least
  /// a few periods of the slowest mode and 10 np samples. >= 0.
  int warmup_samples = 100;
  /// Forgetting factor of the output-error variance σ̂²: 0 = the same as forgetting_factor.
  /// In [0, 1].
  double noise_forgetting = 0.0;
  /// How the measured output is continued between samples before filtering.
  Hold output_interpolation = Hold::first_order_hold;
  /// What RecursiveSrivcResult keeps of the covariance at every sample.
  CovarianceHistory covariance_history = CovarianceHistory::diagonal;

  static constexpr std::string_view type_name = "RecursiveSrivcOptions";
  static constexpr auto fields() {
    using O = RecursiveSrivcOptions;
    return std::tuple{
        field("forgetting_factor", &O::forgetting_factor, Between{0.0, 1.0, false, true},
              "Exponential forgetting factor lambda in (0, 1]; 1: none."),
        field("random_walk", &O::random_walk, Each{Finite{AtLeast{0.0}}},
              "Random-walk covariance Q / sigma^2: empty none, one value times I, or np values."),
        field("initial_covariance", &O::initial_covariance, Finite{GreaterThan{0.0}},
              "P0 = this times diag(theta0^2) (floored at 1e-3 ||theta0||)."),
        field("refresh_interval", &O::refresh_interval, AtLeast{1},
              "Re-discretise the prefilter and auxiliary model every this many samples."),
        field("refilter_samples", &O::refilter_samples, AtLeast{0},
              "Samples re-filtered by the new filters at a refresh (ring buffer); 0: carry "
              "the filtered derivatives instead."),
        field("warmup_samples", &O::warmup_samples, AtLeast{0},
              "Keep the start's filters for this many samples."),
        field("noise_forgetting", &O::noise_forgetting, Between{0.0, 1.0, true, true},
              "Forgetting factor of the output-error variance; 0: forgetting_factor."),
        field("output_interpolation", &O::output_interpolation,
              "How the measured output is continued between samples before filtering."),
        field("covariance_history", &O::covariance_history,
              "What the result keeps of the covariance per sample: diagonal or full."),
    };
  }
  /// Throws InvalidArgument naming the first bad field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// One recursive SRIVC estimator: the filter states, θ, P and σ̂² live across update() calls.
class RecursiveSrivc {
 public:
  /// `order`: n >= 1, 0 <= m <= n, no integrators. `start` must have exactly n poles (none at
  /// the origin), numerator degree <= m, no input delay, and a stable denominator (it is the
  /// first prefilter). Throws InvalidArgument otherwise, or for bad options or sample time.
  RecursiveSrivc(const SubmodelOrder& order, double sample_time, Hold input_hold,
                 const TransferFunction& start, const RecursiveSrivcOptions& options = {});
  ~RecursiveSrivc();
  RecursiveSrivc(const RecursiveSrivc&);
  RecursiveSrivc& operator=(const RecursiveSrivc&);
  RecursiveSrivc(RecursiveSrivc&&) noexcept;
  RecursiveSrivc& operator=(RecursiveSrivc&&) noexcept;

  /// Advances one sample (u_k, y_k). Throws InvalidArgument for a non-finite sample. A step
  /// whose θ or P would not be finite is skipped (θ, P kept) and counted; a refresh whose Â
  /// has a root with real part >= 0 keeps the previous filters and is counted.
  void update(double u, double y);

  /// θ = [a_1 … a_n, b_0 … b_m].
  const Eigen::VectorXd& parameters() const;
  /// B̂/Â of the current θ.
  TransferFunction model() const;
  /// σ̂² (P + Pᵀ)/2, np x np.
  Eigen::MatrixXd covariance() const;
  /// The P of the recursion itself (not scaled by σ̂²).
  const Eigen::MatrixXd& gain_matrix() const;
  /// σ̂², the weighted output-error variance (0 before the first sample).
  double noise_variance() const;
  /// Samples processed.
  int steps() const;
  /// Refreshes refused because Â had a root with real part >= 0 (the filters were kept).
  int rejected_refreshes() const;
  /// Updates skipped because θ or P would not have been finite.
  int skipped_updates() const;
  /// Samples after which θ gave an Â with a root in the closed right half-plane (or lost
  /// its leading coefficient), and the first and last of them (0-based; -1 if none).
  int unstable_samples() const;
  int first_unstable_sample() const;
  int last_unstable_sample() const;
  /// First sample whose update was skipped for a non-finite θ or P, or -1.
  int first_nonfinite_sample() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// What recursive_srivc() found at every sample and at the end.
struct RecursiveSrivcResult {
  explicit RecursiveSrivcResult(TransferFunction final_model) : model(std::move(final_model)) {}

  Eigen::VectorXd times;             ///< N: t_k of each sample
  Eigen::MatrixXd parameters;        ///< N x np: θ after sample k
  Eigen::MatrixXd standard_errors;   ///< N x np: sqrt of the covariance's diagonal
  Eigen::MatrixXd covariance;        ///< N x np (diagonal) or N x np^2 (full, column-major)
  Eigen::VectorXd noise_variance;    ///< N: σ̂² after sample k
  TransferFunction model;            ///< B̂/Â of the final θ
  Eigen::MatrixXd final_covariance;  ///< np x np at the last sample
  /// The final Â is stable. Unstable estimates during the start-up transient are counted
  /// below; they never reach the filters (a refresh with an unstable Â is refused).
  bool stable = true;
  int unstable_samples = 0;         ///< samples after which Â was not stable
  int first_unstable_sample = -1;   ///< the first of them, or -1
  int last_unstable_sample = -1;    ///< the last of them, or -1
  bool finite = true;               ///< no update was skipped for non-finite values
  int first_nonfinite_sample = -1;  ///< first skipped update, or -1
  int rejected_refreshes = 0;       ///< filter refreshes refused (unstable Â)
  int skipped_updates = 0;          ///< updates skipped (non-finite θ or P)
  /// One sentence: stable and finite throughout, or what went wrong first and where.
  std::string message;

  static constexpr std::string_view type_name = "RecursiveSrivcResult";
  static constexpr auto fields() {
    using S = RecursiveSrivcResult;
    return std::tuple{
        field("times", &S::times, "t_k of each sample."),
        field("parameters", &S::parameters, "N x np: theta after each sample."),
        field("standard_errors", &S::standard_errors, "N x np: sqrt of the covariance diagonal."),
        field("covariance", &S::covariance,
              "N x np (diagonal) or N x np^2 (full, column-major) per sample."),
        field("noise_variance", &S::noise_variance, "N: weighted output-error variance."),
        field("model", &S::model, "B/A of the final theta."),
        field("final_covariance", &S::final_covariance, "np x np covariance at the last sample."),
        field("stable", &S::stable, "The final A is stable."),
        field("unstable_samples", &S::unstable_samples,
              "Samples after which A was not stable (start-up transient)."),
        field("first_unstable_sample", &S::first_unstable_sample,
              "First sample whose A was not stable, or -1."),
        field("last_unstable_sample", &S::last_unstable_sample,
              "Last sample whose A was not stable, or -1."),
        field("finite", &S::finite, "No update was skipped for non-finite values."),
        field("first_nonfinite_sample", &S::first_nonfinite_sample, "First skipped update, or -1."),
        field("rejected_refreshes", &S::rejected_refreshes,
              "Filter refreshes refused because A was unstable."),
        field("skipped_updates", &S::skipped_updates, "Updates skipped (non-finite theta or P)."),
        field("message", &S::message, "One sentence on stability and finiteness."),
    };
  }
};

/// Runs RecursiveSrivc over the record from `start`. Throws InvalidArgument for bad options,
/// a structure or start it does not support (see RecursiveSrivc), or fewer samples than
/// 2 (n + m + 1). Numerical trouble is reported in the result, never thrown.
RecursiveSrivcResult recursive_srivc(const SampledData& data, const SubmodelOrder& order,
                                     const TransferFunction& start,
                                     const RecursiveSrivcOptions& options = {});

}  // namespace ctid
