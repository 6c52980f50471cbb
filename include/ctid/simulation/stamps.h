// Exact simulation at irregular time stamps (issue 37; docs/decisions/0034 and 0053): the
// state is propagated over each interval [t_k, t_k+1] as it is, by the augmented matrix
// exponential of discretization.h for the declared input hold (ZOH: u_k held on
// [t_k, t_k+1); FOH: linear from u_k to u_k+1). A duplicate stamp is an interval of length
// zero: the state does not move, and each of the equal stamps gets its own output
// C x + D u_k. Nothing is resampled. The SRIVC on irregular stamps (refined_iv) runs its
// filters through run_on_stamps as well.
#pragma once

#include <string_view>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/hold.h"
#include "ctid/core/transfer_function.h"

namespace ctid {

/// Throws InvalidArgument, the message starting with `context`, for the first stamp that is
/// not finite or that goes back before the one before it (naming both); equal stamps are
/// allowed.
void check_stamp_order(const Eigen::VectorXd& time, std::string_view context);

/// How many stamps equal the one before them (a logger's duplicates).
int duplicate_stamps(const Eigen::VectorXd& time);

/// Row k holds c z(t_k) + d x_k for dz/dt = a z + b x from z(t_0) = 0, x continued between
/// the stamps as `hold` says: a is s x s, b has s entries, c is r x s, d has r entries (one
/// input, r outputs). The discretisation of each distinct interval length is computed once
/// per call. The stamps must be non-decreasing (not checked here: check_stamp_order).
Eigen::MatrixXd run_on_stamps(const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                              const Eigen::MatrixXd& c, const Eigen::VectorXd& d,
                              const Eigen::VectorXd& time, const Eigen::VectorXd& x, Hold hold);

/// y(t_k) of G driven by the input u_k at the stamps t_k, held as `hold` says, from rest at
/// t_0 (a biproper model's y_k includes D u_k). Equal stamps are allowed (the state does not
/// move between them). An input delay tau is exact: the held input u(t - tau) changes at
/// t_j + tau, and those times are stepped to as well; it is zero before the record (with a
/// FOH it ramps from 0 one first step t_1 - t_0 before t_0, as simulate's u_{-1} = 0 does), so
/// on uniform stamps the result is the uniform simulation's, delay included (decision 0053).
/// Throws InvalidArgument for sizes that differ, a stamp that is not finite or goes
/// backwards, a non-finite input or an improper model.
Eigen::VectorXd simulate_on_stamps(const TransferFunction& g, const Eigen::VectorXd& time,
                                   const Eigen::VectorXd& u, Hold hold = Hold::zero_order_hold);
/// The sum of the submodels' responses.
Eigen::VectorXd simulate_on_stamps(const AdditiveModel& g, const Eigen::VectorXd& time,
                                   const Eigen::VectorXd& u, Hold hold = Hold::zero_order_hold);

}  // namespace ctid
