// The sandwich covariance of refined IV from sums over the instrument psi instead of psi
// itself, so an estimator can stream psi (issue 14: memory per sample independent of the model
// order). instrumental_variable_covariance is these pieces applied to a stored psi. Private to
// the estimation layer.
#pragma once

#include <functional>

#include <Eigen/Core>

#include "ctid/refined_iv/covariance.h"

namespace ctid::internal {

/// sum_s g_s g_s' for g = adjoint_ar_filter(x diag(1 / scales), ar) (p x N), without forming
/// g or holding x: the rows of x are given from the newest to the oldest, a chunk at a time,
/// and the backward recursion carries the `order` oldest values of g from one chunk into the
/// next. Memory O(p (1024 + order)).
class AdjointArOuterSum {
 public:
  AdjointArOuterSum(const AutoregressiveModel& ar, const Eigen::VectorXd& scales);

  /// Rows of x in time order, every one earlier than all rows added before.
  void add_earlier(const Eigen::Ref<const Eigen::MatrixXd>& rows);

  const Eigen::MatrixXd& sum() const { return sum_; }

 private:
  Eigen::VectorXd alpha_;    // AR coefficients alpha_1 .. alpha_order
  Eigen::VectorXd inverse_;  // 1 / scales
  Eigen::MatrixXd sum_;      // p x p
  Eigen::MatrixXd g_;        // p x block
  Eigen::MatrixXd carry_;    // p x order: g at the oldest rows added so far, oldest first
  Eigen::Index carried_ = 0;
};

/// The covariance instrumental_variable_covariance computes, from psi' psi (`gram`, q x q) and
/// the residual; for coloured noise `adjoint_outer_sum(ar, scales)` gives the middle factor's
/// sum over the scaled, adjoint-filtered psi (an AdjointArOuterSum fed with psi's rows).
Eigen::MatrixXd covariance_from_gram(
    const Eigen::MatrixXd& gram, const Eigen::VectorXd& residual, int parameter_count,
    NoiseAssumption noise, int max_ar_order,
    const std::function<Eigen::MatrixXd(const AutoregressiveModel& ar,
                                        const Eigen::VectorXd& scales)>& adjoint_outer_sum);

}  // namespace ctid::internal
