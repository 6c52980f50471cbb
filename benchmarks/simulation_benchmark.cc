// Simulation throughput (samples per second) for the 8th-order open-loop system of González
// et al. Section 6.1, simulated unfactored (one 8-state recursion), additively (four 2-state
// recursions) and in closed loop with the Section 6.2 PID; plus the one-off ZOH discretisation.
#include <cstdint>

#include <benchmark/benchmark.h>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/simulation/closed_loop.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace {

constexpr double kH = 0.05;

ctid::Submodel mode(double sigma, double omega_d, double gain) {
  const double magnitude2 = sigma * sigma + omega_d * omega_d;
  return ctid::Submodel{ctid::Polynomial{1.0, 2.0 * sigma / magnitude2, 1.0 / magnitude2},
                        ctid::Polynomial{gain}};
}

ctid::AdditiveModel eighth_order_system() {
  return ctid::AdditiveModel(
      {mode(0.25, 1.39, 3.0), mode(0.15, 3.16, 0.4), mode(0.17, 5.77, 0.2), mode(0.5, 9.99, 0.05)});
}

ctid::DiscreteTransferFunction paper_pid() {
  const ctid::Polynomial q{0.0, 1.0};
  const ctid::Polynomial q1{-1.0, 1.0};
  return ctid::DiscreteTransferFunction(0.0115 * q * q1 + 0.00725 * q * q + 0.00454 * q1 * q1,
                                        q * q1, kH);
}

void BM_SimulateUnfactored8(benchmark::State& state) {
  const ctid::TransferFunction g = eighth_order_system().to_transfer_function();
  const Eigen::VectorXd u = ctid::white_noise(static_cast<int>(state.range(0)), 1.0, 1);
  for (auto _ : state) benchmark::DoNotOptimize(ctid::simulate(g, u, kH).data());
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_SimulateAdditive4Modes(benchmark::State& state) {
  const ctid::AdditiveModel g = eighth_order_system();
  const Eigen::VectorXd u = ctid::white_noise(static_cast<int>(state.range(0)), 1.0, 1);
  for (auto _ : state) benchmark::DoNotOptimize(ctid::simulate(g, u, kH).data());
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_SimulateClosedLoop8(benchmark::State& state) {
  const ctid::AdditiveModel g = eighth_order_system();
  const ctid::DiscreteTransferFunction c = paper_pid();
  const Eigen::VectorXd r = ctid::white_noise(static_cast<int>(state.range(0)), 1.0, 1);
  for (auto _ : state) {
    benchmark::DoNotOptimize(ctid::simulate_closed_loop(g, c, r).output.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_DiscretizeZoh8(benchmark::State& state) {
  const ctid::StateSpace model = eighth_order_system().to_transfer_function().to_state_space();
  for (auto _ : state) benchmark::DoNotOptimize(ctid::discretize_zoh(model, kH).a.data());
}

BENCHMARK(BM_SimulateUnfactored8)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SimulateAdditive4Modes)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SimulateClosedLoop8)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DiscretizeZoh8)->Unit(benchmark::kMicrosecond);

}  // namespace
