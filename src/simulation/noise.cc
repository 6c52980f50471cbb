// Coloured noise and SNR scaling.
#include "ctid/simulation/noise.h"

#include <algorithm>
#include <cmath>

#include "ctid/core/error.h"
#include "ctid/simulation/excitation.h"

namespace ctid {
namespace {

double max_pole_radius(const DiscreteTransferFunction& filter) {
  const Eigen::VectorXcd poles = filter.poles();
  return poles.size() == 0 ? 0.0 : poles.cwiseAbs().maxCoeff();
}

void require_stable(const DiscreteTransferFunction& filter, double radius, const char* function) {
  require(radius < 1.0, function, ": the noise filter ", filter.to_string(),
          " must be stable for stationary noise, but has a pole of magnitude ", radius);
}

double sample_variance(const Eigen::VectorXd& x) {
  return (x.array() - x.mean()).square().sum() / static_cast<double>(x.size() - 1);
}

}  // namespace

int stationary_run_in(const DiscreteTransferFunction& filter, double tolerance) {
  require(std::isfinite(tolerance) && tolerance > 0.0 && tolerance < 1.0,
          "stationary_run_in: tolerance must be in (0, 1), got ", tolerance);
  const double radius = max_pole_radius(filter);
  require_stable(filter, radius, "stationary_run_in");
  const int order = filter.denominator().degree();
  if (radius <= 0.0) return order;
  const double samples = std::ceil(std::log(tolerance) / std::log(radius));
  require(samples <= 1e8, "stationary_run_in: the slowest pole of ", filter.to_string(),
          " (magnitude ", radius, ") needs ", samples, " samples to settle, more than 1e8");
  return std::max(order, static_cast<int>(samples));
}

double stationary_variance_gain(const DiscreteTransferFunction& filter) {
  require_stable(filter, max_pole_radius(filter), "stationary_variance_gain");
  const StateSpace model = filter.to_state_space();
  if (model.order() == 0) return model.d * model.d;
  // P = A P A' + B B' by doubling: P <- P + A^(2^j) P A^(2^j)'; converges quadratically.
  Eigen::MatrixXd p = model.b * model.b.transpose();
  Eigen::MatrixXd a = model.a;
  for (int j = 0; j < 100; ++j) {
    const Eigen::MatrixXd increment = a * p * a.transpose();
    p += increment;
    a = a * a;
    if (increment.norm() <= 1e-17 * p.norm()) break;
  }
  return (model.c * p * model.c.transpose())(0, 0) + model.d * model.d;
}

Eigen::VectorXd colored_noise(const DiscreteTransferFunction& filter, int length, double variance,
                              std::uint64_t seed, int run_in) {
  require(length >= 0, "colored_noise: length must be >= 0, got ", length);
  require(std::isfinite(variance) && variance >= 0.0,
          "colored_noise: variance must be finite and >= 0, got ", variance);
  const int settle = run_in < 0 ? stationary_run_in(filter) : run_in;
  require_stable(filter, max_pole_radius(filter), "colored_noise");
  const Eigen::VectorXd e = white_noise(settle + length, std::sqrt(variance), seed);
  return filter.filter(e).tail(length);
}

double snr_db(const Eigen::VectorXd& signal, const Eigen::VectorXd& noise) {
  require(signal.size() == noise.size(), "snr_db: signal has ", signal.size(),
          " samples but noise has ", noise.size());
  require(signal.size() >= 2, "snr_db: need at least 2 samples, got ", signal.size());
  const double noise_variance = sample_variance(noise);
  require(noise_variance > 0.0, "snr_db: the noise is constant (zero variance)");
  return 10.0 * std::log10(sample_variance(signal) / noise_variance);
}

Eigen::VectorXd scale_noise_to_snr(const Eigen::VectorXd& signal, const Eigen::VectorXd& noise,
                                   double snr) {
  require(std::isfinite(snr), "scale_noise_to_snr: snr must be finite (dB), got ", snr);
  const double current = snr_db(signal, noise);
  require(std::isfinite(current), "scale_noise_to_snr: the signal has zero variance");
  // Scaling the noise by c changes the SNR by -20 log10(c) dB.
  return noise * std::pow(10.0, (current - snr) / 20.0);
}

}  // namespace ctid
