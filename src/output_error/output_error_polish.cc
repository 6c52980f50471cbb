// The output-error (prediction-error) polish: Levenberg–Marquardt by Ceres over beta, tau and
// the noise model's coefficients, the initial state by variable projection (decision 0057).
#include "ctid/output_error/output_error_polish.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Dense>

#include "ctid/core/error.h"
#include "ctid/core/polynomial.h"
#include "ctid/estimation/validation.h"

namespace ctid {
namespace {

// The parameter vector theta = [beta, tau (if estimated), d_1..d_p, c_1..c_q], its free
// part x (theta = map x + offset: held values in offset, the DC gain's b0 a combination) and
// the residual it gives.
struct PolishProblem {
  const SampledData& data;
  std::vector<SubmodelOrder> orders{};
  Eigen::Index beta_count = 0;
  double fixed_delay = 0.0;  // the start's delay when it is held
  bool estimate_delay = false;
  double max_delay = 0.0;
  int ar = 0;
  int ma = 0;
  bool noise = false;
  bool initial_state = false;
  bool keep_stable = false;
  Eigen::MatrixXd map{};
  Eigen::VectorXd offset{};
  Eigen::VectorXd lower{};  // of x
  Eigen::VectorXd upper{};
  std::vector<Eigen::Index> free_index{};  // the entry of theta each entry of x is
  std::vector<bool> user_bounded{};        // x(k) has a bound the constraints gave
  mutable int refused = 0;  // trial points refused as unstable (or a non-invertible C)

  Eigen::Index size() const { return beta_count + (estimate_delay ? 1 : 0) + ar + ma; }
  Eigen::Index free() const { return map.cols(); }
  Eigen::Index noise_offset() const { return beta_count + (estimate_delay ? 1 : 0); }

  // theta from x, each free parameter clamped into its bounds: the central differences of the
  // Jacobian may step just outside them.
  Eigen::VectorXd theta(const double* x) const {
    Eigen::VectorXd z(free());
    for (Eigen::Index k = 0; k < free(); ++k) z(k) = std::clamp(x[k], lower(k), upper(k));
    return map * z + offset;
  }
  AdditiveModel model(const Eigen::VectorXd& theta) const {
    const double tau = estimate_delay ? std::clamp(theta(beta_count), 0.0, max_delay) : fixed_delay;
    return AdditiveModel::from_parameters(orders, theta.head(beta_count), tau);
  }
  ArmaModel noise_model(const Eigen::VectorXd& theta) const {
    ArmaModel m;
    m.ar = Eigen::VectorXd::Ones(ar + 1);
    m.ma = Eigen::VectorXd::Ones(ma + 1);
    m.ar.tail(ar) = theta.segment(noise_offset(), ar);
    m.ma.tail(ma) = theta.segment(noise_offset() + ar, ma);
    return m;
  }

  // Stable denominators (keep_stable) and an invertible C: the filters the residual needs.
  bool admissible(const AdditiveModel& m, const ArmaModel& n) const {
    if (keep_stable) {
      for (int i = 0; i < m.size(); ++i) {
        if (m[i].a.degree() == 0) continue;
        const Eigen::VectorXcd r = m[i].a.roots();
        if (!r.allFinite() || (r.real().array() >= 0.0).any()) return false;
      }
    }
    if (ma > 0) {
      const Eigen::VectorXcd r = Polynomial(n.ma).roots();  // in q^-1: outside the unit circle
      if (!r.allFinite() || (r.cwiseAbs().array() <= 1.0).any()) return false;
    }
    return true;
  }

  // The modelled output (with the free response when estimated) and the criterion's residual;
  // false when theta is not admissible or a signal is not finite.
  bool evaluate(const Eigen::VectorXd& theta, Eigen::VectorXd& residual, Eigen::VectorXd* modelled,
                Eigen::VectorXd* x0) const {
    const AdditiveModel m = model(theta);
    const ArmaModel n = noise_model(theta);
    if (!admissible(m, n)) {
      ++refused;
      return false;
    }
    Eigen::VectorXd y = model_output(m, data.input(), data.sample_time(), data.input_hold());
    residual = data.output() - y;
    if (noise) residual = arma_innovations(n, residual);
    if (initial_state) {
      const Eigen::MatrixXd f = free_responses(m, data.size(), data.sample_time());
      Eigen::MatrixXd ff = f;
      if (noise) {
        for (Eigen::Index c = 0; c < f.cols(); ++c) ff.col(c) = arma_innovations(n, f.col(c));
      }
      const Eigen::VectorXd x = ff.colPivHouseholderQr().solve(residual);
      residual -= ff * x;
      y += f * x;
      if (x0 != nullptr) *x0 = x;
    }
    if (modelled != nullptr) *modelled = y;
    return residual.allFinite() && y.allFinite();
  }
};

struct PolishCost {
  const PolishProblem* problem;
  bool operator()(double const* const* theta, double* out) const {
    Eigen::VectorXd r;
    if (!problem->evaluate(problem->theta(theta[0]), r, nullptr, nullptr)) return false;
    Eigen::Map<Eigen::VectorXd>(out, r.size()) = r;
    return true;
  }
};

// `a` (anti-monic, a(0) = 1) with its right-half-plane roots mirrored into the left; A(0) = 1
// keeps the static gain.
Polynomial mirrored(const Polynomial& a, bool& changed) {
  if (a.degree() == 0) return a;
  Eigen::VectorXcd r = a.roots();
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    if (r(i).real() >= 0.0) {
      r(i) = {-std::max(std::abs(r(i).real()), 1e-9 * std::abs(r(i))), r(i).imag()};
      changed = true;
    }
  }
  return Polynomial::from_roots(r).anti_monic();
}

AdditiveModel stabilised_start(const AdditiveModel& start, bool& changed) {
  std::vector<Submodel> submodels = start.submodels();
  for (Submodel& s : submodels) s.a = mirrored(s.a, changed);
  return AdditiveModel(submodels, start.input_delay());
}

// The names settings may use: beta's, then tau with estimate_delay.
std::vector<std::string> settable_names(const AdditiveModel& model, bool delay) {
  std::vector<std::string> names = model.parameter_names();
  if (delay) names.emplace_back("tau");
  return names;
}

Eigen::Index index_in(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : it - names.begin();
}

// The b0 of each submodel (all of them have no integrator when a DC gain is known).
std::vector<Eigen::Index> b0_indices(const AdditiveModel& model) {
  std::vector<Eigen::Index> out;
  Eigen::Index offset = 0;
  for (int i = 0; i < model.size(); ++i) {
    out.push_back(offset + model[i].n());
    offset += model[i].parameter_count();
  }
  return out;
}

const CoefficientSetting* setting_of(const CoefficientConstraints& o, Eigen::Index j,
                                     const std::vector<std::string>& names) {
  for (const CoefficientSetting& s : o.coefficients) {
    if (s.name == names[static_cast<std::size_t>(j)]) return &s;
  }
  return nullptr;
}

// The b0 solved from the DC gain: the last one neither held nor bounded; -1 if none.
Eigen::Index dc_gain_carrier(const AdditiveModel& model, const CoefficientConstraints& o,
                             const std::vector<std::string>& names) {
  Eigen::Index carrier = -1;
  for (const Eigen::Index j : b0_indices(model)) {
    const CoefficientSetting* s = setting_of(o, j, names);
    if (s == nullptr || (!s->fixed && !s->lower && !s->upper)) carrier = j;
  }
  return carrier;
}

void validate_dc_gain(const AdditiveModel& model, const CoefficientConstraints& options,
                      const std::vector<std::string>& names) {
  for (int i = 0; i < model.size(); ++i) {
    require(model[i].integrators == 0, "a known DC gain contradicts the structure: submodel ",
            i + 1, " has an integrator (its static gain is infinite)");
  }
  if (dc_gain_carrier(model, options, names) >= 0) return;
  double held = 0.0;
  bool all_held = true;
  for (const Eigen::Index j : b0_indices(model)) {
    const CoefficientSetting* s = setting_of(options, j, names);
    all_held = all_held && s != nullptr && s->fixed;
    if (all_held) held += *s->fixed;
  }
  require(all_held, "the known DC gain needs a b0 that is neither held nor bounded to carry it");
  require(std::abs(held - *options.dc_gain) <= 1e-12 * std::max(1.0, std::abs(held)),
          "the known DC gain ", *options.dc_gain, " contradicts the held b0 values, whose sum is ",
          held);
}

}  // namespace

void validate_constraints(const AdditiveModel& model, const CoefficientConstraints& options,
                          bool delay_free) {
  options.validate();
  const std::vector<std::string> names = settable_names(model, delay_free);
  std::vector<std::string> seen;
  std::string listed;
  for (const std::string& n : names) listed += (listed.empty() ? "" : ", ") + n;
  for (const CoefficientSetting& s : options.coefficients) {
    if (s.name == "tau") {
      require(delay_free, "a setting of tau needs the delay estimated by the polish (it is held)");
    }
    require(index_in(names, s.name) >= 0, "parameter '", s.name, "' is not in the model (its ",
            "parameters: ", listed, ")");
    require(std::find(seen.begin(), seen.end(), s.name) == seen.end(), "parameter '", s.name,
            "' is set twice");
    seen.push_back(s.name);
    require(!s.lower || !s.upper || *s.lower <= *s.upper, "the bounds of ", s.name,
            " are empty: lower ", s.lower.value_or(0.0), " > upper ", s.upper.value_or(0.0));
    require(!s.fixed || ((!s.lower || *s.fixed >= *s.lower) && (!s.upper || *s.fixed <= *s.upper)),
            "the held value ", s.fixed.value_or(0.0), " of ", s.name, " is outside its bounds");
    require(s.name != "tau" || !s.fixed || *s.fixed >= 0.0, "the held value ",
            s.fixed.value_or(0.0), " of tau contradicts the structure: the delay is >= 0");
  }
  if (options.dc_gain) validate_dc_gain(model, options, names);
}

std::vector<std::pair<Eigen::Index, double>> held_coefficients(
    const AdditiveModel& model, const CoefficientConstraints& constraints) {
  validate_constraints(model, constraints, false);
  const std::vector<std::string> names = model.parameter_names();
  std::vector<std::pair<Eigen::Index, double>> held;
  for (Eigen::Index j = 0; j < static_cast<Eigen::Index>(names.size()); ++j) {
    const CoefficientSetting* s = setting_of(constraints, j, names);
    if (s != nullptr && s->fixed) held.emplace_back(j, *s->fixed);
  }
  if (constraints.dc_gain) {
    // The carrier is determined when it is the only b0 not held.
    const Eigen::Index carrier = dc_gain_carrier(model, constraints, names);
    double value = *constraints.dc_gain;
    int free_b0 = 0;
    for (const Eigen::Index j : b0_indices(model)) {
      const CoefficientSetting* s = setting_of(constraints, j, names);
      if (s != nullptr && s->fixed) {
        value -= *s->fixed;
      } else {
        ++free_b0;
      }
    }
    if (carrier >= 0 && free_b0 == 1) held.emplace_back(carrier, value);
  }
  std::sort(held.begin(), held.end());
  return held;
}

std::vector<std::tuple<Eigen::Index, double, double>> bounded_coefficients(
    const AdditiveModel& model, const CoefficientConstraints& constraints) {
  const std::vector<std::pair<Eigen::Index, double>> held = held_coefficients(model, constraints);
  const std::vector<std::string> names = model.parameter_names();
  std::vector<std::tuple<Eigen::Index, double, double>> bounds;
  for (Eigen::Index j = 0; j < static_cast<Eigen::Index>(names.size()); ++j) {
    const CoefficientSetting* s = setting_of(constraints, j, names);
    const bool is_held =
        std::any_of(held.begin(), held.end(), [&](const auto& h) { return h.first == j; });
    if (s == nullptr || is_held || !(s->lower || s->upper)) continue;
    constexpr double inf = std::numeric_limits<double>::infinity();
    bounds.emplace_back(j, s->lower.value_or(-inf), s->upper.value_or(inf));
  }
  return bounds;
}

namespace {

// theta = map x + offset from the settings: held parameters in offset, the DC gain's carrier
// b0 = K - (the other b0), free parameters with their bounds (tau always within [0, max]).
void set_constraints(PolishProblem& p, const AdditiveModel& model,
                     const CoefficientConstraints& o) {
  const std::vector<std::string> names = settable_names(model, p.estimate_delay);
  const Eigen::Index n = p.size();
  const Eigen::Index carrier = o.dc_gain ? dc_gain_carrier(model, o, names) : -1;
  std::vector<Eigen::Index> free;
  p.offset = Eigen::VectorXd::Zero(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const CoefficientSetting* s =
        j < static_cast<Eigen::Index>(names.size()) ? setting_of(o, j, names) : nullptr;
    if (s != nullptr && s->fixed) {
      p.offset(j) = *s->fixed;
    } else if (j != carrier) {
      free.push_back(j);
    }
  }
  const auto count = static_cast<Eigen::Index>(free.size());
  p.map = Eigen::MatrixXd::Zero(n, count);
  p.lower = Eigen::VectorXd::Constant(count, -std::numeric_limits<double>::infinity());
  p.upper = Eigen::VectorXd::Constant(count, std::numeric_limits<double>::infinity());
  p.user_bounded.assign(static_cast<std::size_t>(count), false);
  for (Eigen::Index k = 0; k < count; ++k) {
    const Eigen::Index j = free[static_cast<std::size_t>(k)];
    p.map(j, k) = 1.0;
    if (p.estimate_delay && j == p.beta_count) {
      p.lower(k) = 0.0;
      p.upper(k) = p.max_delay;
    }
    if (const CoefficientSetting* s =
            j < static_cast<Eigen::Index>(names.size()) ? setting_of(o, j, names) : nullptr) {
      if (s->lower) p.lower(k) = std::max(p.lower(k), *s->lower);
      if (s->upper) p.upper(k) = std::min(p.upper(k), *s->upper);
      p.user_bounded[static_cast<std::size_t>(k)] = s->lower || s->upper;
    }
  }
  if (carrier >= 0) {
    p.offset(carrier) = *o.dc_gain;
    for (const Eigen::Index j : b0_indices(model)) {
      if (j == carrier) continue;
      const auto it = std::find(free.begin(), free.end(), j);
      if (it == free.end()) {
        p.offset(carrier) -= p.offset(j);
      } else {
        p.map(carrier, it - free.begin()) = -1.0;
      }
    }
  }
  p.free_index = std::move(free);
}

PolishProblem polish_problem(const SampledData& data, const AdditiveModel& start,
                             const std::optional<ArmaModel>& noise,
                             const OutputErrorPolishOptions& options,
                             const CoefficientConstraints& constraints) {
  PolishProblem p{.data = data};
  p.orders = start.orders();
  p.beta_count = start.parameter_count();
  p.fixed_delay = start.input_delay();
  p.estimate_delay = options.estimate_delay;
  p.max_delay = 0.5 * (data.size() - 1) * data.sample_time();
  p.noise = noise.has_value();
  p.ar = noise ? noise->ar_order() : 0;
  p.ma = noise ? noise->ma_order() : 0;
  p.initial_state = options.estimate_initial_state;
  p.keep_stable = options.keep_stable;
  set_constraints(p, start, constraints);
  return p;
}

// The free part of the start: theta's free entries, each clamped into its bounds.
Eigen::VectorXd start_vector(const PolishProblem& p, const AdditiveModel& start,
                             const std::optional<ArmaModel>& noise) {
  Eigen::VectorXd theta(p.size());
  theta.head(p.beta_count) = start.parameters();
  if (p.estimate_delay) theta(p.beta_count) = std::min(start.input_delay(), p.max_delay);
  if (noise) {
    theta.segment(p.noise_offset(), p.ar) = noise->ar.tail(p.ar);
    theta.segment(p.noise_offset() + p.ar, p.ma) = noise->ma.tail(p.ma);
  }
  Eigen::VectorXd x(p.free());
  for (Eigen::Index k = 0; k < p.free(); ++k) {
    x(k) = std::clamp(theta(p.free_index[static_cast<std::size_t>(k)]), p.lower(k), p.upper(k));
  }
  return x;
}

struct Solved {
  Eigen::VectorXd x;
  Eigen::MatrixXd jacobian;  // of the residual in x (empty when it cannot be evaluated)
  ceres::Solver::Summary summary;
};

Solved solve_polish(const PolishProblem& p, Eigen::VectorXd x, int max_iterations) {
  Solved out;
  if (x.size() == 0) {  // every parameter is held: nothing to solve
    out.x = x;
    out.summary.termination_type = ceres::CONVERGENCE;
    out.summary.message = "every parameter is held";
    return out;
  }
  ceres::Problem problem;
  auto* cost =
      new ceres::DynamicNumericDiffCostFunction<PolishCost, ceres::CENTRAL>(new PolishCost{&p});
  cost->AddParameterBlock(static_cast<int>(x.size()));
  cost->SetNumResiduals(p.data.size());
  problem.AddResidualBlock(cost, nullptr, x.data());
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    if (std::isfinite(p.lower(k))) {
      problem.SetParameterLowerBound(x.data(), static_cast<int>(k), p.lower(k));
    }
    if (std::isfinite(p.upper(k))) {
      problem.SetParameterUpperBound(x.data(), static_cast<int>(k), p.upper(k));
    }
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.function_tolerance = 1e-15;
  so.parameter_tolerance = 1e-14;
  so.gradient_tolerance = 1e-20;
  so.logging_type = ceres::SILENT;
  so.num_threads = 1;
  ceres::Solve(so, &problem, &out.summary);
  out.x = x;
  ceres::CRSMatrix crs;
  if (problem.Evaluate(ceres::Problem::EvaluateOptions(), nullptr, nullptr, nullptr, &crs)) {
    out.jacobian = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
    for (int r = 0; r < crs.num_rows; ++r) {
      for (int k = crs.rows[static_cast<std::size_t>(r)];
           k < crs.rows[static_cast<std::size_t>(r) + 1]; ++k) {
        const auto kk = static_cast<std::size_t>(k);
        out.jacobian(r, crs.cols[kk]) = crs.values[kk];
      }
    }
  }
  return out;
}

Termination termination_of(const ceres::Solver::Summary& s) {
  switch (s.termination_type) {
    case ceres::CONVERGENCE:
      return Termination::converged;
    case ceres::NO_CONVERGENCE:
      return Termination::iteration_limit;
    default:
      return Termination::non_finite;
  }
}

// sigma^2 (J^T J)^{-1}; NaN when J is missing or singular.
Eigen::MatrixXd gauss_newton_covariance(const Eigen::MatrixXd& jacobian, double sigma2,
                                        Eigen::Index count) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (jacobian.rows() == 0 || !jacobian.allFinite()) {
    return Eigen::MatrixXd::Constant(count, count, nan);
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(jacobian);
  if (qr.rank() < count) return Eigen::MatrixXd::Constant(count, count, nan);
  const Eigen::MatrixXd r_inv = qr.matrixR()
                                    .topLeftCorner(count, count)
                                    .triangularView<Eigen::Upper>()
                                    .solve(Eigen::MatrixXd::Identity(count, count));
  const Eigen::MatrixXd p = qr.colsPermutation();
  const Eigen::MatrixXd inverse = p * r_inv * r_inv.transpose() * p.transpose();
  return sigma2 * inverse;
}

// The polished ARMA model: coefficients, innovation variance, its covariance block, spectrum.
ArmaModel polished_noise(const PolishProblem& p, const Eigen::VectorXd& theta,
                         const Eigen::MatrixXd& covariance, double ssr, double sigma2, int steps,
                         bool converged) {
  ArmaModel m = p.noise_model(theta);
  const Eigen::Index at = p.noise_offset();
  const auto n = static_cast<double>(p.data.size());
  m.innovation_variance = sigma2;
  m.covariance = covariance.block(at, at, p.ar + p.ma, p.ar + p.ma);
  m.standard_errors = m.covariance.diagonal().cwiseSqrt();
  m.criterion = n * std::log(ssr / n) + (p.ar + p.ma) * std::log(n);
  m.iterations = steps;
  m.converged = converged;
  arma_spectrum(m, p.data.sample_time());
  return m;
}

void judge_polish(OutputErrorPolishResult& r) {
  check_finite(r.verdict, r.parameters.allFinite() && std::isfinite(r.cost), "the polished model");
  if (!r.noise_model)
    check_fit(r.verdict, r.fit_percent, r.start_fit_percent);
  else
    check_fit(r.verdict, r.fit_percent, std::numeric_limits<double>::quiet_NaN());
  check_stable(r.verdict, r.transfer_function.poles());
  // Decision 0058: the constraints that acted, in the verdict.
  if (r.stability_constraint_active) {
    r.verdict.active_constraints.push_back(
        "stability: unstable start poles were mirrored or unstable trial points refused");
  }
  for (const std::string& name : r.active_bounds) {
    r.verdict.active_constraints.push_back(name + " is at a bound");
  }
}

// The names of the held parameters and of the free ones at a bound they were given.
void name_constraints(OutputErrorPolishResult& out, const PolishProblem& p,
                      const AdditiveModel& model, const Eigen::VectorXd& x) {
  const std::vector<std::string> names = settable_names(model, p.estimate_delay);
  for (Eigen::Index j = 0; j < static_cast<Eigen::Index>(names.size()); ++j) {
    if (std::find(p.free_index.begin(), p.free_index.end(), j) == p.free_index.end()) {
      out.held_parameters.push_back(names[static_cast<std::size_t>(j)]);
    }
  }
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    const auto kk = static_cast<std::size_t>(k);
    if (!p.user_bounded[kk]) continue;
    const double scale = 1e-9 * std::max(1.0, std::abs(x(k)));
    if (x(k) <= p.lower(k) + scale || x(k) >= p.upper(k) - scale) {
      out.active_bounds.push_back(names[static_cast<std::size_t>(p.free_index[kk])]);
    }
  }
}

// The result's statistics at the polished x: covariance map cov_x map^T over theta,
// standard errors, the noise model, the criterion and the fits.
void set_polish_statistics(OutputErrorPolishResult& out, const PolishProblem& p,
                           const Solved& solved, const Eigen::VectorXd& r0,
                           const Eigen::VectorXd& y0, const Eigen::VectorXd& r1,
                           const Eigen::VectorXd& y1, Eigen::Index states) {
  const auto n = static_cast<double>(p.data.size());
  const double ssr = r1.squaredNorm();
  const double sigma2 = ssr / (n - static_cast<double>(p.free() + states));
  const Eigen::MatrixXd cx = gauss_newton_covariance(solved.jacobian, sigma2, p.free());
  out.covariance = p.map * cx * p.map.transpose();
  out.standard_errors = out.covariance.diagonal().cwiseSqrt();
  if (p.estimate_delay) out.delay_standard_error = out.standard_errors(p.beta_count);
  if (p.noise) {
    out.noise_model = polished_noise(p, out.parameters, out.covariance, ssr, sigma2, out.iterations,
                                     out.converged());
  }
  out.start_cost = r0.squaredNorm() / n;
  out.cost = ssr / n;
  out.start_fit_percent = fit_percent(p.data.output(), y0);
  out.fit_percent = fit_percent(p.data.output(), y1);
}

// The polish's start: the start made stable when asked (and whether that mirrored a pole), its
// problem, the free start vector and its residual and output.
struct PolishStart {
  AdditiveModel first;
  bool mirrored = false;
  PolishProblem p;
  Eigen::VectorXd x0{};
  Eigen::VectorXd r0{};
  Eigen::VectorXd y0{};
};

// The start, formed once, or why the polish refuses it (a record with a reference, a non-finite
// start, fewer than 10 samples per free parameter, a start it cannot evaluate); bad options and
// constraints throw.
std::variant<std::string, PolishStart> start_polish(const SampledData& data,
                                                    const AdditiveModel& start,
                                                    const std::optional<ArmaModel>& noise,
                                                    const OutputErrorPolishOptions& options,
                                                    const CoefficientConstraints& constraints) {
  options.validate();
  validate_constraints(start, constraints, options.estimate_delay);
  if (data.has_reference()) {
    return "the output-error polish is for open-loop records; this record has a reference";
  }
  if (!start.parameters().allFinite() || !std::isfinite(start.input_delay())) {
    return "the output-error polish needs a finite start model";
  }
  bool mirrored = false;
  AdditiveModel first = options.keep_stable ? stabilised_start(start, mirrored) : start;
  PolishProblem p = polish_problem(data, first, noise, options, constraints);
  if (data.size() < 10 * p.free()) {
    return internal::concat("the output-error polish of ", p.free(), " free parameters needs ",
                            10 * p.free(), " samples (10 per parameter); the record has ",
                            data.size());
  }
  Eigen::VectorXd x0 = start_vector(p, first, noise);
  Eigen::VectorXd r0;
  Eigen::VectorXd y0;
  if (!p.evaluate(p.theta(x0.data()), r0, &y0, nullptr)) {
    return internal::concat(
        "the output-error polish cannot start: the start model",
        p.refused > 0 ? " with the held values is unstable" : "'s output is not finite");
  }
  return PolishStart{std::move(first), mirrored,      std::move(p),
                     std::move(x0),    std::move(r0), std::move(y0)};
}

}  // namespace

std::optional<std::string> polish_start_refusal(const SampledData& data, const AdditiveModel& start,
                                                const std::optional<ArmaModel>& noise,
                                                const OutputErrorPolishOptions& options,
                                                const CoefficientConstraints& constraints) {
  auto started = start_polish(data, start, noise, options, constraints);
  if (const std::string* refusal = std::get_if<std::string>(&started)) return *refusal;
  return std::nullopt;
}

OutputErrorPolishResult polish_output_error(const SampledData& data, const AdditiveModel& start,
                                            const std::optional<ArmaModel>& noise,
                                            const OutputErrorPolishOptions& options,
                                            const CoefficientConstraints& constraints) {
  auto started = start_polish(data, start, noise, options, constraints);
  if (const std::string* refusal = std::get_if<std::string>(&started)) {
    throw InvalidArgument(*refusal);
  }
  const PolishStart& begun = std::get<PolishStart>(started);
  const PolishProblem& p = begun.p;
  const AdditiveModel& first = begun.first;
  const Eigen::VectorXd& x0 = begun.x0;
  const Eigen::VectorXd& r0 = begun.r0;
  const Eigen::VectorXd& y0 = begun.y0;
  const bool mirrored_start = begun.mirrored;
  const int refused_at_start = p.refused;
  Solved solved = solve_polish(p, x0, options.max_iterations);
  Eigen::VectorXd r1;
  Eigen::VectorXd y1;
  Eigen::VectorXd states;
  const bool kept_start = !p.evaluate(p.theta(solved.x.data()), r1, &y1, &states) ||
                          r1.squaredNorm() > r0.squaredNorm();
  if (kept_start) {  // never worse than the start
    solved.x = x0;
    p.evaluate(p.theta(x0.data()), r1, &y1, &states);
  }

  const Eigen::VectorXd theta = p.theta(solved.x.data());
  OutputErrorPolishResult out(p.model(theta));
  out.criterion = noise ? "prediction error" : "output error";
  out.termination = termination_of(solved.summary);
  out.iterations = static_cast<int>(solved.summary.iterations.size());
  out.message =
      kept_start ? "the start was kept: no step lowered the criterion" : solved.summary.message;
  out.parameters = theta;
  out.initial_state = states;
  set_polish_statistics(out, p, solved, r0, y0, r1, y1, states.size());
  out.stability_constraint_active = mirrored_start || p.refused > refused_at_start;
  name_constraints(out, p, first, solved.x);
  judge_polish(out);
  return out;
}

}  // namespace ctid
