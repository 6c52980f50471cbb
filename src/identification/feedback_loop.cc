// The front door of the delayed-feedback loop: identify_delayed_feedback, with or without the
// delay scan, and validate_loop.
#include "ctid/identification/feedback_loop.h"

namespace ctid {

FeedbackIdentificationResult identify(const SampledData& data,
                                      const DelayedFeedbackStructure& structure, double delay,
                                      const FeedbackIdentificationOptions& options) {
  return identify_delayed_feedback(data, structure.forward_order, structure.feedback_order, delay,
                                   options);
}

DelayIdentificationResult identify(const SampledData& data,
                                   const DelayedFeedbackStructure& structure,
                                   const DelayIdentificationOptions& options,
                                   const std::function<void(int, int)>& progress) {
  return identify_delayed_feedback_with_delay_scan(data, structure.forward_order,
                                                   structure.feedback_order, options, progress);
}

ValidationReport validate_model(const DelayedFeedbackLoop& loop, const SampledData& data, Hold hold,
                                int substeps, int max_lag) {
  return validate_loop(loop, data, hold, substeps, max_lag);
}

}  // namespace ctid
