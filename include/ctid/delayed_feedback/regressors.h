// Step 1 regressors for the delayed-feedback loop W = α/(β + γ e^{-Δs}) (De Iuliis, Germani,
// Manes 2017, eqs. 3-12). With q = n + m, θ = [β_{q-1..0} | γ_{q-2..0} | α_{q-1..0}] (3q - 1
// entries, the paper's descending order) and y(k) = C(k) θ. Signals are filtered by L(s) =
// 1/s^q (the paper's Brunovsky integrator chain, eqs. 6-7) or, better conditioned, by the
// linear integral filter 1/(s + a)^q; sampled data are interpolated linearly between samples
// and the filter integrated exactly (eqs. 8-9). Δ need not be a multiple of δ.
#pragma once

#include <array>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"

namespace ctid {

/// Exact propagation of dx/dt = A x + B y over τ when y is linear on the step:
/// x(t + τ) = a x(t) + b y(t) + g ẏ, with b = ∫_0^τ e^{Aθ} B dθ and
/// g = ∫_0^τ e^{Aθ}(τ - θ) B dθ. The paper's B_δ is b(δ) and its B̄_δ is g(δ)/δ.
struct FilterStep {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::VectorXd g;
};

/// Brunovsky chain of order q (v_1 the q-fold integral, v_q the single integral): the closed
/// forms a_ij = τ^{j-i}/(j-i)!, b_i = τ^{r+1}/(r+1)!, g_i = τ^{r+2}/(r+2)!, r = q - i.
FilterStep integrator_chain_step(int q, double tau);
/// Controllable form of 1/(s + a)^q (state i = s^{i-1}/(s+a)^q y, i = 1..q) propagated by the
/// simulator's exact FOH discretisation (simulation/discretization.h); pole a = 0 gives
/// integrator_chain_step, τ = 0 the identity.
FilterStep integral_filter_step(int q, double pole, double tau);

enum class RegressorFilter {
  integrator_chain,        ///< 1/s^q, the paper's choice (eqs. 6-9)
  linear_integral_filter,  ///< 1/(s + a)^q, regressors stay bounded on long records
};
inline constexpr std::array<Enumerator<RegressorFilter>, 2> regressor_filter_enumerators{{
    {RegressorFilter::integrator_chain, "integrator_chain",
     "1/s^q, the paper's choice (eqs. 6-9)."},
    {RegressorFilter::linear_integral_filter, "linear_integral_filter",
     "1/(s + a)^q: regressors stay bounded on long records."},
}};
constexpr std::span<const Enumerator<RegressorFilter>> enumerators(RegressorFilter) {
  return regressor_filter_enumerators;
}

struct FeedbackRegressorOptions {
  RegressorFilter filter = RegressorFilter::integrator_chain;
  /// a > 0 of 1/(s + a)^q [rad/s]; used by linear_integral_filter only.
  double filter_pole = 1.0;
  /// Append nuisance columns t^j e^{-at}/j! and their Δ-delayed copies (j = 0..q-1): they
  /// absorb non-zero initial conditions (the paper's Remark 1) and the boundary terms of
  /// the piecewise-linear interpolation, which otherwise integrate into polynomial drift.
  /// The delayed copies are added only when equations start before Δ (after Δ they are in
  /// the span of the undelayed ones).
  bool initial_condition_terms = false;
  /// First equation k; -1 uses the paper's k = p = ceil(Δ/δ).
  int first_equation = -1;

  static constexpr std::string_view type_name = "FeedbackRegressorOptions";
  static constexpr auto fields() {
    using O = FeedbackRegressorOptions;
    return std::tuple{
        field("filter", &O::filter, "Filter of the step-1 regressors."),
        field("filter_pole", &O::filter_pole,
              "Pole a > 0 of 1/(s + a)^q [rad/s]; checked and used by linear_integral_filter "
              "only."),
        field("initial_condition_terms", &O::initial_condition_terms,
              "Append nuisance columns for initial conditions and interpolation boundaries."),
        field("first_equation", &O::first_equation, AtLeast{-1},
              "First equation k; -1: the paper's ceil(delay / sample time)."),
    };
  }
  void validate() const { validate_fields(*this); }
  /// filter_pole > 0 and finite when the linear integral filter is used.
  void check_relations(const std::string& path) const;
};

/// Rows are the equations k = first..N-1: target(k) = regressor.row(k) [θ; nuisance].
/// With the chain the target is y(k); with 1/(s+a)^q it is s^q/(s+a)^q y.
struct FeedbackRegression {
  Eigen::MatrixXd regressor;
  Eigen::VectorXd target;
  Eigen::VectorXi sample_index;
  int forward_order = 0;   ///< n
  int feedback_order = 0;  ///< m
  int theta_size = 0;      ///< 3(n + m) - 1
  int nuisance_size = 0;
  double delay = 0.0;
  double sample_time = 0.0;

  static constexpr std::string_view type_name = "FeedbackRegression";
  static constexpr auto fields() {
    using R = FeedbackRegression;
    return std::tuple{
        field("regressor", &R::regressor, "C: one row per equation, [theta | nuisance] columns."),
        field("target", &R::target, "y (chain) or s^q/(s+a)^q y (linear integral filter)."),
        field("sample_index", &R::sample_index, "Sample k of each equation."),
        field("forward_order", &R::forward_order, "n."),
        field("feedback_order", &R::feedback_order, "m."),
        field("theta_size", &R::theta_size, "3(n + m) - 1."),
        field("nuisance_size", &R::nuisance_size, "Nuisance columns."),
        field("delay", &R::delay, "Delay [s]."),
        field("sample_time", &R::sample_time, "Sample time [s]."),
    };
  }
};

/// The highest order of F or H: the separation step (Kronecker LS, approximate GCD) works on
/// products of the two polynomials, and orders 40/40 on 600 samples ran for minutes.
inline constexpr int kMaxFeedbackOrder = 10;

/// Why the regression cannot be built from this record (orders < 1 or > kMaxFeedbackOrder,
/// Δ < 0, a record not longer
/// than Δ, fewer equations than unknowns), or nullopt: lets a scan skip such delays.
std::optional<std::string> feedback_regression_problem(const SampledData& data, int forward_order,
                                                       int feedback_order, double delay,
                                                       const FeedbackRegressorOptions& options);

/// Throws InvalidArgument for orders < 1, Δ < 0, a record not longer than Δ, or fewer
/// equations than unknowns.
FeedbackRegression build_feedback_regression(const SampledData& data, int forward_order,
                                             int feedback_order, double delay,
                                             const FeedbackRegressorOptions& options = {});

}  // namespace ctid
