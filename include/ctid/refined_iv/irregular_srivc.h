// SRIVC on a record sampled at irregular time stamps (issue 37; docs/decisions/0034): the
// refined IV prefilters s^i/A(s) and the instrument B/A u are discretised exactly on each
// interval [t_k, t_k+1] as it is (augmented matrix exponential for the declared input hold;
// the output linearly or held, as RefinedIvOptions::output_interpolation says), so the record
// is fitted on the stamps as logged: jitter, gaps and duplicate stamps included, nothing
// resampled. A duplicate stamp is a zero-length interval: the filter states do not move and
// both samples are observations. Open loop, one input and one output.
#pragma once

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/hold.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

/// An open-loop SISO record at time stamps t_k, non-decreasing (equal stamps allowed).
struct IrregularRecord {
  Eigen::VectorXd time;    ///< [s], non-decreasing
  Eigen::VectorXd input;   ///< u_k
  Eigen::VectorXd output;  ///< y_k
  /// How u is continued between stamps: zero-order hold (u_k on [t_k, t_k+1)) or
  /// first-order hold (linear between u_k and u_k+1).
  Hold input_hold = Hold::zero_order_hold;

  /// Throws InvalidArgument for sizes that differ, fewer than 2 samples, a stamp that is not
  /// finite or goes backwards (naming it), a non-finite u or y (naming it), or a record
  /// whose stamps all coincide.
  void validate() const;
  /// The median of the positive steps t_k+1 - t_k [s].
  double median_step() const;
};

/// Estimates B(p)/(p^l A(p)) (deg A = order.n, deg B = order.m, l = order.integrators) by
/// SRIVC on the stamps as they are. The start: options.initial_model, or else SRIVC with the
/// automatic start (options.start) on the record resampled onto its median step (equal
/// stamps reduced to the last sample, preprocessing.h resample); then the iteration (30) runs
/// on the stamps. Covariance: instrumental_variable_covariance of the instrument at the
/// estimate (options.noise; the coloured form treats the residuals as a sequence). Throws
/// InvalidArgument for a bad record (IrregularRecord::validate), impossible orders, fewer
/// than max(3 p, p + 20) samples for p parameters, an input not persistently exciting of
/// order p, or options it does not support (a known input delay, several records' delays, a
/// delay estimated, estimated initial conditions). How the iteration ended and whether the
/// model is usable are the result's termination and verdict.
EstimationResult srivc_irregular(const IrregularRecord& record, const SubmodelOrder& order,
                                 const RefinedIvOptions& options = {});

}  // namespace ctid
