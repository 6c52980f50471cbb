// Recursive SRIVC (recursive_srivc.h). The filters are the batch SRIVC's (refined_iv.cc): one
// derivative bank of 1/Â on u, cascaded with a second 1/Â bank on x̂ = B̂/Â u, and one bank
// of 1/Â on y, each discretised exactly for its hold. When the estimate is refreshed the
// realisation changes; the filtered signals and their first n - 1 derivatives at the current
// sample (the physical meaning of the state) are carried over into the new realisation, so
// the prefilter is a time-varying filter whose state is continuous across refreshes.
#include "ctid/refined_iv/recursive_srivc.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>

#include <Eigen/Dense>

#include "ctid/core/error.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/simulation/discretization.h"
#include "refined_iv/internal/refined_iv_engine.h"

namespace ctid {

namespace internal {

// A filter dz/dt = A z + b x, y = C z + d x discretised for one hold, stepped one sample at a
// time: z(t_k) = Φ z(t_{k-1}) + γ_current x_{k-1} + γ_next x_k. Named, not anonymous: a member
// of the public RecursiveSrivc::State holds it.
struct RecursiveFilterStep {
  Eigen::MatrixXd phi;
  Eigen::VectorXd current;
  Eigen::VectorXd next;
  Eigen::MatrixXd c;
  Eigen::VectorXd d;

  RecursiveFilterStep() = default;
  RecursiveFilterStep(const FilterRealization& f, double h, Hold hold) : c(f.c), d(f.d) {
    DelayedHoldDiscretization w = discretize_delayed(f.a, f.b, h, 0.0, hold);
    phi = std::move(w.phi);
    current = w.current.col(0);
    next = w.next.col(0);
  }
};

}  // namespace internal

namespace {

bool stable_denominator(const Polynomial& a, int n) {
  if (a.degree() != n || !a.coefficients().allFinite()) return false;
  const Eigen::VectorXcd r = a.roots();
  if (!r.allFinite()) return false;
  return (r.real().array() < 0.0).all();
}

Polynomial denominator_of(const Eigen::VectorXd& theta, int n) {
  Eigen::VectorXd a(n + 1);
  a(0) = 1.0;
  a.tail(n) = theta.head(n);
  return Polynomial::trimmed(a);
}

Polynomial numerator_of(const Eigen::VectorXd& theta, int n, int m) {
  return Polynomial::trimmed(theta.segment(n, m + 1));
}

}  // namespace

struct RecursiveSrivc::State {
  SubmodelOrder order;
  int np = 0;
  double h = 0.0;
  Hold input_hold = Hold::zero_order_hold;
  RecursiveSrivcOptions options;
  Eigen::MatrixXd q;  // random-walk increment of P per sample (np x np diagonal)
  double noise_lambda = 1.0;

  Eigen::VectorXd theta;
  Eigen::MatrixXd p;

  // The filters of the current prefilter estimate.
  Eigen::VectorXd filter_theta;            // θ the filters were built from
  Eigen::MatrixXd to_physical;             // n x n: state of one 1/Â bank -> (p^k/Â) x, k < n
  double gain = 1.0;                       // x̂ stage carries x̂ / gain
  internal::RecursiveFilterStep u_filter;  // states [u bank (n); x̂ bank (n)]
  internal::RecursiveFilterStep y_filter;  // states n
  Eigen::VectorXd zu;
  Eigen::VectorXd zy;
  Eigen::VectorXd u_out;  // rows 0..n p^k u_f, row n+1 x̂, rows n+2..2n+2 p^k x̂_f
  Eigen::VectorXd y_out;  // rows 0..n p^k y_f
  double u_previous = 0.0;
  double y_previous = 0.0;
  // The last options.refilter_samples samples (ring buffer), re-filtered at a refresh.
  std::vector<double> u_history;
  std::vector<double> y_history;
  int refiltered = 0;  // samples re-filtered at the last refresh

  Eigen::VectorXd phi_row;
  Eigen::VectorXd zeta;
  Eigen::VectorXd pz;
  Eigen::RowVectorXd phi_p;

  double weighted_squares = 0.0;
  double weights = 0.0;
  double sigma2 = 0.0;

  int steps = 0;
  int rejected = 0;
  int skipped = 0;
  int first_unstable = -1;
  int last_unstable = -1;
  int unstable_count = 0;
  int first_nonfinite = -1;

  // Builds the filters of `t` (a stable Â). When `carry` the current filtered signals and
  // their derivatives are mapped into the new realisation's state.
  void build_filters(const Eigen::VectorXd& t, bool carry) {
    const int n = order.n;
    const int m = order.m;
    const Polynomial a = denominator_of(t, n);
    const FilterRealization bank = derivative_filters(a);
    const Eigen::VectorXd old_zu = zu;
    const Eigen::VectorXd old_zy = zy;
    Eigen::VectorXd w = Eigen::VectorXd::Zero(n + 1);
    w.head(m + 1) = t.segment(n, m + 1);
    // As the batch: the cascade carries B / ||B|| and ||B|| scales its outputs.
    const double new_gain = w.norm() > 0.0 ? w.norm() : 1.0;
    const FilterRealization chain = cascade(bank, w / new_gain, bank);
    FilterRealization u_real;
    u_real.a = chain.a;
    u_real.b = chain.b;
    u_real.c = Eigen::MatrixXd::Zero(2 * n + 3, 2 * n);
    u_real.d = Eigen::VectorXd::Zero(2 * n + 3);
    u_real.c.topLeftCorner(n + 1, n) = bank.c;
    u_real.d.head(n + 1) = bank.d;
    u_real.c.block(n + 1, 0, 1, n) = w.transpose() * bank.c;
    u_real.d(n + 1) = w.dot(bank.d);
    u_real.c.bottomRows(n + 1) = new_gain * chain.c;
    u_real.d.tail(n + 1) = new_gain * chain.d;
    const Eigen::MatrixXd new_to_physical = bank.c.topRows(n);
    u_filter = internal::RecursiveFilterStep(u_real, h, input_hold);
    y_filter = internal::RecursiveFilterStep(bank, h, options.output_interpolation);
    zu = Eigen::VectorXd::Zero(2 * n);
    zy = Eigen::VectorXd::Zero(n);
    refiltered = 0;
    if (carry && !u_history.empty()) {
      // Run the new filters from rest over the stored samples up to the current one, so
      // their state is (to within the decay of their slowest mode over the window) what they
      // would have reached on the whole record: the equations after the refresh stay exact
      // on noise-free data. From the first sample the state is exactly the batch one.
      // Window: the buffer, or fewer samples once the slowest mode of Â has decayed by
      // e^-37 (below double rounding) over it.
      const int cap = static_cast<int>(u_history.size());
      const double decay = -a.roots().real().maxCoeff();
      const double needed = std::ceil(37.0 / (decay * h));
      const int count =
          std::min(steps, needed < static_cast<double>(cap) ? static_cast<int>(needed) : cap);
      for (int j = steps - count; j < steps; ++j) {
        const double uj = u_history[static_cast<size_t>(j % cap)];
        const double yj = y_history[static_cast<size_t>(j % cap)];
        if (j > steps - count) {
          zu = u_filter.phi * zu + u_filter.current * u_previous + u_filter.next * uj;
          zy = y_filter.phi * zy + y_filter.current * y_previous + y_filter.next * yj;
        }
        u_previous = uj;
        y_previous = yj;
      }
      refiltered = count;
    } else if (carry) {
      // Carry the filtered signals and their first n - 1 derivatives (continuous across the
      // refresh); the change of Â leaves a transient in the equations.
      const auto lu = new_to_physical.partialPivLu();
      const Eigen::VectorXd du = to_physical * old_zu.head(n);
      const Eigen::VectorXd dx = gain * (to_physical * old_zu.tail(n));
      const Eigen::VectorXd dy = to_physical * old_zy;
      zu.head(n) = lu.solve(du);
      zu.tail(n) = lu.solve(dx) / new_gain;
      zy = lu.solve(dy);
    }
    to_physical = new_to_physical;
    gain = new_gain;
    filter_theta = t;
  }

  void step(double u, double y) {
    const int n = order.n;
    const int m = order.m;
    // Refresh the filters from the current estimate (never during the warm-up, never with
    // an unstable Â: then the previous filters stay).
    if (steps > 0 && steps >= options.warmup_samples && steps % options.refresh_interval == 0 &&
        theta != filter_theta) {
      if (stable_denominator(denominator_of(theta, n), n)) {
        build_filters(theta, true);
      } else {
        ++rejected;
      }
    }
    // Filters to t_k.
    if (steps > 0) {
      zu = u_filter.phi * zu + u_filter.current * u_previous + u_filter.next * u;
      zy = y_filter.phi * zy + y_filter.current * y_previous + y_filter.next * y;
    }
    u_out.noalias() = u_filter.c * zu;
    u_out += u_filter.d * u;
    y_out.noalias() = y_filter.c * zy;
    y_out += y_filter.d * y;
    u_previous = u;
    y_previous = y;
    if (!u_history.empty()) {
      const size_t at = static_cast<size_t>(steps) % u_history.size();
      u_history[at] = u;
      y_history[at] = y;
    }

    // Output-error variance with the current auxiliary model.
    const double e = y - u_out(n + 1);
    weighted_squares = noise_lambda * weighted_squares + e * e;
    weights = noise_lambda * weights + 1.0;
    sigma2 = weighted_squares / weights;

    // Regressor, instrument and the recursive IV step.
    for (int k = 1; k <= n; ++k) {
      phi_row(k - 1) = -y_out(k);
      zeta(k - 1) = -u_out(n + 2 + k);
    }
    for (int j = 0; j <= m; ++j) {
      phi_row(n + j) = u_out(j);
      zeta(n + j) = u_out(j);
    }
    const double lambda = options.forgetting_factor;
    pz.noalias() = p * zeta;
    phi_p.noalias() = phi_row.transpose() * p;
    const double denominator = lambda + phi_row.dot(pz);
    const double error = y_out(0) - phi_row.dot(theta);
    const Eigen::VectorXd gain_vector = pz / denominator;
    Eigen::VectorXd new_theta = theta + gain_vector * error;
    Eigen::MatrixXd new_p = (p - gain_vector * phi_p) / lambda;
    if (q.size() > 0) new_p += q;
    if (std::isfinite(denominator) && new_theta.allFinite() && new_p.allFinite()) {
      theta = std::move(new_theta);
      p = std::move(new_p);
    } else {
      ++skipped;
      if (first_nonfinite < 0) first_nonfinite = steps;
    }
    if (!stable_denominator(denominator_of(theta, n), n)) {
      ++unstable_count;
      if (first_unstable < 0) first_unstable = steps;
      last_unstable = steps;
    }
    ++steps;
  }
};

RecursiveSrivc::RecursiveSrivc(const SubmodelOrder& order, double sample_time, Hold input_hold,
                               const TransferFunction& start, const RecursiveSrivcOptions& options)
    : state_(std::make_unique<State>()) {
  options.validate();
  order.validate();
  require(order.integrators == 0, "recursive_srivc: order.integrators is ", order.integrators,
          "; it must be 0 (integrators are not supported by the recursive estimator)");
  require(order.n >= 1, "recursive_srivc: order.n is ", order.n, "; it must be >= 1");
  require(order.m <= order.n, "recursive_srivc: order.m is ", order.m,
          "; it must be <= order.n = ", order.n, " (a proper model)");
  require(std::isfinite(sample_time) && sample_time > 0.0, "recursive_srivc: sample_time is ",
          sample_time, "; it must be finite and > 0");
  require(start.input_delay() == 0.0, "recursive_srivc: start has an input delay of ",
          start.input_delay(), " s; it must be 0 (delays are not supported)");
  State& s = *state_;
  s.order = order;
  s.np = order.n + order.m + 1;
  s.h = sample_time;
  s.input_hold = input_hold;
  s.options = options;
  s.theta = internal::unfactored_parameters(start, order);
  require(stable_denominator(denominator_of(s.theta, order.n), order.n),
          "recursive_srivc: start has poles ", start.denominator().to_string(),
          " = 0 with a root in the closed right half-plane; the start must be stable (it is "
          "the first prefilter)");
  const std::vector<double>& rw = options.random_walk;
  require(rw.empty() || rw.size() == 1 || static_cast<int>(rw.size()) == s.np,
          "RecursiveSrivcOptions.random_walk has ", rw.size(),
          " values; it must have 0, 1 or np = n + m + 1 = ", s.np);
  if (!rw.empty()) {
    s.q = Eigen::MatrixXd::Zero(s.np, s.np);
    for (int i = 0; i < s.np; ++i) s.q(i, i) = rw.size() == 1 ? rw[0] : rw[static_cast<size_t>(i)];
    if (s.q.isZero()) s.q.resize(0, 0);
  }
  s.noise_lambda =
      options.noise_forgetting > 0.0 ? options.noise_forgetting : options.forgetting_factor;
  const double floor = 1e-3 * s.theta.norm();
  Eigen::VectorXd scale = s.theta.cwiseAbs().cwiseMax(floor > 0.0 ? floor : 1.0);
  s.p = (options.initial_covariance * scale.cwiseAbs2()).asDiagonal();
  s.phi_row.resize(s.np);
  s.zeta.resize(s.np);
  s.pz.resize(s.np);
  s.phi_p.resize(s.np);
  s.u_history.assign(static_cast<size_t>(options.refilter_samples), 0.0);
  s.y_history.assign(static_cast<size_t>(options.refilter_samples), 0.0);
  s.build_filters(s.theta, false);
}

RecursiveSrivc::~RecursiveSrivc() = default;
RecursiveSrivc::RecursiveSrivc(const RecursiveSrivc& other)
    : state_(std::make_unique<State>(*other.state_)) {}
RecursiveSrivc& RecursiveSrivc::operator=(const RecursiveSrivc& other) {
  if (this != &other) state_ = std::make_unique<State>(*other.state_);
  return *this;
}
RecursiveSrivc::RecursiveSrivc(RecursiveSrivc&&) noexcept = default;
RecursiveSrivc& RecursiveSrivc::operator=(RecursiveSrivc&&) noexcept = default;

void RecursiveSrivc::update(double u, double y) {
  require(std::isfinite(u) && std::isfinite(y), "RecursiveSrivc::update: sample ", state_->steps,
          " has u = ", u, ", y = ", y, "; both must be finite");
  state_->step(u, y);
}

const Eigen::VectorXd& RecursiveSrivc::parameters() const { return state_->theta; }

TransferFunction RecursiveSrivc::model() const {
  const State& s = *state_;
  return TransferFunction(numerator_of(s.theta, s.order.n, s.order.m),
                          denominator_of(s.theta, s.order.n));
}

Eigen::MatrixXd RecursiveSrivc::covariance() const {
  const State& s = *state_;
  return 0.5 * s.sigma2 * (s.p + s.p.transpose());
}

const Eigen::MatrixXd& RecursiveSrivc::gain_matrix() const { return state_->p; }
double RecursiveSrivc::noise_variance() const { return state_->sigma2; }
int RecursiveSrivc::steps() const { return state_->steps; }
int RecursiveSrivc::rejected_refreshes() const { return state_->rejected; }
int RecursiveSrivc::skipped_updates() const { return state_->skipped; }
int RecursiveSrivc::unstable_samples() const { return state_->unstable_count; }
int RecursiveSrivc::first_unstable_sample() const { return state_->first_unstable; }
int RecursiveSrivc::last_unstable_sample() const { return state_->last_unstable; }
int RecursiveSrivc::first_nonfinite_sample() const { return state_->first_nonfinite; }

RecursiveSrivcResult recursive_srivc(const SampledData& data, const SubmodelOrder& order,
                                     const TransferFunction& start,
                                     const RecursiveSrivcOptions& options) {
  RecursiveSrivc estimator(order, data.sample_time(), data.input_hold(), start, options);
  const int np = order.n + order.m + 1;
  const int n = data.size();
  require(n >= 2 * np, "recursive_srivc: the record has ", n,
          " samples; it must have at least 2 (n + m + 1) = ", 2 * np);
  const bool full = options.covariance_history == CovarianceHistory::full;
  RecursiveSrivcResult r(start);
  r.times = data.time();
  r.parameters.resize(n, np);
  r.standard_errors.resize(n, np);
  r.covariance.resize(n, full ? np * np : np);
  r.noise_variance.resize(n);
  const Eigen::VectorXd& u = data.input();
  const Eigen::VectorXd& y = data.output();
  for (int k = 0; k < n; ++k) {
    estimator.update(u(k), y(k));
    const Eigen::MatrixXd c = estimator.covariance();
    r.parameters.row(k) = estimator.parameters().transpose();
    r.standard_errors.row(k) = c.diagonal().cwiseMax(0.0).cwiseSqrt().transpose();
    if (full) {
      r.covariance.row(k) = Eigen::Map<const Eigen::RowVectorXd>(c.data(), np * np);
    } else {
      r.covariance.row(k) = c.diagonal().transpose();
    }
    r.noise_variance(k) = estimator.noise_variance();
  }
  r.model = estimator.model();
  r.final_covariance = estimator.covariance();
  r.unstable_samples = estimator.unstable_samples();
  r.first_unstable_sample = estimator.first_unstable_sample();
  r.last_unstable_sample = estimator.last_unstable_sample();
  r.stable = r.last_unstable_sample != n - 1;
  r.skipped_updates = estimator.skipped_updates();
  r.first_nonfinite_sample = estimator.first_nonfinite_sample();
  r.finite = r.skipped_updates == 0;
  r.rejected_refreshes = estimator.rejected_refreshes();
  if (!r.finite) {
    r.message =
        internal::concat("recursive_srivc: ", r.skipped_updates,
                         " updates were skipped because theta or P would not have been finite, "
                         "the first at sample ",
                         r.first_nonfinite_sample);
  } else if (!r.stable) {
    r.message = internal::concat(
        "recursive_srivc: the final estimate has a pole in the closed right "
        "half-plane (unstable since sample ",
        r.first_unstable_sample, ")");
  } else if (r.unstable_samples > 0) {
    r.message = internal::concat(
        "recursive_srivc: stable and finite at the end; the estimate was "
        "unstable at ",
        r.unstable_samples, " samples, the last at sample ", r.last_unstable_sample);
  } else {
    r.message = "recursive_srivc: every estimate was stable and finite";
  }
  return r;
}

}  // namespace ctid
