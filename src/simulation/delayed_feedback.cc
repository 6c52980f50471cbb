// Method-of-steps simulation of a linear system with one delayed internal feedback.
// The delayed signal z(t - Δ) is read from a dense cubic Hermite interpolant of the stored
// (z, dz/dt) at every past grid point, which is O(h^4) like RK4 itself; the grid is broken at
// every multiple of Δ and every sample time, where the solution's derivatives jump.
#include "ctid/simulation/delayed_feedback.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "ctid/core/controllable_form.h"
#include "ctid/core/error.h"

namespace ctid {
namespace {

// Controllable canonical form of a strictly proper N/D (the form of the paper's eq. 22).
StateSpace companion(const Polynomial& numerator, const Polynomial& denominator, const char* what) {
  const int n = denominator.degree();
  require(n >= 1, what, ": the denominator must have degree >= 1, got ", n);
  require(numerator.degree() < n, what, ": must be strictly proper, numerator degree ",
          numerator.degree(), " >= denominator degree ", n);
  return controllable_form(numerator.coefficients(), denominator.coefficients());
}

Polynomial monic_numerator(const TransferFunction& g) {
  return (1.0 / g.denominator().leading()) * g.numerator();
}
Polynomial monic_denominator(const TransferFunction& g) { return g.denominator().monic(); }

void check_common(const DelayedStateSpace& model, double sample_time, int samples,
                  const DelayedSimulationOptions& options) {
  model.validate();
  options.validate();
  require(std::isfinite(sample_time) && sample_time > 0.0,
          "simulate_delayed: sample_time must be positive and finite, got ", sample_time);
  require(samples >= 1, "simulate_delayed: need at least 1 sample, got ", samples);
}

// Past values of z on the grid with their derivatives, read back by cubic Hermite
// interpolation. Zero before t = 0 (the loop is at rest on [-Δ, 0)).
class History {
 public:
  void push(double t, double z, double dz) {
    t_.push_back(t);
    z_.push_back(z);
    dz_.push_back(dz);
  }
  double at(double tau) const {
    if (tau <= 0.0 || t_.empty()) return 0.0;
    if (tau >= t_.back()) return z_.back();
    const auto it = std::upper_bound(t_.begin(), t_.end(), tau);
    const auto i = static_cast<size_t>(it - t_.begin()) - 1;
    const double h = t_[i + 1] - t_[i];
    const double s = (tau - t_[i]) / h;
    const double s2 = s * s;
    const double s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * z_[i] + (s3 - 2 * s2 + s) * h * dz_[i] +
           (-2 * s3 + 3 * s2) * z_[i + 1] + (s3 - s2) * h * dz_[i + 1];
  }

 private:
  std::vector<double> t_, z_, dz_;
};

// Integrates over periods [kδ, (k+1)δ], k = 0..samples-2, calling input(t, k) for u.
template <typename Input>
Eigen::VectorXd integrate(const DelayedStateSpace& model, const Input& input, double delta,
                          int samples, const DelayedSimulationOptions& options) {
  const Eigen::Index order = model.a.rows();
  const bool delayed = model.delay > 0.0;
  // Without delay the feedback is instantaneous: fold it into A.
  const Eigen::MatrixXd a = delayed ? model.a : Eigen::MatrixXd(model.a + model.e * model.g);
  int substeps = options.substeps;
  if (delayed) {
    // A stage at t + h reads z(t + h - Δ), which must already be on the grid.
    substeps = std::max(substeps, static_cast<int>(std::ceil(delta / model.delay)));
  }
  History history;
  auto rhs = [&](double t, const Eigen::VectorXd& x, int period) -> Eigen::VectorXd {
    Eigen::VectorXd dx = a * x + model.b * input(t, period);
    if (delayed) dx += model.e * history.at(t - model.delay);
    return dx;
  };
  Eigen::VectorXd x = Eigen::VectorXd::Zero(order);
  Eigen::VectorXd y(samples);
  y(0) = 0.0;
  std::vector<double> grid;
  for (int k = 0; k + 1 < samples; ++k) {
    const double t0 = k * delta;
    const double t1 = (k + 1) * delta;
    grid.clear();
    for (int i = 0; i <= substeps; ++i) grid.push_back(t0 + (t1 - t0) * i / substeps);
    if (delayed) {
      const double tol = 1e-9 * delta;
      for (double j = std::ceil(t0 / model.delay); j * model.delay < t1; j += 1.0) {
        const double b = j * model.delay;
        const bool near =
            std::any_of(grid.begin(), grid.end(), [&](double g) { return std::abs(g - b) <= tol; });
        if (!near) grid.push_back(b);
      }
      std::sort(grid.begin(), grid.end());
    }
    for (size_t i = 0; i + 1 < grid.size(); ++i) {
      const double t = grid[i];
      const double h = grid[i + 1] - t;
      const Eigen::VectorXd k1 = rhs(t, x, k);
      if (delayed) history.push(t, model.g.dot(x), model.g.dot(k1));
      const Eigen::VectorXd k2 = rhs(t + h / 2, x + h / 2 * k1, k);
      const Eigen::VectorXd k3 = rhs(t + h / 2, x + h / 2 * k2, k);
      const Eigen::VectorXd k4 = rhs(t + h, x + h * k3, k);
      x += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    y(k + 1) = model.c.dot(x);
    if (!x.allFinite()) {
      y.tail(samples - k - 1).setConstant(std::numeric_limits<double>::infinity());
      break;
    }
  }
  return y;
}

}  // namespace

void DelayedFeedbackLoop::validate() const {
  require(std::isfinite(delay) && delay >= 0.0,
          "DelayedFeedbackLoop: delay must be finite and >= 0, got ", delay);
  require(forward.is_strictly_proper(),
          "DelayedFeedbackLoop: forward F must be strictly proper, relative degree ",
          forward.relative_degree());
  require(feedback.is_strictly_proper(),
          "DelayedFeedbackLoop: feedback H must be strictly proper, relative degree ",
          feedback.relative_degree());
  require(forward.input_delay() == 0.0 && feedback.input_delay() == 0.0,
          "DelayedFeedbackLoop: F and H must carry no delay of their own (the loop delay is "
          "'delay')");
}

std::complex<double> DelayedFeedbackLoop::closed_loop_response(std::complex<double> s) const {
  const std::complex<double> f = forward(s);
  const std::complex<double> h = feedback(s);
  return f / (1.0 + f * h * std::exp(-delay * s));
}

Polynomial DelayedFeedbackLoop::alpha() const {
  return monic_numerator(forward) * monic_denominator(feedback);
}
Polynomial DelayedFeedbackLoop::beta() const {
  return monic_denominator(forward) * monic_denominator(feedback);
}
Polynomial DelayedFeedbackLoop::gamma() const {
  return monic_numerator(forward) * monic_numerator(feedback);
}

void DelayedStateSpace::validate() const {
  const Eigen::Index n = a.rows();
  require(n >= 1 && a.cols() == n, "DelayedStateSpace: A must be square and non-empty, got ",
          a.rows(), " x ", a.cols());
  require(b.size() == n && e.size() == n && c.size() == n && g.size() == n,
          "DelayedStateSpace: B, E, C, G must all have ", n, " entries");
  require(a.allFinite() && b.allFinite() && e.allFinite() && c.allFinite() && g.allFinite(),
          "DelayedStateSpace: a matrix has a non-finite entry");
  require(std::isfinite(delay) && delay >= 0.0,
          "DelayedStateSpace: delay must be finite and >= 0, got ", delay);
}

DelayedStateSpace to_delayed_state_space(const DelayedFeedbackLoop& loop) {
  loop.validate();
  const StateSpace f = companion(loop.forward.numerator(), loop.forward.denominator(), "F");
  const StateSpace h = companion(loop.feedback.numerator(), loop.feedback.denominator(), "H");
  const Eigen::Index n = f.a.rows();
  const Eigen::Index m = h.a.rows();
  DelayedStateSpace r;
  r.a = Eigen::MatrixXd::Zero(n + m, n + m);
  r.a.topLeftCorner(n, n) = f.a;
  r.a.bottomRightCorner(m, m) = h.a;
  r.a.bottomLeftCorner(m, n) = h.b * f.c;
  r.b = Eigen::VectorXd::Zero(n + m);
  r.b.head(n) = f.b;
  r.e = Eigen::VectorXd::Zero(n + m);
  r.e.head(n) = -f.b;
  r.c = Eigen::RowVectorXd::Zero(n + m);
  r.c.head(n) = f.c;
  r.g = Eigen::RowVectorXd::Zero(n + m);
  r.g.tail(m) = h.c;
  r.delay = loop.delay;
  return r;
}

DelayedStateSpace to_delayed_state_space(const Polynomial& alpha, const Polynomial& beta,
                                         const Polynomial& gamma, double delay) {
  require(std::isfinite(delay) && delay >= 0.0,
          "to_delayed_state_space: delay must be finite and >= 0, got ", delay);
  const StateSpace u = companion(alpha, beta, "alpha/beta");
  const StateSpace d = companion(gamma, beta, "gamma/beta");
  const Eigen::Index q = u.a.rows();
  DelayedStateSpace r;
  r.a = Eigen::MatrixXd::Zero(2 * q, 2 * q);
  r.a.topLeftCorner(q, q) = u.a;
  r.a.bottomRightCorner(q, q) = d.a;
  r.b = Eigen::VectorXd::Zero(2 * q);
  r.b.head(q) = u.b;
  r.e = Eigen::VectorXd::Zero(2 * q);
  r.e.tail(q) = d.b;
  r.c.resize(2 * q);
  r.c << u.c, -d.c;
  r.g = r.c;  // the delayed signal is y itself
  r.delay = delay;
  return r;
}

Eigen::VectorXd simulate_delayed(const DelayedStateSpace& model,
                                 const std::function<double(double)>& input, double sample_time,
                                 int samples, const DelayedSimulationOptions& options) {
  check_common(model, sample_time, samples, options);
  require(static_cast<bool>(input), "simulate_delayed: the input function is empty");
  return integrate(
      model, [&](double t, int) { return input(t); }, sample_time, samples, options);
}

Eigen::VectorXd simulate_delayed(const DelayedStateSpace& model, const Eigen::VectorXd& input,
                                 double sample_time, Hold hold,
                                 const DelayedSimulationOptions& options) {
  const int samples = static_cast<int>(input.size());
  check_common(model, sample_time, samples, options);
  require(input.allFinite(), "simulate_delayed: the input has a non-finite sample");
  if (hold == Hold::zero_order_hold) {
    return integrate(
        model, [&](double, int k) { return input(k); }, sample_time, samples, options);
  }
  return integrate(
      model,
      [&](double t, int k) {
        if (k + 1 >= samples) return input(k);
        const double s = (t - k * sample_time) / sample_time;
        return input(k) + (input(k + 1) - input(k)) * s;
      },
      sample_time, samples, options);
}

double FourierBasisInput::operator()(double t) const {
  const double w = 2.0 * M_PI * t / period;
  double u = 1.0;
  for (int k = 1; k <= harmonics; ++k) u += std::sqrt(2.0) * (std::sin(k * w) + std::cos(k * w));
  return u;
}

NoisyOutput add_noise_at_nsr(const Eigen::VectorXd& signal, double noise_to_signal,
                             std::uint64_t seed) {
  require(std::isfinite(noise_to_signal) && noise_to_signal >= 0.0,
          "add_noise_at_nsr: noise_to_signal must be finite and >= 0, got ", noise_to_signal);
  require(signal.size() >= 1 && signal.allFinite(),
          "add_noise_at_nsr: the signal must be non-empty and finite");
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd noise(signal.size());
  for (Eigen::Index i = 0; i < noise.size(); ++i) noise(i) = normal(rng);
  const double signal_level = signal.cwiseAbs().mean();
  const double noise_level = noise.cwiseAbs().mean();
  noise *= noise_level > 0.0 ? noise_to_signal * signal_level / noise_level : 0.0;
  return {signal + noise, noise};
}

}  // namespace ctid
