// The front door of shared-pole estimation from time records: mimo_srivc.
#include "ctid/identification/mimo.h"

namespace ctid {

MimoEstimationResult identify(const MimoData& data, const std::vector<SubmodelOrder>& orders,
                              const MimoIdentificationOptions& options,
                              const std::function<void(int, int)>& progress) {
  return mimo_srivc(data, orders, options.refined_iv, options.initial_model, progress);
}

}  // namespace ctid
