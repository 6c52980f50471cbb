// Step and impulse responses through the matrix exponential: each submodel is realised in state
// space, y at an arbitrary time s after the delay is C Gamma(s) + D (step) or C e^{As} B
// (impulse) from the blocks of exp([[A, B], [0, 0]] s), and on a uniform grid the state is
// carried by the exact one-step map, so nothing is integrated numerically. Characteristics are
// bracketed on a scan grid set by the poles, then the crossings solved to rounding on the exact
// response (the peak as a zero of the impulse response), so they are smooth in the parameters
// and their central differences are accurate.
#include "ctid/simulation/time_response.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "ctid/core/error.h"
#include "ctid/simulation/discretization.h"

namespace ctid {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A model as realisations to sum, and its input delay.
struct Realisation {
  std::vector<StateSpace> parts;
  double delay = 0.0;
};

Realisation realise(const AdditiveModel& model, const char* function) {
  Realisation r;
  r.delay = model.input_delay();
  for (int i = 0; i < model.size(); ++i) {
    const Submodel& s = model[i];
    const TransferFunction part(s.b, Polynomial::monomial(s.integrators) * s.a);
    require(part.is_proper(), function, ": submodel ", i + 1, " is improper (numerator degree ",
            s.b.degree(), " > denominator degree ", part.denominator().degree(),
            "); its step response has a Dirac impulse");
    r.parts.push_back(part.to_state_space());
  }
  return r;
}

Realisation realise(const TransferFunction& model, const char* function) {
  require(model.is_proper(), function, ": the model is improper (numerator degree ",
          model.numerator().degree(), " > denominator degree ", model.denominator().degree(),
          "); its step response has a Dirac impulse");
  return {{model.with_input_delay(0.0).to_state_space()}, model.input_delay()};
}

// Step and impulse response at s >= 0 after the delay, from one matrix exponential per part.
std::pair<double, double> evaluate(const Realisation& r, double s) {
  double step = 0.0;
  double impulse = 0.0;
  for (const StateSpace& p : r.parts) {
    step += p.d;
    if (p.order() == 0) continue;
    if (s == 0.0) {
      impulse += p.c.dot(p.b);
      continue;
    }
    const ZohDiscretization e = discretize_zoh(p.a, p.b, s);
    step += p.c.dot(e.gamma.col(0));
    impulse += p.c.dot(e.phi * p.b);
  }
  return {step, impulse};
}

double step_at(const Realisation& r, double s) { return evaluate(r, s).first; }
double impulse_at(const Realisation& r, double s) { return evaluate(r, s).second; }

// The response at t_k = k h, k < count, carried by the exact one-step map from the first
// sample at or after the delay.
Eigen::VectorXd uniform_response(const Realisation& r, double h, Eigen::Index count,
                                 ResponseKind kind) {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(count);
  Eigen::Index first = 0;
  while (first < count && static_cast<double>(first) * h < r.delay) ++first;
  if (first == count) return y;
  const double offset = static_cast<double>(first) * h - r.delay;
  const bool step = kind == ResponseKind::step;
  for (const StateSpace& p : r.parts) {
    if (step) y.tail(count - first).array() += p.d;
    if (p.order() == 0) continue;
    const ZohDiscretization one = discretize_zoh(p.a, p.b, h);
    Eigen::VectorXd x = step ? Eigen::VectorXd::Zero(p.order()) : Eigen::VectorXd(p.b);
    if (offset > 0.0) {
      const ZohDiscretization start = discretize_zoh(p.a, p.b, offset);
      x = step ? Eigen::VectorXd(start.gamma.col(0)) : Eigen::VectorXd(start.phi * p.b);
    }
    for (Eigen::Index k = first; k < count; ++k) {
      y(k) += p.c.dot(x);
      x = one.phi * x;
      if (step) x += one.gamma.col(0);
    }
  }
  return y;
}

Eigen::VectorXd at_times(const Realisation& r, const Eigen::VectorXd& times, bool step,
                         const char* function) {
  Eigen::VectorXd y(times.size());
  for (Eigen::Index k = 0; k < times.size(); ++k) {
    require(std::isfinite(times(k)), function, ": times[", k, "] is not finite (", times(k), ")");
    const double s = times(k) - r.delay;
    y(k) = s < 0.0 ? 0.0 : (step ? step_at(r, s) : impulse_at(r, s));
  }
  return y;
}

// A root of f in [a, b] where f(a) and f(b) differ in sign (Illinois regula falsi, to rounding).
template <class F>
double solve(const F& f, double a, double b) {
  double fa = f(a);
  double fb = f(b);
  if (fa == 0.0) return a;
  if (fb == 0.0) return b;
  int side = 0;
  for (int i = 0; i < 200 && std::abs(b - a) > 4e-16 * std::max(std::abs(a), std::abs(b)); ++i) {
    double c = (a * fb - b * fa) / (fb - fa);
    // A secant step that leaves the open bracket (rounding, a stalled side) bisects instead.
    if (!(c > std::min(a, b) && c < std::max(a, b))) c = 0.5 * (a + b);
    if (c == a || c == b) break;
    const double fc = f(c);
    if (fc == 0.0) return c;
    if ((fc > 0.0) == (fb > 0.0)) {
      b = c;
      fb = fc;
      if (side == -1) fa *= 0.5;
      side = -1;
    } else {
      a = c;
      fa = fc;
      if (side == 1) fb *= 0.5;
      side = 1;
    }
  }
  return 0.5 * (a + b);
}

// Poles of every part, and whether any submodel has integrators.
struct PoleSummary {
  bool integrator = false;
  bool unstable = false;
  double slowest_decay = 0.0;  ///< min |Re p| over the poles (stable models)
  double smallest = 0.0;       ///< min |p| over the nonzero poles
  double largest = 0.0;        ///< max |p|
};

PoleSummary summarise_poles(const AdditiveModel& model) {
  PoleSummary out;
  out.slowest_decay = std::numeric_limits<double>::infinity();
  out.smallest = std::numeric_limits<double>::infinity();
  for (const Submodel& s : model.submodels()) {
    if (s.integrators > 0) out.integrator = true;
    if (s.a.degree() < 1) continue;
    const Eigen::VectorXcd poles = s.a.roots();
    for (Eigen::Index k = 0; k < poles.size(); ++k) {
      const double magnitude = std::abs(poles(k));
      if (poles(k).real() >= 0.0) out.unstable = true;
      out.slowest_decay = std::min(out.slowest_decay, std::abs(poles(k).real()));
      if (magnitude > 0.0) out.smallest = std::min(out.smallest, magnitude);
      out.largest = std::max(out.largest, magnitude);
    }
  }
  return out;
}

double dc_gain_of(const AdditiveModel& model) {
  double gain = 0.0;
  for (const Submodel& s : model.submodels()) gain += s.b[0] / s.a[0];
  return gain;
}

std::string not_defined_reason(const PoleSummary& poles, double dc_gain) {
  if (poles.integrator) {
    return "the model has an integrator (a pole at the origin): its step response has no final "
           "value";
  }
  if (poles.unstable) {
    return "the model is not stable (a pole has a real part >= 0): its step response has no "
           "final value";
  }
  if (dc_gain == 0.0) {
    return "the DC gain is 0: rise time, settling time and overshoot are fractions of the final "
           "value";
  }
  return {};
}

// The delay-free grid the characteristics are bracketed on: long enough for the slowest mode
// to die out, fine enough for 16 points per period of the fastest pole.
struct ScanGrid {
  double horizon = 1.0;
  Eigen::Index count = 4000;
  double step() const { return horizon / static_cast<double>(count - 1); }
};

ScanGrid scan_grid(const PoleSummary& poles, double horizon) {
  ScanGrid grid;
  grid.horizon = horizon;
  const double per_period = 16.0 * horizon * poles.largest / (2.0 * std::numbers::pi);
  grid.count = static_cast<Eigen::Index>(std::clamp(std::ceil(per_period), 4000.0, 400000.0));
  return grid;
}

// Delay-free characteristics of one model (NaN where not found): the values the delta method
// differentiates.
struct RawCharacteristics {
  double rise = kNaN;
  double settling = kNaN;
  double overshoot = 0.0;
  double undershoot = 0.0;
  double peak_time = kNaN;
};

// First time the normalised response r reaches `level`, bracketed on the grid.
double first_crossing(const Realisation& r, const Eigen::VectorXd& ratio, double h, double gain,
                      double level) {
  for (Eigen::Index k = 0; k < ratio.size(); ++k) {
    if (ratio(k) < level) continue;
    if (k == 0) return 0.0;
    return solve([&](double s) { return step_at(r, s) / gain - level; },
                 static_cast<double>(k - 1) * h, static_cast<double>(k) * h);
  }
  return kNaN;
}

// The extremum of the normalised response nearest grid point k, where the impulse response
// (its derivative) changes sign; the grid point itself when it is not bracketed.
double extremum_near(const Realisation& r, Eigen::Index k, Eigen::Index count, double h,
                     double gain) {
  if (k == 0 || k + 1 >= count) return static_cast<double>(k) * h;
  const auto slope = [&](double s) { return impulse_at(r, s) / gain; };
  const double a = static_cast<double>(k - 1) * h;
  const double b = static_cast<double>(k + 1) * h;
  if ((slope(a) > 0.0) == (slope(b) > 0.0)) return static_cast<double>(k) * h;
  return solve(slope, a, b);
}

RawCharacteristics raw_characteristics(const Realisation& r, double gain, const ScanGrid& grid,
                                       double band) {
  RawCharacteristics out;
  const double h = grid.step();
  const Eigen::VectorXd ratio =
      uniform_response({r.parts, 0.0}, h, grid.count, ResponseKind::step) / gain;
  const double t10 = first_crossing(r, ratio, h, gain, 0.1);
  const double t90 = first_crossing(r, ratio, h, gain, 0.9);
  out.rise = t90 - t10;
  Eigen::Index last_out = -1;
  for (Eigen::Index k = grid.count - 1; k >= 0; --k) {
    if (std::abs(ratio(k) - 1.0) > band) {
      last_out = k;
      break;
    }
  }
  if (last_out < 0) {
    out.settling = 0.0;
  } else if (last_out < grid.count - 1) {
    out.settling = solve([&](double s) { return std::abs(step_at(r, s) / gain - 1.0) - band; },
                         static_cast<double>(last_out) * h, static_cast<double>(last_out + 1) * h);
  }
  Eigen::Index top = 0;
  Eigen::Index bottom = 0;
  ratio.maxCoeff(&top);
  ratio.minCoeff(&bottom);
  if (ratio(top) > 1.0) {
    out.peak_time = extremum_near(r, top, grid.count, h, gain);
    out.overshoot = 100.0 * (step_at(r, out.peak_time) / gain - 1.0);
  }
  if (ratio(bottom) < 0.0) {
    const double trough = extremum_near(r, bottom, grid.count, h, gain);
    out.undershoot = -100.0 * step_at(r, trough) / gain;
  }
  return out;
}

// The horizon over which the step response of a stable model has settled well inside the band:
// 10 time constants of the slowest mode, doubled while the last tenth is not.
double settled_horizon(const Realisation& r, const PoleSummary& poles, double gain, double band) {
  double horizon = poles.slowest_decay > 0.0 && std::isfinite(poles.slowest_decay)
                       ? 10.0 / poles.slowest_decay
                       : 1.0;
  for (int attempt = 0; attempt < 6; ++attempt) {
    const ScanGrid grid = scan_grid(poles, horizon);
    const Eigen::VectorXd ratio =
        uniform_response({r.parts, 0.0}, grid.step(), grid.count, ResponseKind::step) / gain;
    const Eigen::Index tail = grid.count / 10;
    if ((ratio.tail(tail).array() - 1.0).abs().maxCoeff() <= 0.5 * band) return horizon;
    horizon *= 2.0;
  }
  return horizon;
}

void check_covariance(const Eigen::MatrixXd& covariance, int parameters, const char* function) {
  if (covariance.size() == 0) return;
  require(covariance.rows() == parameters && covariance.cols() == parameters, function,
          ": covariance is ", covariance.rows(), " x ", covariance.cols(), " but the model has ",
          parameters, " parameters");
  require(covariance.allFinite(), function, ": covariance has a non-finite entry");
}

double finite_difference_step(double value) { return value != 0.0 ? 1e-6 * std::abs(value) : 1e-9; }

double quadratic_form(const Eigen::RowVectorXd& gradient, const Eigen::MatrixXd& covariance) {
  return std::max(0.0, gradient.dot(covariance * gradient.transpose()));
}

// The characteristics as a vector (dc gain, rise, settling, overshoot, undershoot, peak time)
// of a model whose poles are classified as the nominal model's; NaN entries where they are not.
Eigen::VectorXd characteristic_vector(const AdditiveModel& model, const ScanGrid& grid, double band,
                                      bool defined) {
  Eigen::VectorXd v = Eigen::VectorXd::Constant(6, kNaN);
  const PoleSummary poles = summarise_poles(model);
  if (poles.integrator || poles.unstable) return v;
  const double gain = dc_gain_of(model);
  v(0) = gain;
  if (!defined || gain == 0.0) return v;
  const RawCharacteristics raw =
      raw_characteristics(realise(model, "step_characteristics"), gain, grid, band);
  v << gain, raw.rise, raw.settling, raw.overshoot, raw.undershoot, raw.peak_time;
  return v;
}

}  // namespace

Eigen::VectorXd step_response(const AdditiveModel& model, const Eigen::VectorXd& times) {
  return at_times(realise(model, "step_response"), times, true, "step_response");
}

Eigen::VectorXd step_response(const TransferFunction& model, const Eigen::VectorXd& times) {
  return at_times(realise(model, "step_response"), times, true, "step_response");
}

Eigen::VectorXd impulse_response(const AdditiveModel& model, const Eigen::VectorXd& times) {
  return at_times(realise(model, "impulse_response"), times, false, "impulse_response");
}

Eigen::VectorXd impulse_response(const TransferFunction& model, const Eigen::VectorXd& times) {
  return at_times(realise(model, "impulse_response"), times, false, "impulse_response");
}

double two_sided_normal_quantile(double confidence) {
  require(confidence > 0.0 && confidence < 1.0,
          "two_sided_normal_quantile: confidence must be in (0, 1), got ", confidence);
  double low = 0.0;
  double high = 40.0;
  for (int i = 0; i < 200 && high - low > 1e-15 * high; ++i) {
    const double mid = 0.5 * (low + high);
    (std::erf(mid / std::sqrt(2.0)) < confidence ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

StepCharacteristics step_characteristics(const AdditiveModel& model,
                                         const Eigen::MatrixXd& covariance, double settling_band,
                                         double delay_standard_error) {
  require(settling_band > 0.0 && settling_band < 1.0,
          "step_characteristics: settling_band must be in (0, 1), got ", settling_band);
  require(std::isfinite(delay_standard_error) && delay_standard_error >= 0.0,
          "step_characteristics: delay_standard_error must be finite and >= 0, got ",
          delay_standard_error);
  check_covariance(covariance, model.parameter_count(), "step_characteristics");
  const Realisation r = realise(model, "step_characteristics");
  const PoleSummary poles = summarise_poles(model);
  StepCharacteristics out;
  out.stable = !poles.integrator && !poles.unstable;
  const double gain = out.stable ? dc_gain_of(model) : kNaN;
  out.not_defined_reason = not_defined_reason(poles, gain);
  const bool defined = out.not_defined_reason.empty();
  ScanGrid grid;
  if (defined) grid = scan_grid(poles, settled_horizon(r, poles, gain, settling_band));
  const Eigen::VectorXd nominal = characteristic_vector(model, grid, settling_band, defined);
  Eigen::VectorXd variance = Eigen::VectorXd::Constant(6, kNaN);
  if (covariance.size() > 0) {
    const Eigen::VectorXd theta = model.parameters();
    Eigen::MatrixXd jacobian(6, theta.size());
    for (Eigen::Index i = 0; i < theta.size(); ++i) {
      const double delta = finite_difference_step(theta(i));
      Eigen::VectorXd up = theta;
      Eigen::VectorXd down = theta;
      up(i) += delta;
      down(i) -= delta;
      jacobian.col(i) =
          (characteristic_vector(model.with_parameters(up), grid, settling_band, defined) -
           characteristic_vector(model.with_parameters(down), grid, settling_band, defined)) /
          (2.0 * delta);
    }
    for (int j = 0; j < 6; ++j) variance(j) = quadratic_form(jacobian.row(j), covariance);
    // Settling and peak times count from the step, so they move with the delay one for one.
    variance(2) += delay_standard_error * delay_standard_error;
    variance(5) += delay_standard_error * delay_standard_error;
  }
  const auto estimate = [&](int j, double shift = 0.0) {
    return ResponseEstimate{nominal(j) + shift, std::sqrt(variance(j))};
  };
  out.dc_gain = estimate(0);
  out.rise_time = estimate(1);
  out.settling_time = estimate(2, r.delay);
  out.overshoot_percent = estimate(3);
  out.undershoot_percent = estimate(4);
  out.peak_time = estimate(5, r.delay);
  // A characteristic at its floor of 0 is not a smooth function of the parameters there.
  if (out.overshoot_percent.value == 0.0) out.overshoot_percent.standard_error = kNaN;
  if (out.undershoot_percent.value == 0.0) out.undershoot_percent.standard_error = kNaN;
  return out;
}

namespace {

// The final time of options, or one the model suggests (see TimeResponseOptions).
double final_time_for(const AdditiveModel& model, const StepCharacteristics& characteristics,
                      const TimeResponseOptions& options) {
  if (options.final_time) return *options.final_time;
  const double settling = characteristics.settling_time.value;
  if (characteristics.defined() && std::isfinite(settling) && settling > model.input_delay()) {
    return 1.5 * settling;
  }
  const PoleSummary poles = summarise_poles(model);
  const double span = std::isfinite(poles.smallest) ? 10.0 / poles.smallest : 10.0;
  return model.input_delay() + span;
}

// The grid's spacing and length, bounded before anything is allocated.
std::pair<double, Eigen::Index> grid_of(double final_time, const TimeResponseOptions& options) {
  if (!options.sample_time) {
    return {final_time / static_cast<double>(options.points - 1), options.points};
  }
  const double h = *options.sample_time;
  const double intervals = std::floor(final_time / h * (1.0 + 1e-12));
  require(intervals + 1.0 <= static_cast<double>(kMaxTimeResponsePoints),
          "time_response: final_time ", final_time, " at sample_time ", h, " gives ",
          intervals + 1.0, " points; at most ", kMaxTimeResponsePoints, " are computed");
  require(intervals >= 1.0, "time_response: sample_time ", h, " exceeds final_time ", final_time,
          "; the grid needs at least 2 points");
  return {h, static_cast<Eigen::Index>(intervals) + 1};
}

}  // namespace

TimeResponse time_response(const AdditiveModel& model, const Eigen::MatrixXd& covariance,
                           const TimeResponseOptions& options, double delay_standard_error) {
  options.validate();
  TimeResponse out;
  out.kind = options.kind;
  out.characteristics =
      step_characteristics(model, covariance, options.settling_band, delay_standard_error);
  const double final_time = final_time_for(model, out.characteristics, options);
  const auto [h, count] = grid_of(final_time, options);
  const Realisation r = realise(model, "time_response");
  out.time = Eigen::VectorXd::LinSpaced(count, 0.0, h * static_cast<double>(count - 1));
  out.output = uniform_response(r, h, count, options.kind);
  if (options.kind == ResponseKind::impulse) {
    for (const StateSpace& p : r.parts) out.dirac_weight += p.d;
  }
  out.z = two_sided_normal_quantile(options.confidence);
  if (covariance.size() == 0) return out;
  const Eigen::VectorXd theta = model.parameters();
  Eigen::VectorXd variance = Eigen::VectorXd::Zero(count);
  Eigen::MatrixXd gradient(count, theta.size());
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    const double delta = finite_difference_step(theta(i));
    Eigen::VectorXd up = theta;
    Eigen::VectorXd down = theta;
    up(i) += delta;
    down(i) -= delta;
    gradient.col(i) = (uniform_response(realise(model.with_parameters(up), "time_response"), h,
                                        count, options.kind) -
                       uniform_response(realise(model.with_parameters(down), "time_response"), h,
                                        count, options.kind)) /
                      (2.0 * delta);
  }
  variance = (gradient * covariance).cwiseProduct(gradient).rowwise().sum().cwiseMax(0.0);
  if (delay_standard_error > 0.0) {
    const double delta = finite_difference_step(std::max(model.input_delay(), h));
    const Eigen::VectorXd later =
        uniform_response({r.parts, r.delay + delta}, h, count, options.kind);
    const Eigen::VectorXd earlier =
        uniform_response({r.parts, std::max(0.0, r.delay - delta)}, h, count, options.kind);
    const double spread = r.delay + delta - std::max(0.0, r.delay - delta);
    variance += ((later - earlier) / spread * delay_standard_error).cwiseAbs2();
  }
  out.standard_deviation = variance.cwiseSqrt();
  out.lower = out.output - out.z * out.standard_deviation;
  out.upper = out.output + out.z * out.standard_deviation;
  return out;
}

}  // namespace ctid
