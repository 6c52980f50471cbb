// Frequency responses evaluated pointwise from the models' polynomials.
#include "ctid/frequency/response.h"

#include <cmath>
#include <complex>

#include "ctid/core/error.h"

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

}  // namespace ctid
