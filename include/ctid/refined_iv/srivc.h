// SRIVC: the simplified refined instrumental-variable method for one unfactored
// continuous-time model B(p)/(p^l A(p)) from open-loop data (Young & Jakeman 1980; González
// et al., Remark 4, eq. 30 with the instrument (10); integrators as in Remark 5).
// A is anti-monic (A(0) = 1); the input is a zero-order hold; see RefinedIvOptions.
#pragma once

#include "ctid/core/additive_model.h"
#include "ctid/core/sampled_data.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

/// Estimates B(p)/(p^l A(p)) with deg A = order.n, deg B = order.m, l = order.integrators.
/// Throws InvalidArgument for impossible orders, too few samples for the parameter count,
/// an input that is not persistently exciting of order n + m + 1, or bad options.
EstimationResult srivc(const SampledData& data, const SubmodelOrder& order,
                       const RefinedIvOptions& options = {});

}  // namespace ctid
