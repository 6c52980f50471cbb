// The covariance and the modes of a mimo_srivc estimate: the sandwich covariance, each
// mode's residue matrix, shape and delta-method standard errors, and the modal assurance
// criterion.
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
#include "internal/mimo_layout.h"
#include "internal/mimo_srivc_parts.h"
#include "internal/refined_iv_engine.h"
#include "internal/scaled_least_squares.h"

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

namespace {

// The mode shape of a residue matrix (see MimoMode) and its share of the residue.
Eigen::VectorXcd principal_shape(const Eigen::MatrixXcd& residue, double* share = nullptr) {
  const Eigen::JacobiSVD<Eigen::MatrixXcd> svd(residue, Eigen::ComputeThinU);
  Eigen::VectorXcd shape = svd.matrixU().col(0);
  Eigen::Index largest = 0;
  shape.cwiseAbs().maxCoeff(&largest);
  if (std::abs(shape(largest)) > 0.0) shape *= std::conj(shape(largest)) / std::abs(shape(largest));
  if (share != nullptr) {
    const Eigen::VectorXd sigma = svd.singularValues();
    *share = sigma.squaredNorm() > 0.0 ? sigma(0) * sigma(0) / sigma.squaredNorm() : 1.0;
  }
  return shape;
}

}  // namespace

// Residue matrix of submodel i (second order) at its upper pole, from its denominator
// coefficients and per-channel numerator coefficients (numerators[j * inputs + k]).
// The root with a non-negative imaginary part of 1 + a1 s + a2 s^2.
std::complex<double> upper_pole(double a1, double a2) {
  const std::complex<double> pole =
      (-a1 + std::sqrt(std::complex<double>(a1 * a1 - 4.0 * a2))) / (2.0 * a2);
  return pole.imag() < 0.0 ? std::conj(pole) : pole;
}

namespace {

Eigen::MatrixXcd residue_matrix(const Layout& layout, double a1, double a2,
                                const std::vector<Eigen::VectorXd>& numerators) {
  const std::complex<double> pole = upper_pole(a1, a2);
  const std::complex<double> slope = a1 + 2.0 * a2 * pole;
  Eigen::MatrixXcd res(layout.outputs, layout.inputs);
  for (int j = 0; j < layout.outputs; ++j) {
    for (int k = 0; k < layout.inputs; ++k) {
      const Eigen::VectorXd& b = numerators[static_cast<size_t>(j * layout.inputs + k)];
      std::complex<double> value = 0.0;
      for (Eigen::Index r = b.size() - 1; r >= 0; --r) value = value * pole + b(r);
      res(j, k) = value / slope;
    }
  }
  return res;
}

}  // namespace

// Every second-order submodel as a MimoMode, with delta-method standard errors when the
// covariance is given (numerical derivatives of the shape with respect to the submodel's own
// parameters).
std::vector<MimoMode> modes_of(const Layout& layout, const MimoAdditiveModel& model,
                               const Eigen::MatrixXd& covariance) {
  std::vector<MimoMode> modes;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < layout.size(); ++i) {
    const SubmodelOrder& o = layout.orders[static_cast<size_t>(i)];
    const Polynomial& a = model[i].a;
    // A complex pair only (not one times integrators).
    if (o.n != 2 || o.integrators > 0 || !(a[1] * a[1] < 4.0 * a[2])) continue;
    std::vector<Eigen::VectorXd> numerators;
    std::vector<int> indices{layout.a_index(i, 1), layout.a_index(i, 2)};
    for (int j = 0; j < layout.outputs; ++j) {
      for (int k = 0; k < layout.inputs; ++k) {
        Eigen::VectorXd b = Eigen::VectorXd::Zero(o.m + 1);
        const Polynomial& given = model.numerator(i, j, k);
        for (int r = 0; r <= std::min(o.m, given.degree()); ++r) b(r) = given[r];
        numerators.push_back(b);
        for (int r = 0; r <= o.m; ++r)
          indices.push_back(layout.b_index(j, layout.u_column(i, k, r)));
      }
    }
    MimoMode mode;
    mode.submodel = i;
    mode.natural_frequency = 1.0 / std::sqrt(a[2]);
    mode.damping_ratio = a[1] / (2.0 * std::sqrt(a[2]));
    const auto shape_at = [&](double a1, double a2, const std::vector<Eigen::VectorXd>& b) {
      return principal_shape(residue_matrix(layout, a1, a2, b));
    };
    const Eigen::MatrixXcd res = residue_matrix(layout, a[1], a[2], numerators);
    mode.shape = principal_shape(res, &mode.rank_one_share);
    mode.participation = res.transpose() * mode.shape.conjugate();
    mode.natural_frequency_se = mode.damping_ratio_se = nan;
    mode.shape_se_real = mode.shape_se_imag = Eigen::VectorXd::Constant(layout.outputs, nan);
    if (covariance.size() > 0) {
      const Eigen::Index m = static_cast<Eigen::Index>(indices.size());
      Eigen::MatrixXd c(m, m);
      for (Eigen::Index x = 0; x < m; ++x) {
        for (Eigen::Index y = 0; y < m; ++y) c(x, y) = covariance(indices[x], indices[y]);
      }
      // w_n = a2^(-1/2), zeta = a1 / (2 sqrt(a2)).
      Eigen::RowVector2d dw(0.0, -0.5 * std::pow(a[2], -1.5));
      Eigen::RowVector2d dz(0.5 / std::sqrt(a[2]), -0.25 * a[1] * std::pow(a[2], -1.5));
      mode.natural_frequency_se = std::sqrt((dw * c.topLeftCorner(2, 2) * dw.transpose())(0));
      mode.damping_ratio_se = std::sqrt((dz * c.topLeftCorner(2, 2) * dz.transpose())(0));
      // Central differences of [Re shape; Im shape] in every one of the submodel's parameters.
      Eigen::MatrixXd jac(2 * layout.outputs, m);
      for (Eigen::Index x = 0; x < m; ++x) {
        double a1 = a[1];
        double a2 = a[2];
        std::vector<Eigen::VectorXd> b = numerators;
        double* value = nullptr;
        if (x == 0) {
          value = &a1;
        } else if (x == 1) {
          value = &a2;
        } else {
          const Eigen::Index c0 = x - 2;
          value = &b[static_cast<size_t>(c0 / (o.m + 1))](c0 % (o.m + 1));
        }
        const double step = 1e-6 * std::max(std::abs(*value), 1e-6 * std::abs(a[x == 0 ? 1 : 2]));
        const double saved = *value;
        *value = saved + step;
        const Eigen::VectorXcd plus = shape_at(a1, a2, b);
        *value = saved - step;
        const Eigen::VectorXcd minus = shape_at(a1, a2, b);
        const Eigen::VectorXcd d = (plus - minus) / (2.0 * step);
        jac.col(x) << d.real(), d.imag();
      }
      const Eigen::VectorXd var = (jac * c * jac.transpose()).diagonal();
      mode.shape_se_real = var.head(layout.outputs).cwiseMax(0.0).cwiseSqrt();
      mode.shape_se_imag = var.tail(layout.outputs).cwiseMax(0.0).cwiseSqrt();
    }
    modes.push_back(std::move(mode));
  }
  return modes;
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

namespace ctid {

double modal_assurance(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b) {
  require(a.size() == b.size(), "modal_assurance: shapes of ", a.size(), " and ", b.size(),
          " entries; they must have equal lengths");
  const double aa = a.squaredNorm();
  const double bb = b.squaredNorm();
  return aa > 0.0 && bb > 0.0 ? std::norm(a.dot(b)) / (aa * bb) : 0.0;
}

Eigen::MatrixXd modal_assurance(const std::vector<MimoMode>& a, const std::vector<MimoMode>& b) {
  Eigen::MatrixXd mac(static_cast<Eigen::Index>(a.size()), static_cast<Eigen::Index>(b.size()));
  for (size_t x = 0; x < a.size(); ++x) {
    for (size_t y = 0; y < b.size(); ++y) {
      mac(static_cast<Eigen::Index>(x), static_cast<Eigen::Index>(y)) =
          modal_assurance(a[x].shape, b[y].shape);
    }
  }
  return mac;
}

std::vector<MimoMode> mimo_modes(const MimoAdditiveModel& model,
                                 const std::vector<SubmodelOrder>& orders,
                                 const Eigen::MatrixXd& covariance) {
  require(static_cast<int>(orders.size()) == model.size(), "mimo_modes: ", orders.size(),
          " orders for a model of ", model.size(), " submodels");
  const mimo_srivc_parts::Layout layout(orders, model.inputs(), model.outputs(),
                                        model.has_direct_term());
  require(covariance.size() == 0 ||
              (covariance.rows() == covariance.cols() &&
               covariance.rows() == layout.a_count + layout.outputs * layout.u_count),
          "mimo_modes: the covariance is ", covariance.rows(), " x ", covariance.cols(),
          "; the model has ", layout.a_count + layout.outputs * layout.u_count, " parameters");
  return mimo_srivc_parts::modes_of(layout, model, covariance);
}

}  // namespace ctid
