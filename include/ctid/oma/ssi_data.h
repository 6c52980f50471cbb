// The numerical core of data-driven SSI with reference channels (Peeters and De Roeck, MSSP
// 1999; van Overschee and De Moor 1996): the block Hankel matrix of past references over future
// outputs, built transposed (one row per Hankel column), the past columns of its LQ factor from
// Householder reflections of the past columns accumulated chunk by chunk (neither Q, L22 nor the
// projection is formed), and the SVD of the L21 block (future outputs x past references), whose
// left singular vectors span the observability matrix. From there on it is the SSI-cov path
// (observability_factor, ssi_poles).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "ctid/oma/ssi_cov.h"

namespace ctid::oma_detail {

/// Samples N that p block rows need: the transposed Hankel matrix has N - 2p + 1 rows and must
/// have at least its p (r + l) columns.
Eigen::Index ssi_data_samples_needed(int block_rows, Eigen::Index outputs, Eigen::Index references);

/// The first p r columns [L11; L21] (p (r + l) x p r) of the lower triangle L of the LQ
/// factorisation H = L Q of the mean-removed, 1/sqrt(j)-scaled block Hankel matrix H of past
/// references over future outputs: the blocks the projection needs (L22 is never formed). Column
/// signs are those of the Householder reflections (L L^T does not depend on them). The rows of
/// H^T are reduced in ssi_data_stripes stripes on up to `threads` threads (0: all cores), merged
/// in a fixed pairwise order: the same bits for any thread count.
Eigen::MatrixXd ssi_data_past_columns(const Eigen::MatrixXd& y, const std::vector<int>& references,
                                      int block_rows, int threads = 0);

/// Stripes of at least kSsiDataStripeWidths x width rows of H^T each (at most
/// kSsiDataMaxStripes, at least one) that ssi_data_past_columns reduces independently.
inline constexpr Eigen::Index kSsiDataStripeWidths = 8;
inline constexpr Eigen::Index kSsiDataMaxStripes = 8;
Eigen::Index ssi_data_stripes(Eigen::Index hankel_columns, Eigen::Index width);

/// O of order max_order and the QR of O_up from the SVD of L21 (pl x pr); `threads` as for
/// ssi_data_past_columns.
SsiFactor ssi_data_factor(const Eigen::MatrixXd& y, const std::vector<int>& references,
                          int block_rows, int max_order, int threads = 0);

}  // namespace ctid::oma_detail
