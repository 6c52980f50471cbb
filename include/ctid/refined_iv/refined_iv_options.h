// Options shared by the refined instrumental-variable estimators (SRIVC, CLSRIVC and the
// additive open/closed-loop iteration (29) of González et al.). Plain struct with defaults;
// validate() names the field, its value and the rule.
#pragma once

#include <optional>

#include "ctid/core/additive_model.h"
#include "ctid/filtering/filter_bank.h"

namespace ctid {

/// How the asymptotic covariance treats the output noise (Theorem 3.2).
enum class NoiseAssumption {
  white,     ///< sigma^2 (sum psi psi')^-1
  coloured,  ///< sandwich R^-1 Q R^-1 with Q from an AR model of the residuals
};

struct RefinedIvOptions {
  /// Upper bound on the iterations of (29)/(30). >= 1.
  int max_iterations = 100;
  /// Stop when ||beta_{j+1} - beta_j|| / ||beta_j|| < tolerance. > 0 and < 1. The rounding
  /// floor is about 1e-15 (additive) to 5e-14 (8-pole unfactored).
  double tolerance = 1e-10;
  /// Starting model. Any model is accepted: if its submodel orders differ from the requested
  /// ones it is converted to one transfer function and regrouped. Without it the start is
  /// found from the data (initialization.h).
  std::optional<AdditiveModel> initial_model;
  /// Interpolation of the measured output between samples before filtering.
  Hold output_interpolation = Hold::first_order_hold;
  /// Known input delay in whole samples (>= 0); the model's input_delay is set to delay * h.
  int input_delay = 0;
  /// Keep one IterationRecord per iteration in the result.
  bool record_history = false;
  /// Step control: a step of (29) whose equations are singular or non-finite, whose model
  /// the controller does not stabilise, which is unstable, or after which the scaled IV
  /// residual ||sum zeta (y - G u)|| grows is halved toward the last accepted iterate (at
  /// most max_step_halvings times per step). Accepted steps are the plain iteration, so the
  /// fixed points are unchanged; halvings are counted in EstimationResult::step_halvings.
  bool step_control = true;
  /// Largest number of halvings of one step. >= 0.
  int max_step_halvings = 8;
  /// Noise assumption for the covariance.
  NoiseAssumption noise = NoiseAssumption::coloured;
  /// Largest AR order tried for the coloured-noise covariance (chosen by AIC). >= 1.
  int noise_model_max_order = 20;
  /// Compute covariance, standard errors and modal standard errors (skip to save time).
  bool compute_covariance = true;

  /// Throws InvalidArgument naming the first bad field.
  void validate() const;
};

}  // namespace ctid
