// Time responses of a process model (issue 36): the step or impulse response of the estimate,
// with its band and the step characteristics' standard errors by the delta method in the
// process parameters themselves (K, Tp1, ..., Td), so their correlations, the dead time's
// included, carry into the band.
#pragma once

#include "ctid/process_model/process_model.h"
#include "ctid/simulation/time_response.h"

namespace ctid {

/// The response of options.kind of `result`'s model on the options' grid (as
/// time_response(AdditiveModel) chooses it), and the step characteristics. With a covariance
/// in the result (parameters x parameters), the standard deviation of y(t_k) and of each
/// characteristic is sqrt(g' P g), g their central-difference gradient in the parameters
/// (step 1e-6 |value|, 1e-9 at 0), and the band is output -+ z standard deviations. Throws
/// InvalidArgument for a result whose structure, names, parameters or covariance do not agree,
/// or bad options.
TimeResponse process_time_response(const ProcessModelResult& result,
                                   const TimeResponseOptions& options = {});

}  // namespace ctid
