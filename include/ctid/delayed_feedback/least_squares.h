// Step 1 solvers for the delayed-feedback regression y = C θ (De Iuliis, Germani, Manes
// 2017, Section 3.1): batch least squares by column-pivoted QR or SVD on unit-norm columns
// (never the normal equations: cond(C) reaches 1e11), optional ridge with the weight chosen by
// generalised cross-validation (nuisance columns are projected out, not penalised), and the
// recursive least squares of eq. (13) with forgetting factor λ, θ(0) and P(0).
#pragma once

#include <array>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/polynomial.h"
#include "ctid/delayed_feedback/regressors.h"
#include "ctid/estimation/termination.h"

namespace ctid {

/// α̂, β̂ (monic), γ̂ of W = α/(β + γ e^{-Δs}) with the diagnostics of the fit. The outcome:
/// converged (one solve, or every RLS update), singular_equations (a rank-deficient regressor
/// without regularisation; α̂, β̂, γ̂ are then empty) or non_finite (NaN/Inf in the regression).
struct ClosedLoopEstimate : Outcome {
  Polynomial alpha;
  Polynomial beta;
  Polynomial gamma;
  Eigen::VectorXd theta;          ///< [β_{q-1..0} | γ_{q-2..0} | α_{q-1..0}], the paper's θ
  Eigen::VectorXd nuisance;       ///< initial-condition / boundary coefficients (may be empty)
  double residual_rms = 0.0;      ///< rms of target - C [θ; nuisance]
  double condition_number = 0.0;  ///< of the column-scaled regressor (θ part)
  double ridge = 0.0;  ///< ridge weight used, relative to σ_max² of the scaled θ block
  int equations = 0;
  /// θ̂(k) after each RLS update (only when asked for).
  std::vector<Eigen::VectorXd> theta_history;

  static constexpr std::string_view type_name = "ClosedLoopEstimate";
  static constexpr auto fields() {
    using R = ClosedLoopEstimate;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("alpha", &R::alpha, "alpha (ascending)."),
            field("beta", &R::beta, "beta (monic, ascending)."),
            field("gamma", &R::gamma, "gamma (ascending)."),
            field("theta", &R::theta, "The paper's theta [beta | gamma | alpha], descending."),
            field("nuisance", &R::nuisance, "Initial-condition / boundary coefficients."),
            field("residual_rms", &R::residual_rms, "rms of target - C [theta; nuisance]."),
            field("condition_number", &R::condition_number,
                  "Of the column-scaled regressor (theta part)."),
            field("ridge", &R::ridge, "Ridge weight used, relative to sigma_max^2."),
            field("equations", &R::equations, "Equations used."),
            field("theta_history", &R::theta_history, "theta(k) after each RLS update."),
        });
  }
};

/// Splits θ into α, β (monic, degree q), γ; theta.size() must be 3q - 1.
ClosedLoopEstimate closed_loop_polynomials(const Eigen::VectorXd& theta, int q);
/// θ of known polynomials (β monic of degree q, deg α < q, deg γ < q - 1).
Eigen::VectorXd closed_loop_theta(const Polynomial& alpha, const Polynomial& beta,
                                  const Polynomial& gamma);

enum class LeastSquaresSolver { qr, svd };
inline constexpr std::array<Enumerator<LeastSquaresSolver>, 2> least_squares_solver_enumerators{{
    {LeastSquaresSolver::qr, "qr", "Column-pivoted QR."},
    {LeastSquaresSolver::svd, "svd", "Singular value decomposition."},
}};
constexpr std::span<const Enumerator<LeastSquaresSolver>> enumerators(LeastSquaresSolver) {
  return least_squares_solver_enumerators;
}

enum class Regularisation {
  none,   ///< plain least squares; a rank-deficient regressor ends in singular_equations
  fixed,  ///< ridge with weight `ridge` (relative to σ_max² of the scaled θ block)
  gcv,    ///< ridge with the weight minimising generalised cross-validation
};
inline constexpr std::array<Enumerator<Regularisation>, 3> regularisation_enumerators{{
    {Regularisation::none, "none", "Plain least squares."},
    {Regularisation::fixed, "fixed", "Ridge with the fixed relative weight ridge."},
    {Regularisation::gcv, "gcv", "Ridge weight by generalised cross-validation."},
}};
constexpr std::span<const Enumerator<Regularisation>> enumerators(Regularisation) {
  return regularisation_enumerators;
}

struct BatchLeastSquaresOptions {
  LeastSquaresSolver solver = LeastSquaresSolver::qr;
  Regularisation regularisation = Regularisation::none;
  double ridge = 1e-8;
  /// Log-spaced GCV grid of relative weights in [gcv_min, gcv_max].
  double gcv_min = 1e-14;
  double gcv_max = 1e-1;
  int gcv_points = 80;
  /// Singular values below this times σ_max (scaled columns) count as zero.
  double rank_tolerance = 1e-14;

  static constexpr std::string_view type_name = "BatchLeastSquaresOptions";
  static constexpr auto fields() {
    using O = BatchLeastSquaresOptions;
    constexpr double inf = std::numeric_limits<double>::infinity();
    return std::tuple{
        field("solver", &O::solver, "Solver of the unregularised problem."),
        field("regularisation", &O::regularisation, "Ridge choice."),
        field("ridge", &O::ridge, Between{0.0, inf, true, false},
              "Fixed ridge weight, relative to sigma_max^2 of the scaled theta block."),
        field("gcv_min", &O::gcv_min, Between{0.0, inf}, "Lower end of the GCV grid."),
        field("gcv_max", &O::gcv_max, Between{0.0, inf}, "Upper end of the GCV grid (> gcv_min)."),
        field("gcv_points", &O::gcv_points, AtLeast{2}, "Log-spaced GCV grid points."),
        field("rank_tolerance", &O::rank_tolerance, Between{0.0, 1.0},
              "Singular values below this times sigma_max count as zero."),
    };
  }
  void validate() const { validate_fields(*this); }
  /// gcv_max > gcv_min.
  void check_relations(const std::string& path) const;
};

ClosedLoopEstimate estimate_closed_loop_batch(const FeedbackRegression& regression,
                                              const BatchLeastSquaresOptions& options = {});

struct RecursiveLeastSquaresOptions {
  double forgetting = 0.99;                                  ///< λ in (0, 1]
  std::optional<Eigen::VectorXd> initial_theta;              ///< θ(0); zero when absent
  double initial_covariance = 1.0;                           ///< P(0) = initial_covariance * I ...
  std::optional<Eigen::MatrixXd> initial_covariance_matrix;  ///< ... unless given in full
  bool keep_history = false;                                 ///< fill theta_history

  static constexpr std::string_view type_name = "RecursiveLeastSquaresOptions";
  static constexpr auto fields() {
    using O = RecursiveLeastSquaresOptions;
    constexpr double inf = std::numeric_limits<double>::infinity();
    return std::tuple{
        field("forgetting", &O::forgetting, Between{0.0, 1.0, false, true},
              "Forgetting factor lambda."),
        field("initial_theta", &O::initial_theta, "theta(0) (all columns); None: zero."),
        field("initial_covariance", &O::initial_covariance, Between{0.0, inf},
              "P(0) = initial_covariance * I ..."),
        field("initial_covariance_matrix", &O::initial_covariance_matrix,
              "... unless P(0) is given in full."),
        field("keep_history", &O::keep_history, "Keep theta(k) after every update."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// Eq. (13): L = P c^T/(c P c^T + λ), P <- (P - L c P)/λ, θ <- θ + L (y - c θ).
class RecursiveLeastSquares {
 public:
  RecursiveLeastSquares(Eigen::VectorXd theta0, Eigen::MatrixXd p0, double forgetting);
  void update(const Eigen::RowVectorXd& c, double y);
  const Eigen::VectorXd& theta() const { return theta_; }
  const Eigen::MatrixXd& covariance() const { return p_; }

 private:
  Eigen::VectorXd theta_;
  Eigen::MatrixXd p_;
  double forgetting_;
};

/// Runs eq. (13) over the equations in order (all columns, nuisance included).
ClosedLoopEstimate estimate_closed_loop_recursive(const FeedbackRegression& regression,
                                                  const RecursiveLeastSquaresOptions& options = {});

}  // namespace ctid
