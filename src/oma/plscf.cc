// pLSCF on output-only half-spectra (decision 0066); see ctid/oma/plscf.h.
#include "ctid/oma/plscf.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include "ctid/core/error.h"

namespace ctid::oma_detail {

namespace {

// The window's value at the last lag: w_M = kWindowEnd.
constexpr double kWindowEnd = 0.01;

// The denominator coefficients alpha_0..alpha_{p-1} (stacked, p r x r; alpha_p = I): the
// numerators eliminated by projecting each output's equations on the complement of the
// polynomial basis (real and imaginary parts stacked), the projected equations of every output
// stacked and solved by a pivoted QR. Equal to the reduced normal equations of PolyMAX, without
// squaring their condition number.
Eigen::MatrixXd denominator(const HalfSpectra& h, int p) {
  const int r = h.references;
  const Eigen::Index lines = h.z.size();
  const Eigen::Index l = h.values.front().rows();
  const Eigen::Index cols = static_cast<Eigen::Index>(p + 1) * r;
  const Eigen::MatrixXd q = h.basis.leftCols(p + 1);
  Eigen::MatrixXd z(2 * lines * l, cols);
  Eigen::MatrixXd y(2 * lines, cols);
  for (Eigen::Index o = 0; o < l; ++o) {
    for (Eigen::Index j = 0; j < lines; ++j) {
      std::complex<double> power = 1.0;
      for (int k = 0; k <= p; ++k) {
        for (int c = 0; c < r; ++c) {
          const std::complex<double> v = -power * h.values[static_cast<std::size_t>(j)](o, c);
          y(j, k * r + c) = v.real();
          y(lines + j, k * r + c) = v.imag();
        }
        power *= h.z(j);
      }
    }
    z.middleRows(2 * lines * o, 2 * lines) = y - q * (q.transpose() * y);
  }
  const Eigen::Index lo = static_cast<Eigen::Index>(p) * r;
  return -z.leftCols(lo).colPivHouseholderQr().solve(z.rightCols(r));
}

// The residues of the half-spectra at the discrete poles `mu` (one of each conjugate pair, and
// the real ones), with the poles fixed: real least squares over the lines, each residue l x r.
std::vector<Eigen::MatrixXcd> residues(const HalfSpectra& h,
                                       const std::vector<std::complex<double>>& mu) {
  const Eigen::Index lines = h.z.size();
  const Eigen::Index l = h.values.front().rows();
  const Eigen::Index r = h.values.front().cols();
  Eigen::Index columns = 1;
  for (const auto& m : mu) columns += m.imag() > 0.0 ? 2 : 1;
  Eigen::MatrixXd basis(2 * lines, columns);
  Eigen::MatrixXd data(2 * lines, l * r);
  for (Eigen::Index j = 0; j < lines; ++j) {
    const std::complex<double> zi = 1.0 / h.z(j);
    Eigen::Index c = 0;
    const auto put = [&](std::complex<double> v) {
      basis(j, c) = v.real();
      basis(lines + j, c) = v.imag();
      ++c;
    };
    for (const auto& m : mu) {
      const std::complex<double> g = 1.0 / (1.0 - m * zi);
      if (m.imag() > 0.0) {
        const std::complex<double> gc = 1.0 / (1.0 - std::conj(m) * zi);
        put(g + gc);
        put(std::complex<double>(0.0, 1.0) * (g - gc));
      } else {
        put(g);
      }
    }
    put(1.0);
    for (Eigen::Index b = 0; b < r; ++b) {
      for (Eigen::Index a = 0; a < l; ++a) {
        data(j, a + l * b) = h.values[static_cast<std::size_t>(j)](a, b).real();
        data(lines + j, a + l * b) = h.values[static_cast<std::size_t>(j)](a, b).imag();
      }
    }
  }
  const Eigen::MatrixXd x = basis.colPivHouseholderQr().solve(data);
  std::vector<Eigen::MatrixXcd> out;
  Eigen::Index c = 0;
  for (const auto& m : mu) {
    Eigen::MatrixXcd res(l, r);
    for (Eigen::Index b = 0; b < r; ++b) {
      for (Eigen::Index a = 0; a < l; ++a) {
        const double re = x(c, a + l * b);
        const double im = m.imag() > 0.0 ? x(c + 1, a + l * b) : 0.0;
        res(a, b) = {re, im};
      }
    }
    c += m.imag() > 0.0 ? 2 : 1;
    out.push_back(std::move(res));
  }
  return out;
}

}  // namespace

HalfSpectra half_spectra(const std::vector<Eigen::MatrixXd>& correlations, double sample_time,
                         int max_order) {
  const auto lags = static_cast<int>(correlations.size());
  require(lags >= 2 && max_order >= 1 && correlations.front().cols() >= 1, "half_spectra: ", lags,
          " lags and max_order ", max_order);
  HalfSpectra out;
  out.sample_time = sample_time;
  out.window_decay = std::log(1.0 / kWindowEnd) / (lags * sample_time);
  out.references = static_cast<int>(correlations.front().cols());
  out.max_order = max_order;
  // Lines on the M-point grid (z^M = 1): the truncated sum of a damped exponential is then
  // exactly rational, its truncation a constant factor of the residue.
  const int lines = lags / 2 + 1;
  out.z.resize(lines);
  for (int j = 0; j < lines; ++j) {
    out.z(j) = std::polar(1.0, 2.0 * std::numbers::pi * j / lags);
    Eigen::MatrixXcd s = Eigen::MatrixXcd::Zero(correlations.front().rows(), out.references);
    for (int k = 1; k <= lags; ++k) {
      const double w = std::exp(-out.window_decay * k * sample_time);
      s += (w * std::pow(out.z(j), -k)) * correlations[static_cast<std::size_t>(k - 1)];
    }
    out.values.push_back(std::move(s));
  }
  // An orthonormal basis of the polynomial columns z^0..z^max_order (real and imaginary
  // parts stacked); its leading columns span those of every lower order.
  Eigen::MatrixXd x(2 * lines, max_order + 1);
  for (int j = 0; j < lines; ++j) {
    for (int k = 0; k <= max_order; ++k) {
      const std::complex<double> v = std::pow(out.z(j), k);
      x(j, k) = v.real();
      x(lines + j, k) = v.imag();
    }
  }
  out.basis = Eigen::HouseholderQR<Eigen::MatrixXd>(x).householderQ() *
              Eigen::MatrixXd::Identity(2 * lines, max_order + 1);
  return out;
}

HalfSpectra half_spectra(const Eigen::MatrixXd& y, const std::vector<int>& refs, int lags,
                         double sample_time, int max_order) {
  require(!refs.empty(), "half_spectra: no reference channel");
  return half_spectra(output_correlations(y, refs, lags), sample_time, max_order);
}

std::vector<ModalPole> plscf_poles(const HalfSpectra& h, int order, double max_damping) {
  const int p = std::min(order, h.max_order);
  const int r = h.references;
  if (p < 1) return {};
  const Eigen::MatrixXd alpha = denominator(h, p);
  // The block companion matrix of z^p I + alpha_{p-1} z^{p-1} + ... + alpha_0 (acting on the
  // right): its eigenvalues are the roots of det A(z).
  const Eigen::Index n = static_cast<Eigen::Index>(p) * r;
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < p; ++k) {
    companion.block(0, k * r, r, r) = -alpha.block((p - 1 - k) * r, 0, r, r);
  }
  if (p > 1) companion.bottomLeftCorner(n - r, n - r).setIdentity();
  const Eigen::VectorXcd mu = Eigen::EigenSolver<Eigen::MatrixXd>(companion, false).eigenvalues();
  std::vector<std::complex<double>> kept_mu;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (mu(k).imag() >= 0.0 && std::abs(mu(k)) < 1.0 && std::abs(mu(k)) > 0.0) {
      kept_mu.push_back(mu(k));
    }
  }
  const std::vector<Eigen::MatrixXcd> res = residues(h, kept_mu);
  std::vector<ModalPole> poles;
  for (std::size_t k = 0; k < kept_mu.size(); ++k) {
    if (!(kept_mu[k].imag() > 0.0)) continue;
    auto pole = modal_pole(std::log(kept_mu[k]) / h.sample_time + h.window_decay, max_damping, [&] {
      const Eigen::JacobiSVD<Eigen::MatrixXcd> svd(res[k], Eigen::ComputeThinU);
      return Eigen::VectorXcd(svd.matrixU().col(0));
    });
    if (pole) poles.push_back(std::move(*pole));
  }
  sort_by_frequency(poles);
  return poles;
}

}  // namespace ctid::oma_detail
