// Open-loop ZOH simulation: one exact discretisation per (sub)model, then the per-sample
// state recursion of internal/state_recursion.h.
#include "ctid/simulation/simulate.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/simulation/discretization.h"
#include "simulation/internal/state_recursion.h"

namespace ctid {
namespace {

void check_sample_time(double h, const char* function) {
  require(std::isfinite(h) && h > 0.0, function,
          ": sample time h must be positive and finite, got ", h);
}

void check_input(const Eigen::VectorXd& u, const char* function) {
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    require(std::isfinite(u(k)), function, ": input u[", k, "] is not finite (", u(k), ")");
  }
}

/// The input seen by the undelayed model: u shifted right by `delay` samples.
Eigen::VectorXd delayed(const Eigen::VectorXd& u, int delay) {
  if (delay == 0) return u;
  Eigen::VectorXd shifted = Eigen::VectorXd::Zero(u.size());
  const Eigen::Index kept = std::max<Eigen::Index>(0, u.size() - delay);
  shifted.tail(kept) = u.head(kept);
  return shifted;
}

/// Appends a `delay`-sample shift register in front of a discrete model.
StateSpace with_input_shift(const StateSpace& plant, int delay) {
  if (delay == 0) return plant;
  const int n = plant.order();
  const int total = n + delay;
  // States [x; s_1 ... s_d] with s_j = u_{k-j}: the plant sees s_d.
  StateSpace result;
  result.a = Eigen::MatrixXd::Zero(total, total);
  result.a.topLeftCorner(n, n) = plant.a;
  result.a.block(0, total - 1, n, 1) = plant.b;
  for (int j = 1; j < delay; ++j) result.a(n + j, n + j - 1) = 1.0;
  result.b = Eigen::VectorXd::Zero(total);
  result.b(n) = 1.0;
  result.c = Eigen::RowVectorXd::Zero(total);
  result.c.head(n) = plant.c;
  result.c(total - 1) = plant.d;
  result.d = 0.0;
  return result;
}

// ZOH equivalent of e^{-f h s} G(s), the fraction f of the delay that is not whole samples.
StateSpace undelayed_zoh(const TransferFunction& g, double h, double fraction) {
  require(g.is_proper(), "cannot simulate an improper transfer function (numerator degree ",
          g.numerator().degree(), " > denominator degree ", g.denominator().degree(), ")");
  return discretize_zoh(g.with_input_delay(0.0).to_state_space(), h, fraction);
}

}  // namespace

DelaySplit split_delay(double tau, double h) {
  check_sample_time(h, "split_delay");
  require(std::isfinite(tau) && tau >= 0.0, "input delay tau must be non-negative and finite, got ",
          tau);
  const double ratio = tau / h;
  require(ratio <= 1e9, "input delay tau = ", tau, " s is too long: tau/h = ", ratio);
  const double rounded = std::round(ratio);
  if (std::abs(ratio - rounded) <= 1e-9 * std::max(1.0, rounded)) {
    return {static_cast<int>(rounded), 0.0};
  }
  const double whole = std::floor(ratio);
  return {static_cast<int>(whole), ratio - whole};
}

int delay_in_samples(double tau, double h) {
  check_sample_time(h, "delay_in_samples");
  const DelaySplit split = split_delay(tau, h);
  require(split.fraction == 0.0, "input delay tau = ", tau,
          " s is not a whole number of samples of h = ", h, " s (tau/h = ", tau / h, ")");
  return split.samples;
}

Eigen::VectorXd simulate_discrete(const StateSpace& discrete, const Eigen::VectorXd& u) {
  discrete.validate();
  check_input(u, "simulate_discrete");
  Eigen::VectorXd y(u.size());
  internal::StateRecursion recursion(discrete);
  recursion.run(u.data(), y.data(), u.size(), false);
  return y;
}

StateSpace zoh_equivalent(const TransferFunction& g, double h) {
  check_sample_time(h, "zoh_equivalent");
  const DelaySplit delay = split_delay(g.input_delay(), h);
  return with_input_shift(undelayed_zoh(g, h, delay.fraction), delay.samples);
}

StateSpace zoh_equivalent(const AdditiveModel& g, double h) {
  check_sample_time(h, "zoh_equivalent");
  const DelaySplit delay = split_delay(g.input_delay(), h);
  std::vector<StateSpace> parts;
  int total = 0;
  for (const Submodel& submodel : g.submodels()) {
    parts.push_back(undelayed_zoh(submodel.to_transfer_function(), h, delay.fraction));
    total += parts.back().order();
  }
  StateSpace result;
  result.a = Eigen::MatrixXd::Zero(total, total);
  result.b = Eigen::VectorXd::Zero(total);
  result.c = Eigen::RowVectorXd::Zero(total);
  int offset = 0;
  for (const StateSpace& part : parts) {
    const int n = part.order();
    result.a.block(offset, offset, n, n) = part.a;
    result.b.segment(offset, n) = part.b;
    result.c.segment(offset, n) = part.c;
    result.d += part.d;
    offset += n;
  }
  return with_input_shift(result, delay.samples);
}

Eigen::VectorXd simulate(const TransferFunction& g, const Eigen::VectorXd& u, double h) {
  check_sample_time(h, "simulate");
  check_input(u, "simulate");
  const DelaySplit delay = split_delay(g.input_delay(), h);
  const Eigen::VectorXd input = delayed(u, delay.samples);
  internal::StateRecursion recursion(undelayed_zoh(g, h, delay.fraction));
  Eigen::VectorXd y(u.size());
  recursion.run(input.data(), y.data(), input.size(), false);
  return y;
}

Eigen::MatrixXd simulate_submodels(const AdditiveModel& g, const Eigen::VectorXd& u, double h) {
  check_sample_time(h, "simulate_submodels");
  check_input(u, "simulate_submodels");
  const DelaySplit delay = split_delay(g.input_delay(), h);
  const Eigen::VectorXd input = delayed(u, delay.samples);
  Eigen::MatrixXd y(u.size(), g.size());
  for (int i = 0; i < g.size(); ++i) {
    internal::StateRecursion recursion(
        undelayed_zoh(g[i].to_transfer_function(), h, delay.fraction));
    recursion.run(input.data(), y.col(i).data(), input.size(), false);
  }
  return y;
}

Eigen::VectorXd simulate(const AdditiveModel& g, const Eigen::VectorXd& u, double h) {
  check_sample_time(h, "simulate");
  check_input(u, "simulate");
  const DelaySplit delay = split_delay(g.input_delay(), h);
  const Eigen::VectorXd input = delayed(u, delay.samples);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(u.size());
  for (const Submodel& submodel : g.submodels()) {
    internal::StateRecursion recursion(
        undelayed_zoh(submodel.to_transfer_function(), h, delay.fraction));
    recursion.run(input.data(), y.data(), input.size(), true);
  }
  return y;
}

}  // namespace ctid
