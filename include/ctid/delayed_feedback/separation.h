// Step 2 of the delayed-feedback identification: F and H from α̂, β̂, γ̂ (De Iuliis, Germani,
// Manes 2017, Section 3.2). (a) The Kronecker least-squares fit min J of eqs. (19)-(21),
// solved by Levenberg-Marquardt (Ceres) from several starts; (b) the approximate GCD by an
// SVD-truncated Kalman observability decomposition, eqs. (22)-(24), in the paper's basis:
// the controllable canonical form of F̃ = α̂/β̂ and of H̃ = γ̂/α̂ (α̂ made monic first).
// Polynomials are ascending (polynomial.h); F and H come back with monic denominators.
#pragma once

#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/polynomial.h"
#include "ctid/core/transfer_function.h"
#include "ctid/estimation/termination.h"

namespace ctid {

/// J of the paper for candidate F = N_F/D_F, H = N_H/D_H (monic denominators):
/// |α̂ - N_F D_H|² + |β̂ - D_F D_H|² + |γ̂ - N_F N_H|² over the coefficients.
double kronecker_cost(const Polynomial& alpha, const Polynomial& beta, const Polynomial& gamma,
                      const TransferFunction& forward, const TransferFunction& feedback);

struct KroneckerSeparationOptions {
  /// Start from every split of the roots of β̂ into n for D_F and m for D_H (conjugate pairs
  /// kept together; numerators fitted linearly), and from the GCD estimate. Off: GCD only.
  bool multi_start = true;
  int max_iterations = 200;

  static constexpr std::string_view type_name = "KroneckerSeparationOptions";
  static constexpr auto fields() {
    using O = KroneckerSeparationOptions;
    return std::tuple{
        field("multi_start", &O::multi_start,
              "Also start from every split of the roots of beta (off: the GCD start only)."),
        field("max_iterations", &O::max_iterations, AtLeast{1},
              "Levenberg-Marquardt iterations per start."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// One refined start of min J.
struct KroneckerCandidate {
  std::string start;  ///< "gcd" or "roots split k"
  TransferFunction forward{Polynomial{0.0}, Polynomial{1.0}};
  TransferFunction feedback{Polynomial{0.0}, Polynomial{1.0}};
  double cost = 0.0;  ///< J after Levenberg-Marquardt from this start

  static constexpr std::string_view type_name = "KroneckerCandidate";
  static constexpr auto fields() {
    using R = KroneckerCandidate;
    return std::tuple{
        field("start", &R::start, "'gcd' or 'roots split k'."),
        field("forward", &R::forward, "F of this start."),
        field("feedback", &R::feedback, "H of this start."),
        field("cost", &R::cost, "J after Levenberg-Marquardt from this start."),
    };
  }
};

/// The outcome is the best start's Levenberg-Marquardt ending (its iterations), or no_solution
/// when no start is finite (F and H are then the default zero models).
struct KroneckerSeparationResult : Outcome {
  TransferFunction forward{Polynomial{0.0}, Polynomial{1.0}};
  TransferFunction feedback{Polynomial{0.0}, Polynomial{1.0}};
  double cost = 0.0;                           ///< J at the returned F, H
  int starts = 0;                              ///< starts refined
  std::string best_start;                      ///< "gcd" or "roots split k"
  std::vector<KroneckerCandidate> candidates;  ///< every refined start, in start order

  static constexpr std::string_view type_name = "KroneckerSeparationResult";
  static constexpr auto fields() {
    using R = KroneckerSeparationResult;
    return join_fields(Outcome::fields(),
                       std::tuple{
                           field("forward", &R::forward, "F(s)."),
                           field("feedback", &R::feedback, "H(s)."),
                           field("cost", &R::cost, "J at the returned F, H."),
                           field("starts", &R::starts, "Starts refined."),
                           field("best_start", &R::best_start, "The winning start."),
                           field("candidates", &R::candidates, "Every refined start."),
                       });
  }
};

KroneckerSeparationResult separate_kronecker(const Polynomial& alpha, const Polynomial& beta,
                                             const Polynomial& gamma, int forward_order,
                                             int feedback_order,
                                             const KroneckerSeparationOptions& options = {});

struct GcdSeparationResult {
  TransferFunction forward{Polynomial{0.0}, Polynomial{1.0}};
  TransferFunction feedback{Polynomial{0.0}, Polynomial{1.0}};
  Eigen::VectorXd forward_singular_values;   ///< of the observability matrix of F̃ (q values)
  Eigen::VectorXd feedback_singular_values;  ///< of H̃ (q - 1 values)
  double forward_gap = 0.0;       ///< σ_n / σ_{n+1}: large when cancelling m states is justified
  double feedback_gap = 0.0;      ///< σ_m / σ_{m+1}
  Polynomial cancelled_forward;   ///< det(sI - Â_u) for F̃, the approximate D_H
  Polynomial cancelled_feedback;  ///< for H̃, the approximate monic N_F

  static constexpr std::string_view type_name = "GcdSeparationResult";
  static constexpr auto fields() {
    using R = GcdSeparationResult;
    return std::tuple{
        field("forward", &R::forward, "F(s)."),
        field("feedback", &R::feedback, "H(s)."),
        field("forward_singular_values", &R::forward_singular_values,
              "Singular values of the observability matrix of alpha/beta."),
        field("feedback_singular_values", &R::feedback_singular_values,
              "Singular values of the observability matrix of gamma/alpha."),
        field("forward_gap", &R::forward_gap, "sigma_n / sigma_{n+1}."),
        field("feedback_gap", &R::feedback_gap, "sigma_m / sigma_{m+1}."),
        field("cancelled_forward", &R::cancelled_forward,
              "The cancelled part of alpha/beta (approximate D_H)."),
        field("cancelled_feedback", &R::cancelled_feedback,
              "The cancelled part of gamma/alpha (approximate monic N_F)."),
    };
  }
};

/// Throws InvalidArgument if orders < 1, deg β̂ != n + m or α̂ has degree < n + m - 1.
GcdSeparationResult separate_approximate_gcd(const Polynomial& alpha, const Polynomial& beta,
                                             const Polynomial& gamma, int forward_order,
                                             int feedback_order);

}  // namespace ctid
