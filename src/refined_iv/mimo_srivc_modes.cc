// The covariance of a mimo_srivc estimate (the sandwich covariance) and the model's block of
// it; the modes computed from it are estimation's (estimation/mimo_modes.h, decision 0045).
#include "ctid/refined_iv/mimo_srivc.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <utility>

#include <Eigen/Dense>
#include <Eigen/SVD>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/estimation/validation.h"
#include "ctid/estimation/verdict.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/frequency/frf.h"
#include "ctid/frequency/mimo_frf.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/simulate.h"
#include "estimation/internal/mimo_layout.h"
#include "estimation/internal/scaled_least_squares.h"
#include "internal/mimo_srivc_parts.h"
#include "internal/refined_iv_engine.h"

namespace ctid::mimo_srivc_parts {

// Sandwich covariance R^-1 Q R^-1 of the estimate: output j's gradient is [psi_j, 0.., U (in
// j's numerator slot), 0..], R the sum of their products and Q that of the AR-whitened
// gradients (adjoint_ar_filter) weighted by the outputs' innovation covariance (below).
Eigen::MatrixXd mimo_covariance(const Layout& layout, const MimoData& data, const Iterate& x,
                                const Eigen::MatrixXd& u, const Eigen::MatrixXd& residuals,
                                NoiseAssumption noise, int max_ar_order) {
  const MimoAdditiveModel& model = x.model;
  const int n = data.size();
  const int pa = layout.a_count;
  const int pu = layout.u_count;
  const int p = pa + layout.outputs * pu;
  const InstrumentSources sources(layout, data, denominators(model));
  std::vector<Eigen::MatrixXd> psi(static_cast<size_t>(layout.outputs), Eigen::MatrixXd(n, pa));
  Eigen::VectorXd s_a = Eigen::VectorXd::Zero(pa);
  for (int j = 0; j < layout.outputs; ++j) {
    sources.denominator_instrument(x, j, psi[static_cast<size_t>(j)]);
    s_a += psi[static_cast<size_t>(j)].colwise().squaredNorm().transpose();
  }
  for (Eigen::Index c = 0; c < pa; ++c) s_a(c) = s_a(c) > 0.0 ? std::sqrt(s_a(c)) : 1.0;
  const Eigen::VectorXd s_u = internal::column_scales(u);
  const Eigen::MatrixXd us = u * s_u.cwiseInverse().asDiagonal();
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(p, p);
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(p, p);
  const double dof = static_cast<double>(n) / static_cast<double>(std::max(1, n - pu - pa));
  // Per output: its (whitened) gradient g_j ((pa + pu) x N) and its innovations.
  std::vector<Eigen::MatrixXd> g(static_cast<size_t>(layout.outputs));
  Eigen::MatrixXd innovations(n, layout.outputs);
  Eigen::VectorXd variance(layout.outputs);  // of each output's innovations (AR or residual)
  for (int j = 0; j < layout.outputs; ++j) {
    const Eigen::MatrixXd ps = psi[static_cast<size_t>(j)] * s_a.cwiseInverse().asDiagonal();
    const int at = pa + j * pu;
    r.topLeftCorner(pa, pa) += ps.transpose() * ps;
    r.block(0, at, pa, pu) = ps.transpose() * us;
    r.block(at, 0, pu, pa) = r.block(0, at, pa, pu).transpose();
    r.block(at, at, pu, pu) = us.transpose() * us;
    Eigen::MatrixXd both(n, pa + pu);
    both << ps, us;
    if (noise == NoiseAssumption::white) {
      g[static_cast<size_t>(j)] = both.transpose();
      innovations.col(j) = residuals.col(j);
      variance(j) = residuals.col(j).squaredNorm() / static_cast<double>(n) * dof;
    } else {
      const AutoregressiveModel ar = fit_autoregressive(residuals.col(j), max_ar_order);
      g[static_cast<size_t>(j)] = adjoint_ar_filter(both, ar);
      variance(j) = ar.innovation_variance * dof;
      const Eigen::Index order = ar.coefficients.size() - 1;
      for (Eigen::Index t = 0; t < n; ++t) {
        double e = residuals(t, j);
        for (Eigen::Index k = 1; k <= std::min(order, t); ++k) {
          e += ar.coefficients(k) * residuals(t - k, j);
        }
        innovations(t, j) = e;
      }
    }
  }
  // The outputs' innovations are white in time but may be correlated with each other (one
  // disturbance seen by every sensor): Q = sum_jl Sigma_jl g_j g_l'. With Sigma diagonal this is
  // the independent-outputs sandwich; on the measured flexible structure the cross terms
  // make the shared denominators' errors several times larger.
  // Sigma: each output's own innovation variance (as the SISO covariance has it) and the
  // correlations of the innovation series between outputs.
  const Eigen::MatrixXd products = innovations.transpose() * innovations;
  Eigen::MatrixXd sigma(layout.outputs, layout.outputs);
  for (int j = 0; j < layout.outputs; ++j) {
    for (int l = 0; l < layout.outputs; ++l) {
      const double norms = std::sqrt(products(j, j) * products(l, l));
      const double correlation = j == l ? 1.0 : (norms > 0.0 ? products(j, l) / norms : 0.0);
      sigma(j, l) = correlation * std::sqrt(variance(j) * variance(l));
    }
  }
  for (int l = 0; l < layout.outputs; ++l) {
    const Eigen::MatrixXd& gl = g[static_cast<size_t>(l)];
    Eigen::MatrixXd weighted_a = Eigen::MatrixXd::Zero(pa, n);
    for (int j = 0; j < layout.outputs; ++j) {
      weighted_a += sigma(j, l) * g[static_cast<size_t>(j)].topRows(pa);
    }
    const int at = pa + l * pu;
    q.topLeftCorner(pa, pa) += weighted_a * gl.topRows(pa).transpose();
    q.block(0, at, pa, pu) = weighted_a * gl.bottomRows(pu).transpose();
    q.block(at, 0, pu, pa) = q.block(0, at, pa, pu).transpose();
  }
  // The numerator blocks: white noise leaves every output's numerator gradient U itself.
  const Eigen::MatrixXd uu =
      noise == NoiseAssumption::white ? Eigen::MatrixXd(us.transpose() * us) : Eigen::MatrixXd();
  for (int j = 0; j < layout.outputs; ++j) {
    for (int l = j; l < layout.outputs; ++l) {
      const Eigen::MatrixXd block =
          noise == NoiseAssumption::white
              ? Eigen::MatrixXd(sigma(j, l) * uu)
              : Eigen::MatrixXd(sigma(j, l) * g[static_cast<size_t>(j)].bottomRows(pu) *
                                g[static_cast<size_t>(l)].bottomRows(pu).transpose());
      q.block(pa + j * pu, pa + l * pu, pu, pu) = block;
      if (l != j) q.block(pa + l * pu, pa + j * pu, pu, pu) = block.transpose();
    }
  }
  const Eigen::MatrixXd r_inv = r.completeOrthogonalDecomposition().pseudoInverse();
  Eigen::VectorXd scale(p);
  scale << s_a, s_u.replicate(layout.outputs, 1);
  return scale.cwiseInverse().asDiagonal() * (r_inv * q * r_inv) *
         scale.cwiseInverse().asDiagonal();
}

// The layout without free responses: that of the model's parameters and the covariance.
Layout model_layout(const Layout& layout) {
  Layout plain(layout.orders, layout.inputs, layout.outputs, layout.direct);
  plain.input_fractions = layout.input_fractions;
  return plain;
}

// The model's block of the joint covariance of the parameters and the free responses' coefficients
// (docs/decisions/0010): the free responses' uncertainty is accounted for, their entries dropped.
Eigen::MatrixXd model_block(const Layout& layout, const Eigen::MatrixXd& joint) {
  if (layout.free_count == 0) return joint;
  std::vector<Eigen::Index> keep;
  for (int c = 0; c < layout.a_count; ++c) keep.push_back(c);
  for (int j = 0; j < layout.outputs; ++j) {
    for (int c = 0; c < layout.model_columns(); ++c) keep.push_back(layout.b_index(j, c));
  }
  const auto p = static_cast<Eigen::Index>(keep.size());
  Eigen::MatrixXd block(p, p);
  for (Eigen::Index x = 0; x < p; ++x) {
    for (Eigen::Index y = 0; y < p; ++y) {
      block(x, y) = joint(keep[static_cast<size_t>(x)], keep[static_cast<size_t>(y)]);
    }
  }
  return block;
}

}  // namespace ctid::mimo_srivc_parts
