// What every SSI estimate shares once it has its observability factor, defined in oma.cc and
// used by oma() and by the PreGER merge of several setups (multi_setup.cc, decision 0062).
#pragma once

#include <functional>
#include <vector>

#include <Eigen/Core>

#include "ctid/oma/oma.h"
#include "ctid/oma/ssi_cov.h"

namespace ctid::oma_detail {

/// The factor of one record's SSI estimate (SSI-cov or SSI-data by options.method) with p
/// block rows against the reference channels `refs`.
SsiFactor record_factor(const Eigen::MatrixXd& y, const std::vector<int>& refs, int p,
                        const OmaOptions& options, int threads = 0);

/// Samples a record needs for p block rows of the method, with l channels and r references.
Eigen::Index ssi_samples_needed(const OmaOptions& options, int p, Eigen::Index l, Eigen::Index r);

/// The continuous-time poles of one model order: ssi_poles of one record's factor, or of
/// PreGER's global matrix at that order.
using PolesOfOrder = std::function<std::vector<ModalPole>(int order)>;

/// The stabilisation diagram of orders 2, 4, .., max_order (pLSCF: polynomial orders 1, 2, ..,
/// max_order), its clustering, the picked modes (standard errors NaN) and the verdict, into
/// `result` (stabilisation, modes, verdict, iterations).
void ssi_modes(const PolesOfOrder& poles, const OmaOptions& options, OmaResult& result);

/// Segment-based standard errors: `block_poles(b)` gives the poles of block b of `blocks`
/// (called on threads); each mode's estimate in a block is the pole of its order nearest in
/// |df|/f + 1 - MAC, and its variance the blocks' variance over the number of blocks.
void segment_standard_errors(int blocks, const std::function<PolesOfOrder(int)>& block_poles,
                             const OmaOptions& options, std::vector<OmaMode>& modes);

}  // namespace ctid::oma_detail
