// Frequency responses evaluated pointwise from the models' polynomials.
#include "ctid/frequency/response.h"

#include <cmath>
#include <complex>
#include <optional>

#include <Eigen/Dense>

#include "ctid/core/error.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/simulate.h"

namespace ctid {
namespace {

void check_grid(const Eigen::VectorXd& omegas) {
  for (Eigen::Index i = 0; i < omegas.size(); ++i) {
    require(std::isfinite(omegas(i)), "frequency_response: omega[", i, "] is not finite (",
            omegas(i), ")");
  }
}

std::complex<double> delay_factor(double omega, double tau) {
  return std::polar(1.0, -omega * tau);
}

}  // namespace

Eigen::VectorXd log_frequency_grid(double omega_min, double omega_max, int count) {
  require(std::isfinite(omega_min) && omega_min > 0.0,
          "log_frequency_grid: omega_min must be positive and finite, got ", omega_min);
  require(std::isfinite(omega_max) && omega_max > omega_min,
          "log_frequency_grid: omega_max must be finite and > omega_min (", omega_min, "), got ",
          omega_max);
  require(count >= 2, "log_frequency_grid: count must be >= 2, got ", count);
  Eigen::VectorXd grid =
      Eigen::VectorXd::LinSpaced(count, std::log10(omega_min), std::log10(omega_max));
  for (int i = 0; i < count; ++i) grid(i) = std::pow(10.0, grid(i));
  grid(0) = omega_min;
  grid(count - 1) = omega_max;
  return grid;
}

Eigen::VectorXcd frequency_response(const TransferFunction& g, const Eigen::VectorXd& omegas) {
  check_grid(omegas);
  Eigen::VectorXcd response(omegas.size());
  for (Eigen::Index i = 0; i < omegas.size(); ++i) response(i) = g.frequency_response(omegas(i));
  return response;
}

Eigen::VectorXcd frequency_response(const DiscreteTransferFunction& g,
                                    const Eigen::VectorXd& omegas) {
  check_grid(omegas);
  Eigen::VectorXcd response(omegas.size());
  for (Eigen::Index i = 0; i < omegas.size(); ++i) response(i) = g.frequency_response(omegas(i));
  return response;
}

Eigen::MatrixXcd submodel_frequency_responses(const AdditiveModel& g,
                                              const Eigen::VectorXd& omegas) {
  check_grid(omegas);
  Eigen::MatrixXcd responses(omegas.size(), g.size());
  for (int k = 0; k < g.size(); ++k) {
    const TransferFunction part = g[k].to_transfer_function();
    for (Eigen::Index i = 0; i < omegas.size(); ++i) {
      responses(i, k) = part(std::complex<double>(0.0, omegas(i)));
    }
  }
  return responses;
}

Eigen::VectorXcd frequency_response(const AdditiveModel& g, const Eigen::VectorXd& omegas) {
  const Eigen::MatrixXcd parts = submodel_frequency_responses(g, omegas);
  Eigen::VectorXcd response = parts.rowwise().sum();
  if (g.input_delay() != 0.0) {
    for (Eigen::Index i = 0; i < omegas.size(); ++i) {
      response(i) *= delay_factor(omegas(i), g.input_delay());
    }
  }
  return response;
}

Eigen::VectorXcd sampled_frequency_response(const AdditiveModel& g, const Eigen::VectorXd& omegas,
                                            double h, Hold hold) {
  require(std::isfinite(h) && h > 0.0, "sampled_frequency_response: h must be positive, got ", h);
  const DelaySplit delay = split_delay(g.input_delay(), h);
  Eigen::VectorXcd out = Eigen::VectorXcd::Zero(omegas.size());
  for (const Submodel& s : g.submodels()) {
    const TransferFunction part(s.b, Polynomial::monomial(s.integrators) * s.a);
    require(part.is_proper(), "sampled_frequency_response: submodel numerator degree ",
            s.b.degree(), " exceeds its denominator's");
    const StateSpace ss = part.to_state_space();
    // The direct term sees the delayed input at the samples; a static gain has nothing else.
    const DelayedSample now = delayed_sample(delay.fraction, hold);
    std::optional<DelayedHoldDiscretization> w;
    if (ss.order() > 0) w = discretize_delayed(ss.a, ss.b, h, delay.fraction, hold);
    for (Eigen::Index k = 0; k < omegas.size(); ++k) {
      const std::complex<double> z = std::exp(std::complex<double>(0.0, omegas(k) * h));
      out(k) += ss.d * (now.previous / z + now.current);
      if (!w) continue;
      const Eigen::MatrixXcd resolvent = (z * Eigen::MatrixXcd::Identity(ss.order(), ss.order()) -
                                          w->phi.cast<std::complex<double>>())
                                             .inverse();
      const Eigen::VectorXcd drive = w->previous.col(0).cast<std::complex<double>>() / z +
                                     w->current.col(0).cast<std::complex<double>>() +
                                     w->next.col(0).cast<std::complex<double>>() * z;
      out(k) += ss.c.cast<std::complex<double>>().dot(resolvent * drive);
    }
  }
  for (Eigen::Index k = 0; k < omegas.size(); ++k) {
    out(k) *= std::exp(std::complex<double>(0.0, -omegas(k) * h * delay.samples));
  }
  return out;
}

}  // namespace ctid
