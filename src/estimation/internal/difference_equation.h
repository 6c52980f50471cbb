// y = (b / a) x by the difference equation, from rest at each record's first sample (a(0) = 1):
// the one discrete filter of the ARMA fit (arma.cc) and the k-step predictor (prediction.cc).
#pragma once

#include <utility>
#include <vector>

#include <Eigen/Core>

namespace ctid::internal {

/// Records as [first, end) ranges of x.
using RecordRanges = std::vector<std::pair<Eigen::Index, Eigen::Index>>;

Eigen::VectorXd filter_from_rest(const Eigen::VectorXd& b, const Eigen::VectorXd& a,
                                 const Eigen::VectorXd& x, const RecordRanges& records);

/// The same on one record, the whole of x.
inline Eigen::VectorXd filter_from_rest(const Eigen::VectorXd& b, const Eigen::VectorXd& a,
                                        const Eigen::VectorXd& x) {
  return filter_from_rest(b, a, x, {{0, x.size()}});
}

}  // namespace ctid::internal
