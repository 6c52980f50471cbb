// The two-stage method (decision 0043) as its two stages, so that a caller fitting several
// structures to the same records fits stage 1 once (the structure scan, decision 0071).
// Private to the identification layer.
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/sampled_data.h"
#include "ctid/identification/identification.h"
#include "ctid/identification/two_stage.h"

namespace ctid::internal {

/// Stage 1 on every record: the kind and order chosen on the longest, each record's fit, and
/// the records with u replaced by the simulated input u_hat = S_hat r.
struct StageOne {
  TwoStageOptions chosen;
  std::vector<SensitivityFit> fits;           // per record
  std::vector<SampledData> simulated;         // per record: (u_hat, y)
  std::vector<Eigen::VectorXd> references;    // per record: r
  std::vector<Eigen::VectorXd> input_errors;  // per record: u - u_hat
};

/// Stage 1 as identify runs it with IdentificationOptions::two_stage (`two_stage`: those
/// options). Throws InvalidArgument for a record without a reference or that stage 1 refuses.
StageOne fit_stage_one(std::span<const SampledData> records, const TwoStageOptions& two_stage);

/// Stage 2: the open-loop identification of `structure` on stage 1's simulated records, with
/// the two-stage report (IdentificationResult::two_stage, its assumptions, the message).
IdentificationResult identify_from_stage_one(const StageOne& stage_one,
                                             const ModelStructure& structure,
                                             const IdentificationOptions& options,
                                             const IdentificationProgress& progress);

}  // namespace ctid::internal
