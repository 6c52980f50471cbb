// The front door of output-only modal analysis: oma.
#include "ctid/identification/output_only.h"

#include <utility>

namespace ctid {

OmaResult identify_output_only(const Eigen::MatrixXd& outputs, double sample_time,
                               const OmaOptions& options, std::vector<std::string> channel_names) {
  return oma(outputs, sample_time, options, std::move(channel_names));
}

}  // namespace ctid
