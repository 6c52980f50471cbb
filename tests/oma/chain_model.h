// A chain of masses and springs with Rayleigh damping, discretised exactly (A = e^{A_c h} from
// the eigen-decomposition of A_c), for the output-only tests: its continuous modes are the
// truth, its discrete stochastic model gives exact correlations (Lyapunov) and seeded records.
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/KroneckerProduct>

#include "ctid/oma/oma.h"
#include "ctid/oma/ssi_cov.h"

namespace ctid::oma_test {

struct TrueMode {
  double frequency_hz;
  double damping_ratio;
  Eigen::VectorXcd shape;  // displacements, normalised as the library does
};

struct ChainModel {
  int dofs = 4;
  double h = 0.005;
  Eigen::MatrixXd ac, ad, c, gamma;  // gamma: force (white, ZOH) to state
  std::vector<TrueMode> modes;       // by frequency

  explicit ChainModel(int n = 4, double sample_time = 0.005, double alpha = 0.5, double beta = 1e-4)
      : dofs(n), h(sample_time) {
    Eigen::MatrixXd k = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; ++i) {
      k(i, i) = 2.0e4 * (i + 1 < n ? 2.0 : 1.0);
      if (i + 1 < n) k(i, i + 1) = k(i + 1, i) = -2.0e4;
    }
    Eigen::MatrixXd m = Eigen::MatrixXd::Identity(n, n);
    for (int i = 0; i < n; ++i) m(i, i) = 1.0 + 0.25 * i;
    const Eigen::MatrixXd minv = m.inverse();
    const Eigen::MatrixXd damping = alpha * m + beta * k;
    ac = Eigen::MatrixXd::Zero(2 * n, 2 * n);
    ac.topRightCorner(n, n).setIdentity();
    ac.bottomLeftCorner(n, n) = -minv * k;
    ac.bottomRightCorner(n, n) = -minv * damping;
    const Eigen::EigenSolver<Eigen::MatrixXd> eig(ac);
    const Eigen::VectorXcd lambda = eig.eigenvalues();
    const Eigen::MatrixXcd v = eig.eigenvectors();
    Eigen::VectorXcd e = (lambda * h).array().exp();
    ad = (v * e.asDiagonal() * v.inverse()).real();
    c = Eigen::MatrixXd::Zero(n, 2 * n);
    c.leftCols(n).setIdentity();
    Eigen::MatrixXd b = Eigen::MatrixXd::Zero(2 * n, n);
    b.bottomRows(n) = minv;
    gamma = ac.partialPivLu().solve((ad - Eigen::MatrixXd::Identity(2 * n, 2 * n)) * b);
    for (Eigen::Index i = 0; i < lambda.size(); ++i) {
      if (lambda(i).imag() <= 0.0) continue;
      const double wn = std::abs(lambda(i));
      modes.push_back({wn / (2.0 * std::numbers::pi), -lambda(i).real() / wn,
                       oma_detail::normalise_shape(v.col(i).head(n))});
    }
    std::sort(modes.begin(), modes.end(),
              [](const TrueMode& x, const TrueMode& y) { return x.frequency_hz < y.frequency_hz; });
  }

  /// Exact R_1..R_lags (l x r, references `refs`) for force covariance I and no sensor noise.
  std::vector<Eigen::MatrixXd> correlations(const std::vector<int>& refs, int lags) const {
    const Eigen::Index s = ad.rows();
    const Eigen::MatrixXd q = gamma * gamma.transpose();
    const Eigen::MatrixXd kron =
        Eigen::MatrixXd::Identity(s * s, s * s) - Eigen::kroneckerProduct(ad, ad).eval();
    const Eigen::VectorXd vec_sigma =
        kron.partialPivLu().solve(Eigen::Map<const Eigen::VectorXd>(q.data(), s * s));
    const Eigen::MatrixXd sigma = Eigen::Map<const Eigen::MatrixXd>(vec_sigma.data(), s, s);
    const Eigen::MatrixXd g_full = ad * sigma * c.transpose();
    Eigen::MatrixXd g(s, static_cast<Eigen::Index>(refs.size()));
    for (std::size_t j = 0; j < refs.size(); ++j)
      g.col(static_cast<Eigen::Index>(j)) = g_full.col(refs[j]);
    std::vector<Eigen::MatrixXd> r;
    Eigen::MatrixXd power = Eigen::MatrixXd::Identity(s, s);
    for (int i = 1; i <= lags; ++i) {
      r.push_back(c * power * g);
      power = power * ad;
    }
    return r;
  }

  /// N samples of displacement driven by unit white forces, sensor noise of `noise` times
  /// each channel's standard deviation added (seeded).
  Eigen::MatrixXd simulate(int samples, double noise, unsigned seed) const {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal;
    const Eigen::Index s = ad.rows();
    Eigen::VectorXd x = Eigen::VectorXd::Zero(s);
    Eigen::VectorXd w(dofs);
    const int warmup = 2000;
    Eigen::MatrixXd y(samples, dofs);
    for (int k = -warmup; k < samples; ++k) {
      if (k >= 0) y.row(k) = (c * x).transpose();
      for (int i = 0; i < dofs; ++i) w(i) = normal(rng);
      x = ad * x + gamma * w;
    }
    for (int j = 0; j < dofs; ++j) {
      const double sd = std::sqrt((y.col(j).array() - y.col(j).mean()).square().mean());
      for (int k = 0; k < samples; ++k) y(k, j) += noise * sd * normal(rng);
    }
    return y;
  }
};

/// A mode's shape as the complex vector the library reports (shape_real + i shape_imag).
inline Eigen::VectorXcd shape_of(const OmaMode& m) {
  Eigen::VectorXcd s(static_cast<Eigen::Index>(m.shape_real.size()));
  for (Eigen::Index j = 0; j < s.size(); ++j) {
    s(j) = {m.shape_real[static_cast<std::size_t>(j)], m.shape_imag[static_cast<std::size_t>(j)]};
  }
  return s;
}

/// The mode of `r` nearest `f` [Hz]; nullptr when there is none.
inline const OmaMode* nearest(const OmaResult& r, double f) {
  const OmaMode* best = nullptr;
  for (const auto& m : r.modes) {
    if (best == nullptr || std::abs(m.frequency_hz - f) < std::abs(best->frequency_hz - f)) {
      best = &m;
    }
  }
  return best;
}

/// The mode of `r` nearest the true mode, checked: finite positive standard errors, frequency
/// and damping ratio within 4 of them, MAC >= 0.99 with the true shape and at least 3
/// supporting orders. nullptr (and a failure) when `r` has no mode.
inline const OmaMode* expect_found_within_errors(const OmaResult& r, const TrueMode& truth) {
  const OmaMode* m = nearest(r, truth.frequency_hz);
  EXPECT_NE(m, nullptr);
  if (m == nullptr) return nullptr;
  EXPECT_TRUE(std::isfinite(m->frequency_hz_std) && m->frequency_hz_std > 0.0);
  EXPECT_LT(std::abs(m->frequency_hz - truth.frequency_hz), 4.0 * m->frequency_hz_std);
  EXPECT_LT(std::abs(m->damping_ratio - truth.damping_ratio), 4.0 * m->damping_ratio_std);
  EXPECT_GE(oma_detail::modal_assurance(shape_of(*m), truth.shape), 0.99);
  EXPECT_GE(m->supporting_orders, 3);
  return m;
}

}  // namespace ctid::oma_test
