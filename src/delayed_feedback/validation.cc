// White-noise validation of F̂, Ĥ against F, H (Section 4 of the delayed-feedback paper).
#include "ctid/delayed_feedback/validation.h"

#include <cmath>
#include <limits>
#include <random>

#include "ctid/core/error.h"
#include "ctid/core/state_space.h"
#include "ctid/simulation/discretization.h"

namespace ctid {
namespace {

// Discrete (Φ, Γ, C, D) of estimate - truth, realised in parallel so that a large but
// stable estimate does not cancel numerically against the truth inside one polynomial.
StateSpace error_system(const TransferFunction& truth, const TransferFunction& estimate, double h) {
  const StateSpace a = discretize_zoh(truth.to_state_space(), h);
  const StateSpace b = discretize_zoh(estimate.to_state_space(), h);
  const Eigen::Index n = a.order();
  const Eigen::Index m = b.order();
  StateSpace e;
  e.a = Eigen::MatrixXd::Zero(n + m, n + m);
  e.a.topLeftCorner(n, n) = a.a;
  e.a.bottomRightCorner(m, m) = b.a;
  e.b.resize(n + m);
  e.b << a.b, b.b;
  e.c.resize(n + m);
  e.c << -a.c, b.c;
  e.d = b.d - a.d;
  return e;
}

void check_models(const TransferFunction& truth, const TransferFunction& estimate) {
  require(truth.is_proper() && estimate.is_proper(),
          "white-noise validation: both models must be proper");
  require(truth.input_delay() == 0.0 && estimate.input_delay() == 0.0,
          "white-noise validation: models must carry no delay");
}

}  // namespace

void WhiteNoiseValidationOptions::check_relations(const std::string& path) const {
  require(duration >= sample_time, path, ".duration is ", duration, "; it must be >= sample_time (",
          sample_time, ")");
}

double expected_white_noise_mse(const TransferFunction& truth, const TransferFunction& estimate,
                                double sample_time, int samples) {
  check_models(truth, estimate);
  require(samples >= 1 && sample_time > 0.0,
          "expected_white_noise_mse: need samples >= 1 and sample_time > 0");
  const StateSpace e = error_system(truth, estimate, sample_time);
  // y_k = D w_k + sum_{j>=1} C Φ^{j-1} Γ w_{k-j}; E y_k² = sum_{j=0}^{k} g_j².
  double cumulative = e.d * e.d;
  double total = 0.0;
  Eigen::VectorXd x = e.b;
  for (int k = 1; k <= samples; ++k) {
    const double g = e.c.dot(x);
    cumulative += g * g;
    total += cumulative;
    if (!std::isfinite(total)) return std::numeric_limits<double>::infinity();
    x = e.a * x;
  }
  return total / samples;
}

ResponseComparison compare_white_noise_response(const TransferFunction& truth,
                                                const TransferFunction& estimate,
                                                const WhiteNoiseValidationOptions& options) {
  options.validate();
  check_models(truth, estimate);
  const int n = static_cast<int>(std::lround(options.duration / options.sample_time));
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd w(n + 1);
  for (int k = 0; k <= n; ++k) w(k) = normal(rng);
  auto respond = [&](const TransferFunction& g) {
    const StateSpace d = discretize_zoh(g.to_state_space(), options.sample_time);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(d.order());
    Eigen::VectorXd y(n);
    for (int k = 1; k <= n; ++k) {
      x = d.a * x + d.b * w(k - 1);
      y(k - 1) = d.c.dot(x) + d.d * w(k);
    }
    return y;
  };
  ResponseComparison r;
  r.truth = respond(truth);
  r.estimate = respond(estimate);
  r.estimate_stable = estimate.is_stable();
  r.mse = r.estimate.allFinite() ? (r.estimate - r.truth).squaredNorm() / n
                                 : std::numeric_limits<double>::infinity();
  if (!std::isfinite(r.mse)) r.mse = std::numeric_limits<double>::infinity();
  r.expected_mse = expected_white_noise_mse(truth, estimate, options.sample_time, n);
  return r;
}

}  // namespace ctid
