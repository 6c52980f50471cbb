// Step 1 regressors of the delayed-feedback identification (eqs. 6-12).
#include "ctid/delayed_feedback/regressors.h"

#include <cmath>

#include "ctid/core/controllable_form.h"
#include "ctid/core/error.h"
#include "ctid/simulation/discretization.h"

namespace ctid {
namespace {

double factorial(int k) {
  double f = 1.0;
  for (int i = 2; i <= k; ++i) f *= i;
  return f;
}

// Filter states of a whole sampled signal, X.row(k) = state at kδ, and the state at kδ - Δ.
class FilteredSignal {
 public:
  FilteredSignal(const Eigen::VectorXd& s, const FilterStep& full, const FilterStep& part,
                 double delta, int whole, bool fractional)
      : s_(s), part_(part), delta_(delta), whole_(whole), fractional_(fractional) {
    const Eigen::Index q = full.a.rows();
    states_ = Eigen::MatrixXd::Zero(s.size(), q);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(q);
    for (Eigen::Index k = 0; k + 1 < s.size(); ++k) {
      x = full.a * x + full.b * s(k) + full.g * ((s(k + 1) - s(k)) / delta);
      states_.row(k + 1) = x.transpose();
    }
  }
  Eigen::VectorXd at(Eigen::Index k) const { return states_.row(k).transpose(); }
  // State at kδ - Δ, Δ = whole δ + f: zero before t = 0 (the loop is at rest there).
  Eigen::VectorXd delayed(Eigen::Index k) const {
    const Eigen::Index q = states_.cols();
    if (!fractional_) {
      return k - whole_ >= 0 ? at(k - whole_) : Eigen::VectorXd::Zero(q);
    }
    const Eigen::Index j = k - whole_ - 1;
    if (j < 0) return Eigen::VectorXd::Zero(q);
    return part_.a * at(j) + part_.b * s_(j) + part_.g * ((s_(j + 1) - s_(j)) / delta_);
  }

 private:
  const Eigen::VectorXd& s_;
  FilterStep part_;
  double delta_;
  Eigen::Index whole_;
  bool fractional_;
  Eigen::MatrixXd states_;
};

}  // namespace

FilterStep integrator_chain_step(int q, double tau) {
  require(q >= 1, "integrator_chain_step: order q must be >= 1, got ", q);
  require(std::isfinite(tau) && tau >= 0.0, "integrator_chain_step: tau must be >= 0, got ", tau);
  FilterStep r;
  r.a = Eigen::MatrixXd::Zero(q, q);
  r.b.resize(q);
  r.g.resize(q);
  for (int i = 0; i < q; ++i) {
    for (int j = i; j < q; ++j) r.a(i, j) = std::pow(tau, j - i) / factorial(j - i);
    const int rr = q - 1 - i;  // r = q - i with 1-based i
    r.b(i) = std::pow(tau, rr + 1) / factorial(rr + 1);
    r.g(i) = std::pow(tau, rr + 2) / factorial(rr + 2);
  }
  return r;
}

FilterStep integral_filter_step(int q, double pole, double tau) {
  require(q >= 1, "integral_filter_step: order q must be >= 1, got ", q);
  require(std::isfinite(pole) && pole >= 0.0,
          "integral_filter_step: pole a must be finite and >= 0, got ", pole);
  require(std::isfinite(tau) && tau >= 0.0, "integral_filter_step: tau must be >= 0, got ", tau);
  if (pole == 0.0) return integrator_chain_step(q, tau);
  FilterStep r;
  if (tau == 0.0) {
    r.a = Eigen::MatrixXd::Identity(q, q);
    r.b = Eigen::VectorXd::Zero(q);
    r.g = Eigen::VectorXd::Zero(q);
    return r;
  }
  // 1/(s + a)^q in controllable form, (s + a)^q = sum_i C(q, i) a^{q-i} s^i, propagated over τ
  // by the simulator's exact FOH discretisation: y linear on the step is y(t) + ẏ θ, so
  // b = Γ0 + Γ1 (the weights of y_k and y_{k+1}) and g = τ Γ1.
  Eigen::VectorXd denominator(q + 1);
  for (int i = 0; i < q; ++i) {
    denominator(i) = factorial(q) / (factorial(i) * factorial(q - i)) * std::pow(pole, q - i);
  }
  denominator(q) = 1.0;
  const StateSpace filter = controllable_form(Eigen::VectorXd::Ones(1), denominator);
  const FohDiscretization step = discretize_foh(filter.a, filter.b, tau);
  r.a = step.phi;
  r.b = step.gamma0 + step.gamma1;
  r.g = tau * step.gamma1;
  return r;
}

void FeedbackRegressorOptions::check_relations(const std::string& path) const {
  require(filter == RegressorFilter::integrator_chain ||
              (std::isfinite(filter_pole) && filter_pole > 0.0),
          path, ".filter_pole is ", filter_pole,
          "; it must be > 0 and finite for the linear_integral_filter");
}

namespace {

// The first equation and the number of nuisance columns of the regression.
struct RegressionShape {
  int first = 0;
  int nuisance = 0;
  bool delayed_terms = false;
};

RegressionShape regression_shape(int q, double delay, double delta,
                                 const FeedbackRegressorOptions& options) {
  RegressionShape s;
  s.first = options.first_equation >= 0 ? options.first_equation
                                        : static_cast<int>(std::ceil(delay / delta - 1e-9));
  // For t >= Δ the delayed terms (t - Δ)^j e^{-a(t-Δ)} lie in the span of t^j e^{-at}: they
  // add information only when some equations precede Δ.
  s.delayed_terms = options.initial_condition_terms && s.first * delta < delay - 1e-9 * delta;
  s.nuisance = options.initial_condition_terms ? (s.delayed_terms ? 2 * q : q) : 0;
  return s;
}

}  // namespace

std::optional<std::string> feedback_regression_problem(const SampledData& data, int forward_order,
                                                       int feedback_order, double delay,
                                                       const FeedbackRegressorOptions& options) {
  if (forward_order < 1)
    return internal::concat("feedback identification: forward order n must be >= 1, got ",
                            forward_order);
  if (feedback_order < 1)
    return internal::concat("feedback identification: feedback order m must be >= 1, got ",
                            feedback_order);
  if (forward_order > kMaxFeedbackOrder || feedback_order > kMaxFeedbackOrder)
    return internal::concat("feedback identification: the orders of F (", forward_order,
                            ") and H (", feedback_order, ") must be at most ", kMaxFeedbackOrder,
                            " (the separation of F and H grows with the product of the orders)");
  if (!(std::isfinite(delay) && delay >= 0.0))
    return internal::concat("feedback identification: delay must be finite and >= 0, got ", delay);
  const double delta = data.sample_time();
  const double duration = (data.size() - 1) * delta;
  if (!(duration > delay))
    return internal::concat("feedback identification: the record (", duration,
                            " s) must be longer than the delay (", delay, " s)");
  const int q = forward_order + feedback_order;
  const RegressionShape shape = regression_shape(q, delay, delta, options);
  const int rows = data.size() - shape.first;
  const int theta_size = 3 * q - 1;
  if (rows < theta_size + shape.nuisance + 1)
    return internal::concat("feedback identification: too few samples: ", rows, " equations for ",
                            theta_size + shape.nuisance,
                            " unknowns (need more equations than unknowns; record more samples)");
  return std::nullopt;
}

FeedbackRegression build_feedback_regression(const SampledData& data, int forward_order,
                                             int feedback_order, double delay,
                                             const FeedbackRegressorOptions& options) {
  options.validate();
  if (const auto problem =
          feedback_regression_problem(data, forward_order, feedback_order, delay, options))
    throw InvalidArgument(*problem);
  const double delta = data.sample_time();
  const int samples = data.size();
  const int q = forward_order + feedback_order;
  const double pole =
      options.filter == RegressorFilter::integrator_chain ? 0.0 : options.filter_pole;

  int whole = static_cast<int>(std::floor(delay / delta + 1e-9));
  double frac = delay - whole * delta;
  if (frac < 1e-9 * delta) frac = 0.0;
  const bool fractional = frac > 0.0;
  const FilterStep full = integral_filter_step(q, pole, delta);
  const FilterStep part = integral_filter_step(q, pole, fractional ? delta - frac : 0.0);
  const FilteredSignal y(data.output(), full, part, delta, whole, fractional);
  const FilteredSignal u(data.input(), full, part, delta, whole, fractional);

  const RegressionShape shape = regression_shape(q, delay, delta, options);
  const int first = shape.first;
  const int rows = samples - first;
  const int theta_size = 3 * q - 1;
  const bool delayed_terms = shape.delayed_terms;
  const int nuisance = shape.nuisance;

  // Coefficients of (s + a)^q below s^q: the target is s^q/(s+a)^q y = y - sum c_i x_{i+1}.
  Eigen::VectorXd c = Eigen::VectorXd::Zero(q);
  for (int i = 0; i < q; ++i)
    c(i) = factorial(q) / (factorial(i) * factorial(q - i)) * std::pow(pole, q - i);

  FeedbackRegression r;
  r.regressor = Eigen::MatrixXd::Zero(rows, theta_size + nuisance);
  r.target.resize(rows);
  r.sample_index.resize(rows);
  for (int row = 0; row < rows; ++row) {
    const int k = first + row;
    const Eigen::VectorXd xy = y.at(k);
    const Eigen::VectorXd xd = y.delayed(k);
    const Eigen::VectorXd xu = u.at(k);
    for (int j = 0; j < q; ++j) r.regressor(row, j) = -xy(q - 1 - j);
    for (int j = 0; j + 1 < q; ++j) r.regressor(row, q + j) = -xd(q - 2 - j);
    for (int j = 0; j < q; ++j) r.regressor(row, 2 * q - 1 + j) = xu(q - 1 - j);
    r.target(row) = data.output()(k) - (pole == 0.0 ? 0.0 : c.dot(xy));
    r.sample_index(row) = k;
    if (nuisance > 0) {
      const double t = k * delta;
      const double td = t - delay;
      for (int j = 0; j < q; ++j) {
        r.regressor(row, theta_size + j) = std::pow(t, j) * std::exp(-pole * t) / factorial(j);
        if (!delayed_terms) continue;
        r.regressor(row, theta_size + q + j) =
            td >= -1e-9 * delta
                ? std::pow(std::max(td, 0.0), j) * std::exp(-pole * td) / factorial(j)
                : 0.0;
      }
    }
  }
  r.forward_order = forward_order;
  r.feedback_order = feedback_order;
  r.theta_size = theta_size;
  r.nuisance_size = nuisance;
  r.delay = delay;
  r.sample_time = delta;
  return r;
}

}  // namespace ctid
