// θ(ρ), the nuisance projection and the structured Levenberg-Marquardt shared by the
// structured step 1 and the IV iterations. Private to the delayed_feedback module.
#pragma once

#include <Eigen/Core>

#include "ctid/core/sampled_data.h"
#include "ctid/delayed_feedback/regressors.h"
#include "ctid/delayed_feedback/structured_iv.h"
#include "delayed_feedback/internal/ceres_solve.h"

namespace ctid::internal {

/// θ(ρ) in the paper's order [β_{q-1..0} | γ_{q-2..0} | α_{q-1..0}].
Eigen::VectorXd theta_of(const Eigen::VectorXd& rho, int n, int m);

// The θ block and target with the nuisance columns projected out; `nuisance` is the
// orthonormal basis used, so instruments can be projected the same way.
struct ProjectedSystem {
  Eigen::MatrixXd c;
  Eigen::VectorXd y;
  Eigen::MatrixXd nuisance;
};

ProjectedSystem project_nuisance(const FeedbackRegression& reg);

/// Levenberg-Marquardt on |y - c θ(ρ)|² from rho (updated in place); its outcome and cost.
LeastSquaresOutcome structured_least_squares(const Eigen::MatrixXd& c, const Eigen::VectorXd& y,
                                             int n, int m, int max_iterations,
                                             Eigen::VectorXd& rho);

/// Structured step 1 with the 1/(s + a)^q filter at `pole`, then the bias-corrected IV
/// iterations from it; InvalidArgument when no stable start exists.
StructuredIvResult iv_start(const SampledData& data, int n, int m, double delay,
                            FeedbackRegressorOptions regressors, double pole,
                            const StructuredIvOptions& iv);

}  // namespace ctid::internal
