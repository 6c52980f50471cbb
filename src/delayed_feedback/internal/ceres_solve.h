// One place for the dense Levenberg-Marquardt set-up shared by the delayed-feedback
// estimators (output error, structured step 1, min J). Private to the estimation layer.
#pragma once

#include <ceres/ceres.h>

#include <string>

#include "ctid/estimation/termination.h"

namespace ctid::internal {

/// Stopping rules of one solve; the defaults are Ceres' own except the iteration cap.
struct LeastSquaresSettings {
  int max_iterations = 50;
  double function_tolerance = 1e-6;
  double parameter_tolerance = 1e-8;
  double gradient_tolerance = 1e-10;
  /// Accept steps that raise the cost for a while (crosses long curved valleys faster).
  bool nonmonotonic_steps = false;
};

/// Outcome's termination: converged (Ceres reported CONVERGENCE), iteration_limit (Ceres'
/// NO_CONVERGENCE) or non_finite (a failed evaluation); its message is Ceres' own.
struct LeastSquaresOutcome : Outcome {
  double sum_of_squares = 0.0;  ///< |r|² at the end (twice Ceres' cost)
};

/// Levenberg-Marquardt with a dense QR on `problem`, silently; the parameter blocks hold the
/// solution on return.
inline LeastSquaresOutcome solve_least_squares(ceres::Problem& problem,
                                               const LeastSquaresSettings& settings) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = settings.max_iterations;
  so.function_tolerance = settings.function_tolerance;
  so.parameter_tolerance = settings.parameter_tolerance;
  so.gradient_tolerance = settings.gradient_tolerance;
  so.use_nonmonotonic_steps = settings.nonmonotonic_steps;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  LeastSquaresOutcome outcome;
  outcome.sum_of_squares = 2.0 * summary.final_cost;
  outcome.iterations = static_cast<int>(summary.iterations.size());
  outcome.termination = summary.termination_type == ceres::CONVERGENCE ? Termination::converged
                        : summary.termination_type == ceres::NO_CONVERGENCE
                            ? Termination::iteration_limit
                            : Termination::non_finite;
  outcome.message = summary.message;
  return outcome;
}

}  // namespace ctid::internal
