// The loop parameters of the delayed-feedback refinements (beyond De Iuliis, Germani, Manes
// 2017): ρ = [a_F | b_F | a_H | b_H], ascending coefficients below the monic leading ones of
// D_F and D_H, and the output error and residual statistics of a loop on a record.
#pragma once

#include <Eigen/Core>

#include "ctid/core/hold.h"
#include "ctid/core/sampled_data.h"
#include "ctid/estimation/validation.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid {

/// ρ of a loop (F, H normalised to monic denominators) and back.
Eigen::VectorXd loop_parameters(const DelayedFeedbackLoop& loop);
DelayedFeedbackLoop loop_from_parameters(const Eigen::VectorXd& rho, int forward_order,
                                         int feedback_order, double delay);

/// True when the loop passes DelayedFeedbackLoop::validate with finite coefficients, so it can
/// be simulated; lets a search skip a degenerate candidate without an exception.
bool loop_is_simulable(const DelayedFeedbackLoop& loop);

/// Output-error rms of a loop on the data (+inf when the loop is not simulable or the
/// simulation overflows).
double loop_output_rms(const SampledData& data, const DelayedFeedbackLoop& loop, Hold hold,
                       int substeps);

/// The residual statistics of `ctid validate` (estimation/validation.h) for a loop: its output
/// simulated from rest with the measured input continued by `hold`. Throws InvalidArgument when
/// the loop cannot be simulated (DelayedFeedbackLoop::validate's message).
ValidationReport validate_loop(const DelayedFeedbackLoop& loop, const SampledData& data, Hold hold,
                               int substeps = 4, int max_lag = 20);

}  // namespace ctid
