// The front door of the delayed-feedback loop (De Iuliis, Germani, Manes 2017; module
// delayed_feedback): forward F and feedback H of W = F / (1 + F H e^{-Δs}) from a record of the
// loop's input and output, with the delay known or scanned, as `ctid feedback` runs it; and
// the residual statistics of such a loop on a record, as `ctid validate` reports them. The
// option and result types stay the module's (delayed_feedback/identification.h).
#pragma once

#include <functional>
#include <string_view>
#include <tuple>

#include "ctid/core/fields.h"
#include "ctid/core/hold.h"
#include "ctid/core/sampled_data.h"
#include "ctid/delayed_feedback/identification.h"
#include "ctid/delayed_feedback/loop_parameters.h"
#include "ctid/delayed_feedback/output_error.h"
#include "ctid/estimation/validation.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid {

/// The loop to estimate: the orders of F (deg D_F) and of H (deg D_H).
struct DelayedFeedbackStructure {
  int forward_order = 1;
  int feedback_order = 1;

  static constexpr std::string_view type_name = "DelayedFeedbackStructure";
  static constexpr auto fields() {
    using S = DelayedFeedbackStructure;
    return std::tuple{
        field("forward_order", &S::forward_order, AtLeast{1}, "Order of F (deg D_F)."),
        field("feedback_order", &S::feedback_order, AtLeast{1}, "Order of H (deg D_H)."),
    };
  }
  /// Throws InvalidArgument naming the first bad field by its full path, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// The loop with the delay Δ known [s]: identify_delayed_feedback (step 1, the separation
/// candidates, the output-error refinement from each). Throws InvalidArgument as it does
/// (orders < 1, Δ < 0, too few samples, a record not longer than Δ).
FeedbackIdentificationResult identify(const SampledData& data,
                                      const DelayedFeedbackStructure& structure, double delay,
                                      const FeedbackIdentificationOptions& options = {});

/// The loop with Δ unknown: identify_delayed_feedback_with_delay_scan (a grid scan of Δ, the
/// identification at the best point, then the joint or golden-section refinement of Δ).
/// `progress`, if given, is called once per grid point. Throws InvalidArgument as it does.
DelayIdentificationResult identify(const SampledData& data,
                                   const DelayedFeedbackStructure& structure,
                                   const DelayIdentificationOptions& options,
                                   const std::function<void(int, int)>& progress = {});

/// `ctid validate`'s residual statistics (estimation/validation.h) for a delayed-feedback loop:
/// validate_loop, its output simulated from rest with the measured input continued by `hold`
/// (`substeps` per sample). Throws InvalidArgument when the loop cannot be simulated.
ValidationReport validate_model(const DelayedFeedbackLoop& loop, const SampledData& data, Hold hold,
                                int substeps = 4, int max_lag = 20);

}  // namespace ctid
