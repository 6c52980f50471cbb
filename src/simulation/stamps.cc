// Simulation at irregular time stamps (stamps.h): one exact discretisation per distinct
// interval length, the state stepped interval by interval.
#include "ctid/simulation/stamps.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

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

// The recursion of each interval length, computed once per length; at most kCached lengths
// are kept (stamps with fine jitter rarely repeat a length).
class IntervalSteps {
 public:
  IntervalSteps(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, Hold hold)
      : a_(a), b_(b), hold_(hold) {}

  const IntervalStep& operator()(double h) {
    auto found = steps_.find(h);
    if (found != steps_.end()) return found->second;
    IntervalStep step;
    if (hold_ == Hold::zero_order_hold) {
      ZohDiscretization z = discretize_zoh(a_, b_, h);
      step = {std::move(z.phi), z.gamma.col(0), Eigen::VectorXd::Zero(a_.rows())};
    } else {
      FohDiscretization f = discretize_foh(a_, b_, h);
      step = {std::move(f.phi), f.gamma0.col(0), f.gamma1.col(0)};
    }
    if (steps_.size() >= kCached) {
      uncached_ = std::move(step);
      return uncached_;
    }
    return steps_.emplace(h, std::move(step)).first->second;
  }

 private:
  static constexpr std::size_t kCached = 4096;
  const Eigen::MatrixXd& a_;
  const Eigen::VectorXd& b_;
  Hold hold_;
  std::map<double, IntervalStep> steps_;
  IntervalStep uncached_;
};

// The delayed input w(t) = u(t - tau) on the stamps' clock: knot i + 1 at t_i + tau carries
// u_i; knot 0, at t_0 - h_0 + tau (h_0 the first positive step) carries 0, so w is 0 before
// it and, with a FOH, ramps from 0 to u_0 as in the uniform simulation (u_{-1} = 0 one step
// back). A knot within 1e-12 of the clock's scale of a stamp is moved onto it, so a delay of
// whole steps on a uniform grid puts u_{k-d} at stamp k as simulate() does.
struct DelayedInput {
  std::vector<double> time;
  std::vector<double> value;
};

DelayedInput delayed_input(const Eigen::VectorXd& t, const Eigen::VectorXd& u, double tau) {
  const Eigen::Index n = t.size();
  double first_step = 0.0;
  for (Eigen::Index k = 1; k < n && first_step == 0.0; ++k) first_step = t(k) - t(k - 1);
  DelayedInput w;
  w.time.push_back(t(0) - first_step + tau);
  w.value.push_back(0.0);
  for (Eigen::Index k = 0; k < n; ++k) {
    w.time.push_back(t(k) + tau);
    w.value.push_back(u(k));
  }
  const double tolerance = 1e-12 * (std::abs(t(0)) + std::abs(t(n - 1)) + tau);
  Eigen::Index stamp = 0;
  for (double& knot : w.time) {
    while (stamp + 1 < n && t(stamp) < knot - tolerance) ++stamp;
    if (std::abs(t(stamp) - knot) <= tolerance) knot = t(stamp);
  }
  return w;
}

// w at time x on the piece after knot `last` (-1: before every knot; ZOH: the knot's value;
// FOH: the line to the next knot, held after the last one).
double delayed_value(const DelayedInput& w, std::ptrdiff_t last, double x, Hold hold) {
  if (last < 0) return 0.0;
  const auto i = static_cast<std::size_t>(last);
  if (hold == Hold::zero_order_hold || i + 1 == w.time.size()) return w.value[i];
  const double span = w.time[i + 1] - w.time[i];
  return w.value[i] + (w.value[i + 1] - w.value[i]) * ((x - w.time[i]) / span);
}

// The response at the stamps to the delayed input: the state is stepped over the stamps and
// the knots merged in time order (a knot before a stamp at the same time), so the input is
// constant (ZOH) or linear (FOH) on every piece.
Eigen::VectorXd delayed_response(const StateSpace& ss, const Eigen::VectorXd& t,
                                 const Eigen::VectorXd& u, Hold hold, double tau) {
  const DelayedInput w = delayed_input(t, u, tau);
  const auto knots = static_cast<std::ptrdiff_t>(w.time.size());
  IntervalSteps steps(ss.a, ss.b, hold);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(ss.order());
  double now = t(0);
  std::ptrdiff_t last = -1;
  const auto advance = [&](double to) {
    if (to > now && ss.order() > 0) {
      const IntervalStep& step = steps(to - now);
      z = step.phi * z + step.g0 * delayed_value(w, last, now, hold) +
          step.g1 * delayed_value(w, last, to, hold);
    }
    now = std::max(now, to);
  };
  Eigen::VectorXd y(t.size());
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    while (last + 1 < knots && w.time[static_cast<std::size_t>(last + 1)] <= t(k)) {
      advance(w.time[static_cast<std::size_t>(last + 1)]);
      ++last;
    }
    advance(t(k));
    y(k) = ss.c.dot(z) + ss.d * delayed_value(w, last, t(k), hold);
  }
  return y;
}

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
}

// The response at the stamps of g with the input delayed by tau (inputs checked by the
// caller; g's own delay is ignored).
Eigen::VectorXd stamps_response(const TransferFunction& g, const Eigen::VectorXd& time,
                                const Eigen::VectorXd& u, Hold hold, double tau) {
  const StateSpace ss = g.with_input_delay(0.0).to_state_space();
  if (tau > 0.0 && time.size() > 0) return delayed_response(ss, time, u, hold, tau);
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

int duplicate_stamps(const Eigen::VectorXd& time) {
  int duplicates = 0;
  for (Eigen::Index k = 1; k < time.size(); ++k) duplicates += time(k) == time(k - 1) ? 1 : 0;
  return duplicates;
}

Eigen::MatrixXd run_on_stamps(const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                              const Eigen::MatrixXd& c, const Eigen::VectorXd& d,
                              const Eigen::VectorXd& time, const Eigen::VectorXd& x, Hold hold) {
  const Eigen::Index n = time.size();
  const auto s = static_cast<int>(a.rows());
  IntervalSteps step_for(a, b, hold);
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
  return stamps_response(g, time, u, hold, g.input_delay());
}

Eigen::VectorXd simulate_on_stamps(const AdditiveModel& g, const Eigen::VectorXd& time,
                                   const Eigen::VectorXd& u, Hold hold) {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(u.size());
  for (const Submodel& submodel : g.submodels()) {
    const TransferFunction part = submodel.to_transfer_function();
    check_simulation_inputs(part, time, u);
    y += stamps_response(part, time, u, hold, g.input_delay());
  }
  if (g.size() == 0) check_stamp_order(time, "simulate_on_stamps");
  return y;
}

}  // namespace ctid
