// The refined IV estimator as one call: one record, or several records of one system, open
// or closed loop, unfactored or additive. srivc, clsrivc, additive_srivc and additive_clsrivc
// are this call with one record; the identification layer's identify() chooses the problem
// from the data and the structure (docs/architecture.md).
#pragma once

#include <tuple>
#include <utility>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/sampled_data.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

/// What the refined IV iteration estimates, from what.
struct RefinedIvProblem {
  /// One record, or several of one system, each with its own initial state (one parameter
  /// vector; the same sample time, input hold, signals and input delay).
  std::vector<const SampledData*> records;
  std::vector<SubmodelOrder> orders;
  /// nullptr: open loop (instrument (10)); otherwise closed loop (instrument (20)).
  const DiscreteTransferFunction* controller = nullptr;
  /// One unfactored model whose additive view comes from partial fractions.
  bool unfactored = false;
  const char* name = "estimator";
  /// The covariance from the whole N x p instrument held in memory, as before it was streamed
  /// (issue 14): the reference the streamed sums are tested against, not for estimation.
  bool stored_instrument_covariance = false;
  /// Coefficients of beta held at known values, as (index in beta, value): the start takes
  /// them, each step solves the instrument equations of the free coefficients only (in every
  /// column of (29)), and the covariance is that of the free ones given the held (decision
  /// 0057). Empty: every coefficient free.
  std::vector<std::pair<Eigen::Index, double>> held_coefficients;
  /// Coefficients of beta kept within bounds, as (index in beta, lower, upper), none of them
  /// held: the start is clamped into them, and a step whose solution leaves a bound holds that
  /// coefficient at it and solves again (an active set rebuilt at every step); the covariance
  /// holds those at a bound too, and the verdict lists them (decision 0058). Empty: no bound.
  std::vector<std::tuple<Eigen::Index, double, double>> bounded_coefficients;
};

/// The refined IV estimate of the problem: the iteration of González et al. (eq. 29 and 30)
/// from RefinedIvOptions::initial_model or the automatic start, with covariance and verdict.
/// Throws InvalidArgument for bad records, orders or options, as srivc does.
EstimationResult estimate_refined_iv(const RefinedIvProblem& problem,
                                     const RefinedIvOptions& options = {});

/// The checks of estimation/verdict.h on a finished estimate (decision 0007), as the refined
/// IV estimators judge theirs; a caller that changes an estimate's covariance judges it again
/// with this. `loop_unstable`: closed loop, and the known controller does not stabilise it.
Verdict refined_iv_verdict(const EstimationResult& r, bool closed_loop, bool loop_unstable);

}  // namespace ctid
