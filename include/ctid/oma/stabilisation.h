// The stabilisation diagram and automatic picking of output-only modal analysis: each pole is
// classed against the poles of the previous order (|Δf|/f, |Δζ|/ζ, 1 - MAC; Peeters and De
// Roeck 1999), and the stable poles are clustered by single linkage on
// |Δf|/max f + (1 - MAC) (Magalhães, Cunha and Caetano, MSSP 2009); a cluster with poles from
// enough orders is a mode, represented by its member of median frequency.
#pragma once

#include <vector>

#include "ctid/oma/oma.h"
#include "ctid/oma/ssi_cov.h"

namespace ctid::oma_detail {

/// The poles of one order.
struct OrderPoles {
  int order = 0;
  std::vector<ModalPole> poles;
};

/// The class of every pole (same layout as `orders`); the first order's poles are all new.
std::vector<std::vector<PoleStability>> classify_poles(const std::vector<OrderPoles>& orders,
                                                       const OmaOptions& options);

/// A cluster of stable poles: (order index, pole index) pairs.
struct PoleCluster {
  std::vector<std::pair<int, int>> members;
  int supporting_orders = 0;
  double frequency_hz = 0.0;           ///< median frequency
  std::pair<int, int> representative;  ///< member of median frequency
};

/// Clusters of the stable poles, by frequency.
std::vector<PoleCluster> cluster_stable_poles(
    const std::vector<OrderPoles>& orders, const std::vector<std::vector<PoleStability>>& stability,
    double cluster_distance);

}  // namespace ctid::oma_detail
