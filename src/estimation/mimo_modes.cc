// The modes of a shared-pole MIMO model (mimo_modes.h): each second-order submodel's residue
// matrix, its principal shape and participation, delta-method standard errors, and the modal
// assurance criterion. Written once for mimo_srivc and frf_matrix_fit (decision 0045).
#include "ctid/estimation/mimo_modes.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <utility>

#include <Eigen/Dense>
#include <Eigen/SVD>

#include "ctid/core/error.h"
#include "estimation/internal/mimo_layout.h"
#include "estimation/internal/mimo_modes.h"

namespace ctid::internal {

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

std::complex<double> upper_pole(double a1, double a2) {
  const std::complex<double> pole =
      (-a1 + std::sqrt(std::complex<double>(a1 * a1 - 4.0 * a2))) / (2.0 * a2);
  return pole.imag() < 0.0 ? std::conj(pole) : pole;
}

namespace {

// Residue matrix of submodel i (second order) at its upper pole, from its denominator
// coefficients and per-channel numerator coefficients (numerators[j * inputs + k]).
Eigen::MatrixXcd residue_matrix(const MimoLayout& layout, double a1, double a2,
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

std::vector<MimoMode> modes_of(const MimoLayout& layout, const MimoAdditiveModel& model,
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

}  // namespace ctid::internal

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
  const internal::MimoLayout layout(orders, model.inputs(), model.outputs(),
                                    model.has_direct_term());
  require(covariance.size() == 0 ||
              (covariance.rows() == covariance.cols() &&
               covariance.rows() == layout.a_count + layout.outputs * layout.u_count),
          "mimo_modes: the covariance is ", covariance.rows(), " x ", covariance.cols(),
          "; the model has ", layout.a_count + layout.outputs * layout.u_count, " parameters");
  return internal::modes_of(layout, model, covariance);
}

}  // namespace ctid
