// Stability classes and clustering of the stable poles (stabilisation.h).
#include "ctid/oma/stabilisation.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>
#include <utility>
#include <vector>

namespace ctid::oma_detail {

namespace {

PoleStability classify(const ModalPole& pole, const std::vector<ModalPole>& previous,
                       const OmaOptions& options) {
  const ModalPole* nearest = nullptr;
  for (const ModalPole& q : previous) {
    if (nearest == nullptr || std::abs(q.frequency_hz - pole.frequency_hz) <
                                  std::abs(nearest->frequency_hz - pole.frequency_hz)) {
      nearest = &q;
    }
  }
  if (nearest == nullptr ||
      std::abs(nearest->frequency_hz - pole.frequency_hz) / pole.frequency_hz >
          options.frequency_tolerance) {
    return PoleStability::new_pole;
  }
  const bool damping = std::abs(nearest->damping_ratio - pole.damping_ratio) / pole.damping_ratio <=
                       options.damping_tolerance;
  const bool shape = 1.0 - modal_assurance(nearest->shape, pole.shape) <= options.mac_tolerance;
  if (damping && shape) return PoleStability::stable;
  if (damping) return PoleStability::frequency_damping;
  if (shape) return PoleStability::frequency_shape;
  return PoleStability::frequency;
}

int find_root(std::vector<int>& parent, int i) {
  while (parent[static_cast<std::size_t>(i)] != i) {
    parent[static_cast<std::size_t>(i)] =
        parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    i = parent[static_cast<std::size_t>(i)];
  }
  return i;
}

}  // namespace

std::vector<std::vector<PoleStability>> classify_poles(const std::vector<OrderPoles>& orders,
                                                       const OmaOptions& options) {
  std::vector<std::vector<PoleStability>> out(orders.size());
  for (std::size_t o = 0; o < orders.size(); ++o) {
    for (const ModalPole& pole : orders[o].poles) {
      out[o].push_back(o == 0 ? PoleStability::new_pole
                              : classify(pole, orders[o - 1].poles, options));
    }
  }
  return out;
}

std::vector<PoleCluster> cluster_stable_poles(
    const std::vector<OrderPoles>& orders, const std::vector<std::vector<PoleStability>>& stability,
    double cluster_distance) {
  std::vector<std::pair<int, int>> stable;
  for (std::size_t o = 0; o < orders.size(); ++o) {
    for (std::size_t k = 0; k < orders[o].poles.size(); ++k) {
      if (stability[o][k] == PoleStability::stable) {
        stable.emplace_back(static_cast<int>(o), static_cast<int>(k));
      }
    }
  }
  const auto pole = [&](std::size_t i) -> const ModalPole& {
    return orders[static_cast<std::size_t>(stable[i].first)]
        .poles[static_cast<std::size_t>(stable[i].second)];
  };
  // Single linkage: sorted by frequency, a pair further apart in frequency than the
  // threshold cannot link, so the inner loop stops there.
  std::vector<std::size_t> by_frequency(stable.size());
  std::iota(by_frequency.begin(), by_frequency.end(), std::size_t{0});
  std::sort(by_frequency.begin(), by_frequency.end(), [&](std::size_t a, std::size_t b) {
    return pole(a).frequency_hz < pole(b).frequency_hz;
  });
  std::vector<int> parent(stable.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t x = 0; x < by_frequency.size(); ++x) {
    const ModalPole& a = pole(by_frequency[x]);
    for (std::size_t z = x + 1; z < by_frequency.size(); ++z) {
      const ModalPole& b = pole(by_frequency[z]);
      const double df = (b.frequency_hz - a.frequency_hz) / b.frequency_hz;
      if (df > cluster_distance) break;
      if (df + 1.0 - modal_assurance(a.shape, b.shape) < cluster_distance) {
        parent[static_cast<std::size_t>(find_root(parent, static_cast<int>(by_frequency[x])))] =
            find_root(parent, static_cast<int>(by_frequency[z]));
      }
    }
  }
  std::vector<PoleCluster> clusters;
  std::vector<int> cluster_of(stable.size(), -1);
  for (std::size_t i : by_frequency) {
    const int root = find_root(parent, static_cast<int>(i));
    int& c = cluster_of[static_cast<std::size_t>(root)];
    if (c < 0) {
      c = static_cast<int>(clusters.size());
      clusters.emplace_back();
    }
    clusters[static_cast<std::size_t>(c)].members.push_back(stable[i]);  // by frequency
  }
  for (PoleCluster& cluster : clusters) {
    std::set<int> distinct;
    for (const auto& m : cluster.members) distinct.insert(m.first);
    cluster.supporting_orders = static_cast<int>(distinct.size());
    cluster.representative = cluster.members[cluster.members.size() / 2];
    cluster.frequency_hz = orders[static_cast<std::size_t>(cluster.representative.first)]
                               .poles[static_cast<std::size_t>(cluster.representative.second)]
                               .frequency_hz;
  }
  std::sort(clusters.begin(), clusters.end(), [](const PoleCluster& a, const PoleCluster& b) {
    return a.frequency_hz < b.frequency_hz;
  });
  return clusters;
}

}  // namespace ctid::oma_detail
