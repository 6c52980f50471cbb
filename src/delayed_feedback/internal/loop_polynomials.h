// α = N_F D_H, β = D_F D_H and γ = N_F N_H of De Iuliis et al. (eq. 2) from the loop
// parameters ρ = [a_F (n) | b_F (n) | a_H (m) | b_H (m)] (ascending, D_F and D_H monic), for
// any scalar type T (double or a Ceres Jet). Private to the estimation layer.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "ctid/core/polynomial.h"

namespace ctid::internal {

// The ascending coefficients of p in a vector of `size`, zero beyond its degree (the layout of
// each block of ρ).
inline Eigen::VectorXd padded(const Polynomial& p, int size) {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(size);
  for (int i = 0; i <= p.degree() && i < size; ++i) v(i) = p.coefficient(i);
  return v;
}

template <typename T>
struct LoopPolynomials {
  std::vector<T> alpha;  ///< q = n + m coefficients, ascending
  std::vector<T> beta;   ///< the q coefficients below the monic s^q, ascending
  std::vector<T> gamma;  ///< q - 1 coefficients, ascending
};

template <typename T>
LoopPolynomials<T> loop_polynomials(const T* rho, int n, int m) {
  const int q = n + m;
  std::vector<T> df(n + 1), nf(n), dh(m + 1), nh(m);
  for (int i = 0; i < n; ++i) df[i] = rho[i];
  df[n] = T(1.0);
  for (int i = 0; i < n; ++i) nf[i] = rho[n + i];
  for (int i = 0; i < m; ++i) dh[i] = rho[2 * n + i];
  dh[m] = T(1.0);
  for (int i = 0; i < m; ++i) nh[i] = rho[2 * n + m + i];
  LoopPolynomials<T> p{std::vector<T>(q, T(0.0)), std::vector<T>(q, T(0.0)),
                       std::vector<T>(q - 1, T(0.0))};
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= m; ++j)
      if (i + j < q) p.beta[i + j] += df[i] * dh[j];
  for (int i = 0; i < n; ++i)
    for (int j = 0; j <= m; ++j) p.alpha[i + j] += nf[i] * dh[j];
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) p.gamma[i + j] += nf[i] * nh[j];
  return p;
}

}  // namespace ctid::internal
