// CLSRIVC: the closed-loop SRIVC for one unfactored model (Gilson et al. 2008; González et
// al., Remark 4, eq. 30 with the instrument (20)). The loop is u_k = C_d(q)(r_k - y_k) with
// a known discrete controller and a measured reference r; the instrument filters
// S_uo(q) r, S_uo = C_d / (1 + G_d C_d), G_d the current model's ZOH equivalent.
#pragma once

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/sampled_data.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

/// As srivc(), from closed-loop data with a reference. The controller's sample time must
/// equal the data's. Throws InvalidArgument if the data has no reference.
EstimationResult clsrivc(const SampledData& data, const DiscreteTransferFunction& controller,
                         const SubmodelOrder& order, const RefinedIvOptions& options = {});

}  // namespace ctid
