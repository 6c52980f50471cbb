// Process models (procest's P1D, P2DU, ...): names, transfer functions, the exact sampled
// response, the checks of the settings, and the estimate (automatic start, Levenberg–Marquardt
// output-error refinement with Ceres, Gauss–Newton covariance, verdict). Decision 0040.
#include "ctid/process_model/process_model.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

#include "ctid/core/error.h"
#include "ctid/estimation/validation.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/simulate.h"

namespace ctid {
namespace {

constexpr const char* kLetters = "D (dead time), Z (zero), I (integrator), U (underdamped pair)";

bool is_time_constant(const std::string& name) { return name.size() > 1 && name[0] == 'T'; }
bool is_positive_parameter(const std::string& name) {
  return (is_time_constant(name) && name != "Tz" && name != "Td") || name == "Zeta";
}

int index_of(const std::vector<std::string>& names, std::string_view name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// The number of states of the model's realisation.
Polynomial process_denominator(const ProcessStructure& s, const Eigen::VectorXd& p) {
  const std::vector<std::string> names = s.parameter_names();
  Polynomial den = Polynomial::constant(1.0);
  if (s.underdamped) {
    const double tw = p(index_of(names, "Tw"));
    const double zeta = p(index_of(names, "Zeta"));
    den *= Polynomial{1.0, 2.0 * zeta * tw, tw * tw};
  }
  for (const char* t : {"Tp1", "Tp2", "Tp3"}) {
    const int i = index_of(names, t);
    if (i >= 0) den *= Polynomial{1.0, p(i)};
  }
  if (s.integrator) den *= Polynomial{0.0, 1.0};
  return den;
}

}  // namespace

// --- Structure -------------------------------------------------------------------------------

ProcessStructure ProcessStructure::parse(std::string_view name) {
  const std::string text(name);
  require(text.size() >= 2 && (text[0] == 'P' || text[0] == 'p'), "process model '", text,
          "': a name is P, the number of poles 0 to 3, then any of ", kLetters,
          ", e.g. P1D or P2DU");
  require(std::isdigit(static_cast<unsigned char>(text[1])) != 0, "process model '", text,
          "': P must be followed by the number of poles 0 to 3, e.g. P1D");
  ProcessStructure s;
  s.poles = text[1] - '0';
  require(s.poles <= 3, "process model '", text, "': ", s.poles,
          " poles; a process model has 0 to 3 (P0..P3)");
  for (std::size_t i = 2; i < text.size(); ++i) {
    const char c = static_cast<char>(std::toupper(static_cast<unsigned char>(text[i])));
    bool* flag = c == 'D'   ? &s.delay
                 : c == 'Z' ? &s.zero
                 : c == 'I' ? &s.integrator
                 : c == 'U' ? &s.underdamped
                            : nullptr;
    require(flag != nullptr, "process model '", text, "': '", std::string(1, text[i]),
            "' is not a process-model letter; after P and the poles come any of ", kLetters);
    require(!*flag, "process model '", text, "': the letter ", std::string(1, c),
            " is given twice");
    *flag = true;
  }
  require(!s.underdamped || s.poles >= 2, "process model '", text,
          "': U (an underdamped pair) needs at least 2 poles, e.g. P2U or P2DU");
  return s;
}

std::string ProcessStructure::name() const {
  std::string out = "P" + std::to_string(poles);
  if (delay) out += "D";
  if (zero) out += "Z";
  if (integrator) out += "I";
  if (underdamped) out += "U";
  return out;
}

std::vector<std::string> ProcessStructure::parameter_names() const {
  std::vector<std::string> names{"K"};
  if (underdamped) {
    names.insert(names.end(), {"Tw", "Zeta"});
    if (poles == 3) names.emplace_back("Tp3");
  } else {
    for (int i = 1; i <= poles; ++i) names.push_back("Tp" + std::to_string(i));
  }
  if (zero) names.emplace_back("Tz");
  if (delay) names.emplace_back("Td");
  return names;
}

TransferFunction process_transfer_function(const ProcessStructure& structure,
                                           const Eigen::VectorXd& parameters) {
  const std::vector<std::string> names = structure.parameter_names();
  require(parameters.size() == static_cast<Eigen::Index>(names.size()), "process model ",
          structure.name(), " has ", names.size(), " parameters (", joined(names), "), not ",
          parameters.size());
  const double k = parameters(0);
  const int z = index_of(names, "Tz");
  const Polynomial num = z >= 0 ? Polynomial{k, k * parameters(z)} : Polynomial{k};
  const int d = index_of(names, "Td");
  return TransferFunction(num, process_denominator(structure, parameters),
                          d >= 0 ? std::max(0.0, parameters(d)) : 0.0);
}

double ProcessModelResult::parameter(std::string_view name) const {
  const int i = index_of(parameter_names, name);
  require(i >= 0, "process model ", structure, " has no parameter '", std::string(name),
          "' (its parameters: ", joined(parameter_names), ")");
  return parameters(i);
}

double ProcessModelResult::standard_error(std::string_view name) const {
  const int i = index_of(parameter_names, name);
  require(i >= 0, "process model ", structure, " has no parameter '", std::string(name),
          "' (its parameters: ", joined(parameter_names), ")");
  return standard_errors.size() > i ? standard_errors(i) : std::numeric_limits<double>::quiet_NaN();
}

TransferFunction ProcessModelResult::transfer_function() const {
  return process_transfer_function(ProcessStructure::parse(structure), parameters);
}

// --- Simulation ------------------------------------------------------------------------------

Eigen::VectorXd process_model_output(const ProcessStructure& structure,
                                     const Eigen::VectorXd& parameters, const Eigen::VectorXd& u,
                                     double h, Hold hold) {
  const TransferFunction g = process_transfer_function(structure, parameters);
  const DelaySplit split = split_delay(g.input_delay(), h);
  const int d = split.samples;
  const auto n = static_cast<int>(u.size());
  // v(j): the input delayed by d whole samples (zero before the record, held after it).
  const auto v = [&](int j) {
    const int i = j - d;
    return i < 0 ? 0.0 : u(std::min(i, n - 1));
  };
  const DelayedSample at_sample = delayed_sample(split.fraction, hold);
  Eigen::VectorXd y(n);
  const TransferFunction rational(g.numerator(), g.denominator());
  const StateSpace ss = rational.to_state_space();
  if (ss.order() == 0) {
    for (int k = 0; k < n; ++k) {
      y(k) = ss.d * (at_sample.previous * v(k - 1) + at_sample.current * v(k));
    }
    return y;
  }
  const DelayedHoldDiscretization disc =
      discretize_delayed(ss.a, Eigen::MatrixXd(ss.b), h, split.fraction, hold);
  const int states = ss.order();
  const Eigen::VectorXd previous = disc.previous.col(0);
  const Eigen::VectorXd current = disc.current.col(0);
  const Eigen::VectorXd next = disc.next.col(0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(states);
  Eigen::VectorXd x_next(states);
  for (int k = 0; k < n; ++k) {
    const double vp = v(k - 1);
    const double vc = v(k);
    const double vn = k + 1 < n ? v(k + 1) : vc;
    y(k) = ss.c.dot(x) + ss.d * (at_sample.previous * vp + at_sample.current * vc);
    x_next.noalias() = disc.phi * x;
    x_next += vp * previous + vc * current + vn * next;
    x.swap(x_next);
  }
  return y;
}

// --- Settings --------------------------------------------------------------------------------

void validate_process_model(const ProcessStructure& structure, const ProcessModelOptions& options) {
  options.validate();
  const std::vector<std::string> names = structure.parameter_names();
  std::vector<std::string> seen;
  for (const ProcessParameterSetting& p : options.parameters) {
    require(index_of(names, p.name) >= 0, "parameter '", p.name, "' is not in process model ",
            structure.name(), " (its parameters: ", joined(names), ")");
    require(index_of(seen, p.name) < 0, "parameter '", p.name, "' is set twice");
    seen.push_back(p.name);
    require(!p.fixed || p.value.has_value(), "parameter '", p.name,
            "' is held fixed but has no value");
    if (is_positive_parameter(p.name)) {
      require(!p.upper || *p.upper > 0.0, "the upper bound ", p.upper.value_or(0.0), " of ", p.name,
              " contradicts the structure: ", p.name, " is positive");
      require(!p.value || *p.value > 0.0, "the value ", p.value.value_or(0.0), " of ", p.name,
              " contradicts the structure: ", p.name, " is positive");
    }
    if (p.name == "Td") {
      require(!p.upper || *p.upper >= 0.0, "the upper bound ", p.upper.value_or(0.0),
              " of Td contradicts the structure: the dead time is >= 0");
      require(!p.value || *p.value >= 0.0, "the value ", p.value.value_or(0.0),
              " of Td contradicts the structure: the dead time is >= 0");
    }
    require(!p.lower || !p.upper || *p.lower <= *p.upper, "the bounds of ", p.name,
            " are empty: lower ", p.lower.value_or(0.0), " > upper ", p.upper.value_or(0.0));
    if (p.value) {
      require(!p.lower || *p.value >= *p.lower, "the value ", *p.value, " of ", p.name,
              " is below its lower bound ", p.lower.value_or(0.0));
      require(!p.upper || *p.value <= *p.upper, "the value ", *p.value, " of ", p.name,
              " is above its upper bound ", p.upper.value_or(0.0));
    }
  }
}

// --- Estimation ------------------------------------------------------------------------------

namespace {

struct Problem {
  const ProcessStructure& structure;
  const SampledData& data;
  Eigen::VectorXd full;          // all parameters; free ones overwritten from theta
  std::vector<int> free_index;   // positions of the free parameters in `full`
  Eigen::VectorXd lower, upper;  // of all parameters

  // The free parameters from theta, each clamped into its bounds: the central differences of
  // the Jacobian may step just outside them (a time constant below 0 is an unstable pole).
  Eigen::VectorXd with(const double* theta) const {
    Eigen::VectorXd p = full;
    for (std::size_t i = 0; i < free_index.size(); ++i) {
      const int j = free_index[i];
      p(j) = std::min(std::max(theta[i], lower(j)), upper(j));
    }
    return p;
  }
  // The model's output at p, or an empty vector where p forms no finite model (a solver's
  // trial point or a difference step whose coefficients overflow, or whose state matrix has no
  // eigenvalues: the core types refuse those by throwing). Callers take an empty output for an
  // infeasible point.
  Eigen::VectorXd output(const Eigen::VectorXd& p) const {
    try {
      return process_model_output(structure, p, data.input(), data.sample_time(),
                                  data.input_hold());
    } catch (const InvalidArgument&) {
      return {};
    } catch (const ComputationError&) {
      return {};
    }
  }
};

struct OutputErrorCost {
  const Problem* problem;
  bool operator()(double const* const* theta, double* residuals) const {
    const Eigen::VectorXd p = problem->with(theta[0]);
    if (!p.allFinite()) return false;
    const Eigen::VectorXd y = problem->output(p);
    const Eigen::VectorXd& measured = problem->data.output();
    if (y.size() != measured.size()) return false;
    for (Eigen::Index k = 0; k < measured.size(); ++k) residuals[k] = measured(k) - y(k);
    return y.allFinite();
  }
};

double sum_of_squares(const Problem& problem, const Eigen::VectorXd& p) {
  const Eigen::VectorXd y = problem.output(p);
  if (y.size() != problem.data.output().size()) return std::numeric_limits<double>::infinity();
  const Eigen::VectorXd e = problem.data.output() - y;
  return e.allFinite() ? e.squaredNorm() : std::numeric_limits<double>::infinity();
}

struct Refined {
  Eigen::VectorXd parameters;
  double sum_of_squares = std::numeric_limits<double>::infinity();
  Termination termination = Termination::not_run;
  std::string message;
  int iterations = 0;
};

Refined refine(const Problem& problem, const Eigen::VectorXd& start, int max_iterations) {
  const auto free = static_cast<int>(problem.free_index.size());
  Refined out;
  out.parameters = start;
  if (free == 0) {
    out.sum_of_squares = sum_of_squares(problem, start);
    out.termination = Termination::converged;
    out.message = "every parameter is held";
    return out;
  }
  std::vector<double> theta(static_cast<std::size_t>(free));
  for (int i = 0; i < free; ++i) theta[static_cast<std::size_t>(i)] = start(problem.free_index[i]);
  ceres::Problem::Options problem_options;
  ceres::Problem ceres_problem(problem_options);
  auto* cost = new ceres::DynamicNumericDiffCostFunction<OutputErrorCost, ceres::CENTRAL>(
      new OutputErrorCost{&problem});
  cost->AddParameterBlock(free);
  cost->SetNumResiduals(problem.data.size());
  ceres_problem.AddResidualBlock(cost, nullptr, theta.data());
  for (int i = 0; i < free; ++i) {
    const int j = problem.free_index[i];
    if (std::isfinite(problem.lower(j))) {
      ceres_problem.SetParameterLowerBound(theta.data(), i, problem.lower(j));
    }
    if (std::isfinite(problem.upper(j))) {
      ceres_problem.SetParameterUpperBound(theta.data(), i, problem.upper(j));
    }
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.function_tolerance = 1e-14;
  so.parameter_tolerance = 1e-13;
  so.gradient_tolerance = 1e-16;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &ceres_problem, &summary);
  out.parameters = problem.with(theta.data());
  out.sum_of_squares = sum_of_squares(problem, out.parameters);
  out.iterations = static_cast<int>(summary.iterations.size());
  out.termination = summary.termination_type == ceres::CONVERGENCE ? Termination::converged
                    : summary.termination_type == ceres::NO_CONVERGENCE
                        ? Termination::iteration_limit
                        : Termination::non_finite;
  out.message = summary.message;
  return out;
}

// The projection of a fitted B/(p^l A) onto the process structure: gain, time constants of
// the poles (real ones directly, a complex pair through its natural frequency), the zero.
Eigen::VectorXd from_rational(const ProcessStructure& s, const Submodel& m,
                              const Eigen::VectorXd& fallback) {
  const std::vector<std::string> names = s.parameter_names();
  Eigen::VectorXd p = fallback;
  const double b0 = m.b[0];
  if (std::isfinite(b0) && b0 != 0.0) p(0) = b0;
  const int z = index_of(names, "Tz");
  if (z >= 0 && m.b.degree() >= 1 && b0 != 0.0) p(z) = m.b[1] / b0;
  if (m.a.degree() < 1) return p;
  const Eigen::VectorXcd roots = m.a.roots();
  // Time constants 1/|p|, slowest first, a complex pair as two equal-magnitude entries.
  std::vector<std::pair<double, std::complex<double>>> poles;
  for (Eigen::Index i = 0; i < roots.size(); ++i) poles.emplace_back(std::abs(roots(i)), roots(i));
  std::sort(poles.begin(), poles.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<double> constants;
  for (const auto& [magnitude, root] : poles) {
    if (magnitude > 0.0) constants.push_back(1.0 / magnitude);
  }
  if (s.underdamped) {
    // The pair: the complex roots if there are, else the two slowest real ones.
    std::complex<double> pair_root(0.0, 0.0);
    for (const auto& [magnitude, root] : poles) {
      if (root.imag() > 0.0) pair_root = root;
    }
    const int tw = index_of(names, "Tw");
    const int zeta = index_of(names, "Zeta");
    if (pair_root.imag() > 0.0) {
      p(tw) = 1.0 / std::abs(pair_root);
      p(zeta) = std::max(1e-3, -pair_root.real() / std::abs(pair_root));
      const int t3 = index_of(names, "Tp3");
      for (const auto& [magnitude, root] : poles) {
        if (t3 >= 0 && root.imag() == 0.0 && magnitude > 0.0) p(t3) = 1.0 / magnitude;
      }
    } else if (constants.size() >= 2) {
      const double t1 = constants[0];
      const double t2 = constants[1];
      p(tw) = std::sqrt(t1 * t2);
      p(zeta) = (t1 + t2) / (2.0 * std::sqrt(t1 * t2));
      const int t3 = index_of(names, "Tp3");
      if (t3 >= 0 && constants.size() >= 3) p(t3) = constants[2];
    }
  } else {
    for (int i = 1; i <= s.poles && i <= static_cast<int>(constants.size()); ++i) {
      p(index_of(names, "Tp" + std::to_string(i))) = constants[static_cast<std::size_t>(i - 1)];
    }
    // A complex pair read as two real time constants: split them apart a little.
    if (s.poles >= 2 && constants.size() >= 2 && constants[0] == constants[1]) {
      p(index_of(names, "Tp1")) *= 1.2;
      p(index_of(names, "Tp2")) /= 1.2;
    }
  }
  return p;
}

// Tp1 >= Tp2 >= Tp3 (the structure cannot tell them apart; the report orders them).
void sort_time_constants(const ProcessStructure& s, Eigen::VectorXd& p, Eigen::MatrixXd* cov) {
  const std::vector<std::string> names = s.parameter_names();
  std::vector<int> at;
  for (const char* t : {"Tp1", "Tp2", "Tp3"}) {
    if (index_of(names, t) >= 0) at.push_back(index_of(names, t));
  }
  if (s.underdamped || at.size() < 2) return;
  std::vector<int> order = at;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return p(a) > p(b); });
  Eigen::VectorXi perm = Eigen::VectorXi::LinSpaced(p.size(), 0, static_cast<int>(p.size()) - 1);
  for (std::size_t i = 0; i < at.size(); ++i) perm(at[i]) = order[i];
  const Eigen::VectorXd old = p;
  for (Eigen::Index i = 0; i < p.size(); ++i) p(i) = old(perm(i));
  if (cov != nullptr && cov->rows() == p.size()) {
    const Eigen::MatrixXd c = *cov;
    for (Eigen::Index i = 0; i < p.size(); ++i) {
      for (Eigen::Index j = 0; j < p.size(); ++j) (*cov)(i, j) = c(perm(i), perm(j));
    }
  }
}

Eigen::VectorXd clamp_into(const Eigen::VectorXd& p, const Eigen::VectorXd& lo,
                           const Eigen::VectorXd& hi) {
  Eigen::VectorXd q = p;
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    if (!std::isfinite(q(i))) q(i) = std::isfinite(lo(i)) ? lo(i) : 1.0;
    q(i) = std::min(std::max(q(i), lo(i)), hi(i));
  }
  return q;
}

// The gain that fits best with the other parameters as they are (the output is linear in K).
void best_gain(const Problem& problem, Eigen::VectorXd& p) {
  Eigen::VectorXd unit = p;
  unit(0) = 1.0;
  const Eigen::VectorXd y = problem.output(unit);
  if (y.size() != problem.data.output().size()) return;
  const double yy = y.squaredNorm();
  if (yy > 0.0 && std::isfinite(yy)) {
    p(0) =
        std::min(std::max(y.dot(problem.data.output()) / yy, problem.lower(0)), problem.upper(0));
  }
}

// estimate_process_model's bounds (positive time constants, Zeta >= 1e-6, 0 <= Td <= the
// record), narrowed by the options' settings, with the held parameters and the given values.
struct ProcessSettings {
  Eigen::VectorXd lower;
  Eigen::VectorXd upper;
  std::vector<bool> held;
  std::vector<std::optional<double>> given;
};

ProcessSettings process_settings(const std::vector<std::string>& names,
                                 const ProcessModelOptions& options, double h, double duration) {
  const auto count = static_cast<int>(names.size());
  Eigen::VectorXd lower =
      Eigen::VectorXd::Constant(count, -std::numeric_limits<double>::infinity());
  Eigen::VectorXd upper = Eigen::VectorXd::Constant(count, std::numeric_limits<double>::infinity());
  for (int i = 0; i < count; ++i) {
    if (is_positive_parameter(names[static_cast<std::size_t>(i)])) lower(i) = 1e-9 * h;
    if (names[static_cast<std::size_t>(i)] == "Zeta") lower(i) = 1e-6;
    if (names[static_cast<std::size_t>(i)] == "Td") {
      lower(i) = 0.0;
      upper(i) = duration;
    }
  }
  std::vector<bool> held(static_cast<std::size_t>(count), false);
  std::vector<std::optional<double>> given(static_cast<std::size_t>(count));
  for (const ProcessParameterSetting& s : options.parameters) {
    const int i = index_of(names, s.name);
    if (s.lower) lower(i) = std::max(lower(i), *s.lower);
    if (s.upper) upper(i) = std::min(upper(i), *s.upper);
    held[static_cast<std::size_t>(i)] = s.fixed;
    given[static_cast<std::size_t>(i)] = s.value;
  }
  return {std::move(lower), std::move(upper), std::move(held), std::move(given)};
}

// The default start: time constants a tenth, a twentieth, ... of the record, Zeta 0.7, no
// zero, gain 1.
Eigen::VectorXd default_process_start(const std::vector<std::string>& names, double duration) {
  const auto count = static_cast<int>(names.size());
  Eigen::VectorXd fallback = Eigen::VectorXd::Zero(count);
  fallback(0) = 1.0;
  for (int i = 0; i < count; ++i) {
    const std::string& name = names[static_cast<std::size_t>(i)];
    if (name == "Tp1" || name == "Tw") fallback(i) = duration / 10.0;
    if (name == "Tp2") fallback(i) = duration / 20.0;
    if (name == "Tp3") fallback(i) = duration / 40.0;
    if (name == "Zeta") fallback(i) = 0.7;
  }
  return fallback;
}

// Delays to try: the given one, or whole samples 0..max (at most 64 of them, evenly spaced).
std::vector<double> delays_to_try(int td, const std::vector<std::optional<double>>& given,
                                  const Eigen::VectorXd& upper, const ProcessModelOptions& options,
                                  int n, double h) {
  std::vector<double> delays{0.0};
  if (td >= 0 && given[static_cast<std::size_t>(td)]) {
    delays = {*given[static_cast<std::size_t>(td)]};
  } else if (td >= 0) {
    const double max_delay = options.max_delay.value_or(std::min(n / 4, 200) * h);
    const int max_samples = std::max(
        0,
        std::min(static_cast<int>(std::floor(std::min(max_delay, upper(td)) / h + 1e-9)), n / 2));
    const int stride = std::max(1, (max_samples + 63) / 64);
    delays.clear();
    for (int d = 0; d <= max_samples; d += stride) delays.push_back(d * h);
  }
  return delays;
}

// Gauss–Newton covariance sigma^2 (J^T J)^{-1} over the free parameters at p, J by central
// differences of the simulated output (one-sided at Td = 0); NaN when the output cannot be
// differenced; zero for held parameters.
Eigen::MatrixXd gauss_newton_covariance(const Problem& problem, const Eigen::VectorXd& p, int td,
                                        double ssr, double noise_variance) {
  const auto count = static_cast<int>(p.size());
  const auto free = static_cast<int>(problem.free_index.size());
  const int n = problem.data.size();
  const double h = problem.data.sample_time();
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(count, count);
  if (free > 0 && std::isfinite(ssr)) {
    Eigen::MatrixXd jac(n, free);
    bool ok = true;
    for (int c = 0; c < free; ++c) {
      const int j = problem.free_index[static_cast<std::size_t>(c)];
      const double step = 1e-6 * std::max(std::abs(p(j)), j == td ? h : 1e-3);
      Eigen::VectorXd plus = p;
      Eigen::VectorXd minus = p;
      plus(j) += step;
      minus(j) -= step;
      double width = 2.0 * step;
      if (j == td && minus(j) < 0.0) {  // one-sided at Td = 0
        minus(j) = p(j);
        width = step;
      }
      const Eigen::VectorXd y_plus = problem.output(plus);
      const Eigen::VectorXd y_minus = problem.output(minus);
      if (y_plus.size() != n || y_minus.size() != n) {
        ok = false;  // the covariance is NaN: no other column is needed
        break;
      }
      jac.col(c) = (y_plus - y_minus) / width;
    }
    if (ok && jac.allFinite()) {
      const Eigen::MatrixXd info = jac.transpose() * jac;
      const Eigen::MatrixXd inverse = info.ldlt().solve(Eigen::MatrixXd::Identity(free, free));
      for (int a = 0; a < free; ++a) {
        for (int b = 0; b < free; ++b) {
          covariance(problem.free_index[static_cast<std::size_t>(a)],
                     problem.free_index[static_cast<std::size_t>(b)]) =
              noise_variance * inverse(a, b);
        }
      }
    } else {
      covariance.setConstant(std::numeric_limits<double>::quiet_NaN());
    }
  }
  return covariance;
}

// The verdict: finite, fit not worse than the start, standard errors below the values, no
// time constant at its lower bound.
void judge_process_model(ProcessModelResult& result, const std::vector<std::string>& names,
                         const std::vector<bool>& held, const Eigen::VectorXd& p, double ssr,
                         double h) {
  const auto count = static_cast<int>(names.size());
  const int free = static_cast<int>(std::count(held.begin(), held.end(), false));
  check_finite(result.verdict, p.allFinite() && std::isfinite(ssr), "the estimate");
  check_fit(result.verdict, result.fit_percent, result.start_fit_percent);
  std::vector<std::string> free_names;
  Eigen::VectorXd values(free);
  Eigen::VectorXd errors(free);
  for (int c = 0, i = 0; i < count; ++i) {
    if (held[static_cast<std::size_t>(i)]) continue;
    free_names.push_back(names[static_cast<std::size_t>(i)]);
    values(c) = p(i);
    errors(c) = result.standard_errors(i);
    ++c;
  }
  if (result.fit_percent < verdict_thresholds::exact_fit_percent) {
    check_standard_errors(result.verdict, free_names, values, errors);
  }
  for (int i = 0; i < count; ++i) {
    const std::string& name = names[static_cast<std::size_t>(i)];
    if (held[static_cast<std::size_t>(i)] || !is_positive_parameter(name)) continue;
    if (p(i) <= 2e-9 * h) {
      result.verdict.fail(name + " is at its lower bound (the structure has a pole too many)",
                          {verdict_advice::lower_order});
    }
  }
}

// A start of estimate_process_model: parameters, their output error and where they came from.
struct ProcessStart {
  Eigen::VectorXd p;
  double cost;
  std::string method;
};

// The start of matching order from SRIVC at whole-sample `delay` (the other parameters as in
// `base`); none when the record cannot support those orders at this delay or the fit is not
// finite.
std::optional<Eigen::VectorXd> srivc_process_start(const SampledData& data,
                                                   const ProcessStructure& structure, double delay,
                                                   const Eigen::VectorXd& base) {
  const SubmodelOrder order{structure.poles, structure.zero ? 1 : 0, structure.integrator ? 1 : 0};
  try {
    RefinedIvOptions iv;
    iv.input_delay_samples = static_cast<int>(std::lround(delay / data.sample_time()));
    iv.compute_covariance = false;
    iv.max_iterations = 30;
    const EstimationResult r = srivc(data, order, iv);
    if (r.parameters.allFinite() && r.model.size() == 1) {
      return from_rational(structure, r.model[0], base);
    }
  } catch (const InvalidArgument&) {
    // Orders the record cannot support at this delay: the default start stands.
  } catch (const ComputationError&) {
    // A fit whose polynomial roots do not converge: the default start stands.
  }
  return std::nullopt;
}

// Levenberg-Marquardt from every start: the best refinement (the first of equal ones), its
// start and the iterations spent on all of them.
struct ProcessRefinement {
  Refined best;
  ProcessStart start;
  int iterations = 0;
};

ProcessRefinement refine_starts(Problem& problem, const std::vector<ProcessStart>& starts,
                                int max_iterations) {
  ProcessRefinement out{Refined(), starts.front(), 0};
  for (const ProcessStart& c : starts) {
    problem.full = c.p;
    Refined r = refine(problem, c.p, max_iterations);
    out.iterations += r.iterations;
    if (r.sum_of_squares < out.best.sum_of_squares || out.best.parameters.size() == 0) {
      out.best = std::move(r);
      out.start = c;
    }
  }
  return out;
}

// Standard errors from the covariance's diagonal (negative rounding clipped to 0, NaN kept).
Eigen::VectorXd standard_errors_of(const Eigen::MatrixXd& covariance) {
  Eigen::VectorXd se = covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (Eigen::Index i = 0; i < covariance.rows(); ++i) {
    if (std::isnan(covariance(i, i))) se(i) = covariance(i, i);
  }
  return se;
}

}  // namespace

ProcessModelResult estimate_process_model(const SampledData& data,
                                          const ProcessStructure& structure,
                                          const ProcessModelOptions& options) {
  validate_process_model(structure, options);
  const std::vector<std::string> names = structure.parameter_names();
  const auto count = static_cast<int>(names.size());
  const double h = data.sample_time();
  const int n = data.size();
  const double duration = (n - 1) * h;

  // Bounds, held values and user starts.
  const ProcessSettings settings = process_settings(names, options, h, duration);
  const Eigen::VectorXd& lower = settings.lower;
  const Eigen::VectorXd& upper = settings.upper;
  const std::vector<bool>& held = settings.held;
  const std::vector<std::optional<double>>& given = settings.given;
  const int free = static_cast<int>(std::count(held.begin(), held.end(), false));
  require(n >= 10 * std::max(free, 1), "the record has ", n, " samples; process model ",
          structure.name(), " with ", free,
          " free parameters needs at least 10 per free parameter (", 10 * std::max(free, 1), ")");
  const int td = index_of(names, "Td");
  require(td < 0 || !given[static_cast<std::size_t>(td)] ||
              *given[static_cast<std::size_t>(td)] < duration,
          "the dead time Td = ", td >= 0 ? given[static_cast<std::size_t>(td)].value_or(0.0) : 0.0,
          " s is not shorter than the record (", duration, " s)");

  Problem problem{structure, data, Eigen::VectorXd::Zero(count), {}, lower, upper};
  for (int i = 0; i < count; ++i) {
    if (!held[static_cast<std::size_t>(i)]) problem.free_index.push_back(i);
  }

  // The default start (the gain by least squares).
  const Eigen::VectorXd fallback = default_process_start(names, duration);
  const auto apply_given = [&](Eigen::VectorXd p, bool gain) {
    if (gain && !given[0]) best_gain(problem, p);
    for (int i = 0; i < count; ++i) {
      if (given[static_cast<std::size_t>(i)]) p(i) = *given[static_cast<std::size_t>(i)];
    }
    return clamp_into(p, lower, upper);
  };

  const std::vector<double> delays = delays_to_try(td, given, upper, options, n, h);

  const bool all_given =
      std::all_of(given.begin(), given.end(), [](const auto& g) { return g.has_value(); });
  using Candidate = ProcessStart;
  std::vector<Candidate> candidates;
  if (all_given) {
    Eigen::VectorXd p = apply_given(fallback, false);
    problem.full = p;
    candidates.push_back({p, sum_of_squares(problem, p), "user"});
  } else {
    const bool user_part =
        std::any_of(given.begin(), given.end(), [](const auto& g) { return g.has_value(); });
    const bool srivc_possible = structure.poles + (structure.integrator ? 1 : 0) >= 1;
    for (const double delay : delays) {
      Eigen::VectorXd base = fallback;
      if (td >= 0) base(td) = delay;
      std::vector<std::pair<Eigen::VectorXd, std::string>> tries{{base, "default"}};
      if (srivc_possible) {
        if (std::optional<Eigen::VectorXd> s = srivc_process_start(data, structure, delay, base)) {
          tries.emplace_back(std::move(*s), "srivc");
        }
      }
      for (auto& [p, method] : tries) {
        if (td >= 0) p(td) = delay;
        Eigen::VectorXd q = apply_given(p, true);
        problem.full = q;
        candidates.push_back(
            {q, sum_of_squares(problem, q), user_part ? "user+" + method : method});
      }
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  if (candidates.size() > 3) candidates.resize(3);

  ProcessRefinement refined = refine_starts(problem, candidates, options.max_iterations);
  const Refined& best = refined.best;
  const Candidate& best_start = refined.start;
  const int iterations = refined.iterations;

  ProcessModelResult result;
  result.structure = structure.name();
  result.parameter_names = names;
  result.start = best_start.p;
  result.start_method = best_start.method;
  for (int i = 0; i < count; ++i) {
    if (held[static_cast<std::size_t>(i)])
      result.fixed_parameters.push_back(names[static_cast<std::size_t>(i)]);
  }
  result.termination = best.termination;
  result.iterations = iterations;
  result.message = "Levenberg-Marquardt on the output error from the best of " +
                   std::to_string(candidates.size()) + " starts (" + best_start.method +
                   "): " + best.message;
  Eigen::VectorXd p = best.parameters;
  problem.full = p;

  const double ssr = best.sum_of_squares;
  result.mean_squared_error = ssr / n;
  result.noise_variance = n > free ? ssr / (n - free) : std::numeric_limits<double>::quiet_NaN();
  Eigen::MatrixXd covariance = gauss_newton_covariance(problem, p, td, ssr, result.noise_variance);
  Eigen::VectorXd start = result.start;
  sort_time_constants(structure, p, &covariance);
  sort_time_constants(structure, start, nullptr);
  result.start = start;
  result.parameters = p;
  result.covariance = covariance;
  result.standard_errors = standard_errors_of(covariance);

  problem.full = p;
  const Eigen::VectorXd& y = data.output();
  const Eigen::VectorXd y_model = problem.output(p);
  result.fit_percent = fit_percent(y, y_model);
  result.start_fit_percent = fit_percent(y, problem.output(result.start));

  judge_process_model(result, names, held, p, ssr, h);
  return result;
}

}  // namespace ctid
