// Structured step 1 of the delayed-feedback identification (beyond De Iuliis, Germani, Manes
// 2017): the step-1 equation error minimised over the 2(n+m) true unknowns ρ of F and H.
#pragma once

#include <limits>
#include <string_view>
#include <tuple>
#include <vector>

#include "ctid/delayed_feedback/regressors.h"
#include "ctid/estimation/termination.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid {

/// Structured step 1: the equation error |target - C θ(ρ)|² (nuisance columns projected out)
/// minimised over the 2(n+m) true unknowns, where θ(ρ) stacks β = D_F D_H, γ = N_F N_H,
/// α = N_F D_H. Starts: alternating least squares (the residual is affine in F's parameters
/// for fixed H and vice versa) from D_H = (s + w)^m for each w in start_frequencies, then
/// Levenberg-Marquardt; the smallest cost is kept. The trade between β and γ that makes the
/// unstructured θ ill-determined is not available inside this manifold.
struct StructuredStep1Options {
  std::vector<double> start_frequencies{0.3, 1.0, 3.0};
  int alternating_iterations = 100;
  int max_iterations = 100;

  static constexpr std::string_view type_name = "StructuredStep1Options";
  static constexpr auto fields() {
    using O = StructuredStep1Options;
    return std::tuple{
        field("start_frequencies", &O::start_frequencies,
              Each{Between{0.0, std::numeric_limits<double>::infinity()}},
              "w of the starts D_H = (s + w)^m [rad/s]; at least one."),
        field("alternating_iterations", &O::alternating_iterations, AtLeast{0},
              "Alternating least-squares sweeps per start."),
        field("max_iterations", &O::max_iterations, AtLeast{1},
              "Levenberg-Marquardt iterations per start."),
    };
  }
  void validate() const { validate_fields(*this); }
  /// start_frequencies is not empty.
  void check_relations(const std::string& path) const;
};

/// The outcome of the best start's Levenberg-Marquardt (its iterations), or no_solution when no
/// start ends finite (cost +inf, the loop the default zero models).
struct StructuredStep1Result : Outcome {
  DelayedFeedbackLoop loop{TransferFunction(Polynomial{0.0}, Polynomial{1.0}),
                           TransferFunction(Polynomial{0.0}, Polynomial{1.0}), 0.0};
  double cost = 0.0;  ///< residual sum of squares
  int starts = 0;

  static constexpr std::string_view type_name = "StructuredStep1Result";
  static constexpr auto fields() {
    using R = StructuredStep1Result;
    return join_fields(Outcome::fields(),
                       std::tuple{
                           field("loop", &R::loop, "DelayedFeedbackLoop (F, H, delay)."),
                           field("cost", &R::cost, "Residual sum of squares (inf: none)."),
                           field("starts", &R::starts, "Starts run."),
                       });
  }
};

StructuredStep1Result estimate_structured_step1(const FeedbackRegression& regression,
                                                const StructuredStep1Options& options = {});

}  // namespace ctid
