// The front door of output-only modal analysis: oma, and oma_multi_setup for several setups.
#include "ctid/identification/output_only.h"

#include <utility>

namespace ctid {

OmaResult identify_output_only(const Eigen::MatrixXd& outputs, double sample_time,
                               const OmaOptions& options, std::vector<std::string> channel_names) {
  return oma(outputs, sample_time, options, std::move(channel_names));
}

MultiSetupResult identify_output_only(const std::vector<OmaSetup>& setups,
                                      const MultiSetupOptions& options) {
  return oma_multi_setup(setups, options);
}

}  // namespace ctid
