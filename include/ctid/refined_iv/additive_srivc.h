// Additive refined IV estimators (González et al., Section 4): the iteration (29) with
// filtered residual outputs (22)-(23), regressors (24) and the instrument (10) in open loop or
// (20) in closed loop; an integrator submodel uses (31)-(32). Submodels B_i/(p^l_i A_i) with
// anti-monic A_i, at most one biproper and at most one with integrators.
#pragma once

#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/sampled_data.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

/// Open loop: K = orders.size() submodels. The automatic start fills the submodels in the
/// given order with poles of increasing magnitude, so list them from slowest to fastest.
EstimationResult additive_srivc(const SampledData& data, const std::vector<SubmodelOrder>& orders,
                                const RefinedIvOptions& options = {});

/// Closed loop with a known controller and measured reference (instrument (20)). When the
/// controller does not stabilise an intermediate model, S_uo r of the previous iteration is
/// reused and counted in EstimationResult::sensitivity_fallbacks.
EstimationResult additive_clsrivc(const SampledData& data,
                                  const DiscreteTransferFunction& controller,
                                  const std::vector<SubmodelOrder>& orders,
                                  const RefinedIvOptions& options = {});

}  // namespace ctid
