// The two-stage estimate's covariance with stage 1's error (decision 0072). Private to the
// identification layer.
#pragma once

#include <optional>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "two_stage_stages.h"

namespace ctid::internal {

/// Covariance of `model`'s parameters() when stage 2 fitted it by output-error refined IV
/// (SRIVC, zero-order-hold input, zero initial conditions) to stage_one.simulated: stage 2's
/// noise and stage 1's error of u_hat joined, the two noises' colour and their correlation by
/// a vector AR model of order <= max_noise_order (AIC). Empty when stage 1's or stage 2's
/// gradient is singular.
std::optional<Eigen::MatrixXd> two_stage_covariance(const AdditiveModel& model,
                                                    const StageOne& stage_one, int max_noise_order);

/// The covariance above in place of stage 2's in result.estimate (its standard errors and
/// modal errors, and the verdict judged again with them), when stage 2 was that fit: SRIVC,
/// unfactored or additive, without a noise model, initial conditions, an estimated delay,
/// per-record delays, constraints or relocated modes, on records with a zero-order-hold input.
/// Returns whether it was put in.
bool include_stage_one_error(IdentificationResult& result, const ModelStructure& structure,
                             const IdentificationOptions& options, const StageOne& stage_one);

}  // namespace ctid::internal
