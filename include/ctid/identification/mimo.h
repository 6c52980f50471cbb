// The front door of shared-pole estimation from time records of several inputs and outputs
// (decision 0018): identify(MimoData, orders, ...) runs what `ctid fit --input-columns
// --output-columns` runs, the shared-pole refined IV estimator (refined_iv/mimo_srivc.h), open
// loop, from its automatic start or a given model. The result type stays the estimator's.
#pragma once

#include <functional>
#include <optional>
#include <string_view>
#include <tuple>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/mimo_data.h"
#include "ctid/core/mimo_model.h"
#include "ctid/refined_iv/mimo_srivc.h"

namespace ctid {

struct MimoIdentificationOptions {
  /// Options of the shared-pole estimator (iterations, direct term, known input delays,
  /// rank-one residues, initial conditions, covariance).
  MimoRefinedIvOptions refined_iv;
  /// Start of the iteration (its orders and channels must match); none: the automatic start
  /// (a common-denominator least-squares fit over a grid of filter bandwidths).
  std::optional<MimoAdditiveModel> initial_model;

  static constexpr std::string_view type_name = "MimoIdentificationOptions";
  static constexpr auto fields() {
    using O = MimoIdentificationOptions;
    return std::tuple{
        field("refined_iv", &O::refined_iv, "MimoRefinedIvOptions of the shared-pole estimator."),
        field("initial_model", &O::initial_model,
              "Start of the iteration (orders and channels as the fit's); none: automatic.")
            .with_flag("initial"),
    };
  }
  /// Throws InvalidArgument naming the first bad field by its full path, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// Estimates the submodels `orders` (n_i >= 1, m_i, no integrators), their denominators shared
/// by every channel, from the open-loop record `data`: mimo_srivc(data, orders,
/// options.refined_iv, options.initial_model, progress), with its input checks (options,
/// orders, start, samples, one delay per input); throws InvalidArgument as it does, and how
/// the iteration ended is in the result. `progress`, if given, is called with (iteration,
/// options.refined_iv.max_iterations) as each iteration starts (not on the single-channel
/// SISO path).
MimoEstimationResult identify(const MimoData& data, const std::vector<SubmodelOrder>& orders,
                              const MimoIdentificationOptions& options = {},
                              const std::function<void(int, int)>& progress = {});

}  // namespace ctid
