// Open-loop refined IV for several inputs and outputs with poles shared by every channel
// (issue 13): the additive iteration (29) of González et al. generalised to
// y_j = sum_i sum_k R_i[j, k](p) / A_i(p) u_k + v_j. Each output j contributes the equations
// of (28) with its own residuals y~_ij = y_j - sum_{l != i} G_l,j u; the denominators' rows
// are summed over the outputs and every numerator has its own rows. The numerator regressors
// p^r / A_l u_k are the same for every output, so they are projected out once per iteration
// (one QR factorisation) and the denominators come from the small projected system; each
// output's numerators follow by back-substitution. One output and one input give the
// equations of (29) exactly. See docs/decisions/0018-mimo-shared-poles.md.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/hold.h"
#include "ctid/core/mimo_data.h"
#include "ctid/core/mimo_model.h"
#include "ctid/estimation/termination.h"
#include "ctid/estimation/verdict.h"

namespace ctid {

struct MimoRefinedIvOptions {
  /// Upper bound on the iterations. >= 1.
  int max_iterations = 100;
  /// Stop when ||beta_{j+1} - beta_j|| / ||beta_j|| < tolerance. In (0, 1).
  double tolerance = 1e-10;
  /// Interpolation of the measured outputs between samples before filtering.
  Hold output_interpolation = Hold::first_order_hold;
  /// Estimate a direct term D (outputs x inputs) besides the strictly proper or biproper
  /// submodels: G = sum_i R_i / A_i + D (e.g. accelerations from forces with m_i < n_i).
  bool direct_term = false;

  static constexpr std::string_view type_name = "MimoRefinedIvOptions";
  static constexpr auto fields() {
    using O = MimoRefinedIvOptions;
    return std::tuple{
        field("max_iterations", &O::max_iterations, AtLeast{1}, "Upper bound on the iterations."),
        field("tolerance", &O::tolerance, Between{0.0, 1.0},
              "Relative parameter change that stops the iteration."),
        field("output_interpolation", &O::output_interpolation,
              "Interpolation of the measured outputs before filtering."),
        field("direct_term", &O::direct_term, "Estimate a direct term D as well."),
    };
  }
  void validate() const { validate_fields(*this); }
};

struct MimoEstimationResult {
  /// The estimate: the iterate with the lowest output error (none if nothing was computed).
  std::optional<MimoAdditiveModel> model;
  Termination termination = Termination::not_run;
  std::string message;  ///< one sentence: how the iteration ended
  int iterations = 0;
  /// Per output: mean squared output error y_j - G_j u and fit_percent on the data.
  Eigen::VectorXd mean_squared_errors;
  Eigen::VectorXd fit_percent;
  /// Finite, stable, no output fitted worse than its mean, well-conditioned equations.
  Verdict verdict;
  bool converged() const { return termination == Termination::converged; }
};

/// Estimates the shared denominators and every numerator of `orders` (n_i >= 1, m_i, no
/// integrators) from open-loop data, starting from `initial_model` (its orders must match) or,
/// without one, from the best of a common-denominator least-squares fit over every channel
/// at a grid of state-variable-filter bandwidths (poles grouped into the submodels, numerators
/// by least squares). Throws InvalidArgument for bad options,
/// orders, start or too few samples; the outcome of the iteration is in the result.
MimoEstimationResult mimo_srivc(const MimoData& data, const std::vector<SubmodelOrder>& orders,
                                const MimoRefinedIvOptions& options = {},
                                const std::optional<MimoAdditiveModel>& initial_model = {});

}  // namespace ctid
