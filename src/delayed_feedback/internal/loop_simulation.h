// Simulation of the loop of parameters ρ and its sensitivities, shared by the output error,
// the Cramér-Rao bound and the IV iterations. Private to the delayed_feedback module.
#pragma once

#include <Eigen/Core>

#include "ctid/core/hold.h"
#include "ctid/delayed_feedback/cramer_rao.h"

namespace ctid::internal {

/// ŷ for ρ; +inf entries when the simulation overflows.
Eigen::VectorXd simulate_rho(const Eigen::VectorXd& rho, int n, int m, double delay,
                             const Eigen::VectorXd& input, double delta, Hold hold, int substeps);

/// ∂ŷ/∂ρ by central differences.
Eigen::MatrixXd sensitivity(const Eigen::VectorXd& rho, int n, int m, double delay,
                            const Eigen::VectorXd& input, double delta, Hold hold, int substeps);

/// Covariance variance (JᵀJ)^{-1} on column-scaled J and the separability verdict.
SeparabilityReport report_from_jacobian(const Eigen::MatrixXd& jac, const Eigen::VectorXd& rho,
                                        double variance, double threshold);

}  // namespace ctid::internal
