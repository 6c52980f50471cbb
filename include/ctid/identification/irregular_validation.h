// `ctid validate --irregular` (issue 37; docs/decisions/0053): a SISO model judged on a record
// at irregular time stamps as logged. The model is simulated from rest at the first stamp by
// simulate_on_stamps (simulation/stamps.h) with the record's input hold, and scored on the
// stamps of the window with the statistics of estimation/validation.h. The residual tests
// count lags in samples: white measurement noise is uncorrelated from sample to sample
// whatever the stamps, so the whiteness and cross-correlation tests keep their null
// hypothesis; a lag is not a fixed time shift on irregular stamps.
#pragma once

#include "ctid/core/additive_model.h"
#include "ctid/estimation/validation.h"
#include "ctid/refined_iv/irregular_srivc.h"

namespace ctid {

/// Fit %, residual statistics and residual tests of `model` on the irregular record, from
/// rest, on the stamps t_k with window_start <= t_k <= window_end (a tolerance of 1e-6 of the
/// median step). fit_zero_state is fit_percent; fit_estimated_state is NaN and states 0
/// (InitialState::estimate is refused). Throws InvalidArgument for a bad record
/// (IrregularRecord::validate), options.initial_state = estimate, an improper model, or a
/// window outside the record or holding fewer than 2 stamps.
ValidationReport validate_model(const AdditiveModel& model, const IrregularRecord& record,
                                const ValidationOptions& options = {});

/// The model's output at every stamp of the record, from rest (what validate_model scores).
Eigen::VectorXd validation_output(const AdditiveModel& model, const IrregularRecord& record);

}  // namespace ctid
