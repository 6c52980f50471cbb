// Simulation at irregular time stamps (stamps.h): one exact discretisation per distinct
// interval length, the state stepped interval by interval.
#include "ctid/simulation/stamps.h"

#include <cmath>
#include <cstddef>
#include <map>
#include <string>
#include <utility>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/state_space.h"
#include "ctid/simulation/discretization.h"

namespace ctid {
namespace {

// One interval's exact recursion z+ = phi z + g0 x_k + g1 x_k+1 (g1 = 0 for the ZOH).
struct IntervalStep {
  Eigen::MatrixXd phi;
  Eigen::VectorXd g0;
  Eigen::VectorXd g1;
};

void check_simulation_inputs(const TransferFunction& g, const Eigen::VectorXd& time,
                             const Eigen::VectorXd& u) {
  require(time.size() == u.size(), "simulate_on_stamps: ", time.size(), " time stamps and ",
          u.size(), " input samples; the sizes must agree");
  check_stamp_order(time, "simulate_on_stamps");
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    require(std::isfinite(u(k)), "simulate_on_stamps: input u[", k, "] is not finite (", u(k), ")");
  }
  require(g.is_proper(), "simulate_on_stamps: cannot simulate an improper transfer function ",
          "(numerator degree ", g.numerator().degree(), " > denominator degree ",
          g.denominator().degree(), ")");
  require(g.input_delay() == 0.0, "simulate_on_stamps: the model has an input delay of ",
          g.input_delay(),
          " s; a delay is not supported on irregular time stamps (docs/decisions/0053)");
}

// The undelayed model's response at the stamps (inputs checked by the caller).
Eigen::VectorXd stamps_response(const TransferFunction& g, const Eigen::VectorXd& time,
                                const Eigen::VectorXd& u, Hold hold) {
  const StateSpace ss = g.to_state_space();
  const Eigen::MatrixXd c = ss.c;
  const Eigen::VectorXd d = Eigen::VectorXd::Constant(1, ss.d);
  return run_on_stamps(ss.a, ss.b, c, d, time, u, hold).col(0);
}

}  // namespace

void check_stamp_order(const Eigen::VectorXd& time, std::string_view context) {
  for (Eigen::Index k = 0; k < time.size(); ++k) {
    require(std::isfinite(time(k)), context, ": time stamp ", k, " is ", time(k),
            "; every stamp must be finite");
    // (require evaluates its message parts: time(k - 1) only from k = 1)
    if (k > 0) {
      require(time(k) >= time(k - 1), context, ": time stamp ", k, " (", format_number(time(k)),
              " s) goes back before stamp ", k - 1, " (", format_number(time(k - 1)),
              " s); stamps must not decrease (equal stamps are allowed)");
    }
  }
}

Eigen::MatrixXd run_on_stamps(const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                              const Eigen::MatrixXd& c, const Eigen::VectorXd& d,
                              const Eigen::VectorXd& time, const Eigen::VectorXd& x, Hold hold) {
  const Eigen::Index n = time.size();
  const auto s = static_cast<int>(a.rows());
  // At most kCached lengths are kept (stamps with fine jitter rarely repeat a length).
  constexpr std::size_t kCached = 4096;
  std::map<double, IntervalStep> steps;
  IntervalStep uncached;
  auto step_for = [&](double h) -> const IntervalStep& {
    auto found = steps.find(h);
    if (found != steps.end()) return found->second;
    IntervalStep step;
    if (hold == Hold::zero_order_hold) {
      ZohDiscretization z = discretize_zoh(a, b, h);
      step = {std::move(z.phi), z.gamma.col(0), Eigen::VectorXd::Zero(s)};
    } else {
      FohDiscretization f = discretize_foh(a, b, h);
      step = {std::move(f.phi), f.gamma0.col(0), f.gamma1.col(0)};
    }
    if (steps.size() >= kCached) {
      uncached = std::move(step);
      return uncached;
    }
    return steps.emplace(h, std::move(step)).first->second;
  };
  Eigen::MatrixXd out(n, c.rows());
  Eigen::VectorXd z = Eigen::VectorXd::Zero(s);
  Eigen::VectorXd next(s);
  for (Eigen::Index k = 0; k < n; ++k) {
    if (s > 0 && k > 0 && time(k) > time(k - 1)) {
      const IntervalStep& step = step_for(time(k) - time(k - 1));
      next.noalias() = step.phi * z;
      next += step.g0 * x(k - 1) + step.g1 * x(k);
      z.swap(next);
    }
    out.row(k) = (c * z + d * x(k)).transpose();
  }
  return out;
}

Eigen::VectorXd simulate_on_stamps(const TransferFunction& g, const Eigen::VectorXd& time,
                                   const Eigen::VectorXd& u, Hold hold) {
  check_simulation_inputs(g, time, u);
  return stamps_response(g, time, u, hold);
}

Eigen::VectorXd simulate_on_stamps(const AdditiveModel& g, const Eigen::VectorXd& time,
                                   const Eigen::VectorXd& u, Hold hold) {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(u.size());
  for (const Submodel& submodel : g.submodels()) {
    const TransferFunction part = submodel.to_transfer_function().with_input_delay(g.input_delay());
    check_simulation_inputs(part, time, u);
    y += stamps_response(part.with_input_delay(0.0), time, u, hold);
  }
  if (g.size() == 0) check_stamp_order(time, "simulate_on_stamps");
  return y;
}

}  // namespace ctid
