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
#include "support/paper_systems.h"

namespace {

constexpr double kH = 0.05;

ctid::AdditiveModel eighth_order_system() { return ctid::testing::open_loop_four_modes(); }

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
  const ctid::DiscreteTransferFunction c = ctid::testing::closed_loop_pid();
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
