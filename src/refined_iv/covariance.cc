// Sandwich covariance of IV estimates with an AR noise model, and delta-method modal errors.
#include "ctid/refined_iv/covariance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <Eigen/Dense>

#include "core/internal/finite_transfer_function.h"
#include "ctid/core/error.h"
#include "estimation/internal/scaled_least_squares.h"
#include "refined_iv/internal/covariance_sums.h"

namespace ctid {

AutoregressiveModel fit_autoregressive(const Eigen::VectorXd& x, int max_order) {
  const Eigen::Index n = x.size();
  require(n >= 2, "fit_autoregressive: needs at least 2 samples, got ", n);
  require(max_order >= 0, "fit_autoregressive: max_order is ", max_order, "; it must be >= 0");
  const int top = static_cast<int>(std::min<Eigen::Index>(max_order, n / 4));
  const double mean = x.mean();
  const Eigen::VectorXd c = x.array() - mean;
  Eigen::VectorXd r(top + 1);
  for (int k = 0; k <= top; ++k) r(k) = c.head(n - k).dot(c.tail(n - k)) / static_cast<double>(n);
  AutoregressiveModel best;
  best.coefficients = Eigen::VectorXd::Ones(1);
  best.innovation_variance = r(0);
  if (!(r(0) > 0.0)) return best;
  double best_aic = static_cast<double>(n) * std::log(r(0));
  Eigen::VectorXd a = Eigen::VectorXd::Zero(top + 1);
  a(0) = 1.0;
  double err = r(0);
  for (int k = 1; k <= top; ++k) {
    double acc = r(k);
    for (int j = 1; j < k; ++j) acc += a(j) * r(k - j);
    const double reflection = -acc / err;
    const Eigen::VectorXd previous = a;
    for (int j = 1; j < k; ++j) a(j) = previous(j) + reflection * previous(k - j);
    a(k) = reflection;
    err *= 1.0 - reflection * reflection;
    if (!(err > 0.0)) break;
    const double aic = static_cast<double>(n) * std::log(err) + 2.0 * k;
    if (aic < best_aic) {
      best_aic = aic;
      best.coefficients = a.head(k + 1);
      best.innovation_variance = err;
    }
  }
  return best;
}

Eigen::MatrixXd adjoint_ar_filter(const Eigen::MatrixXd& x, const AutoregressiveModel& ar) {
  // x~_s = sum_j h_j x_{s+j}, h the impulse response of 1/A: run 1/A backwards in time.
  // Time runs along the columns of g (p x N) so each step touches contiguous memory.
  const Eigen::Index n = x.rows();
  Eigen::MatrixXd g = x.transpose();
  const Eigen::Index order = ar.coefficients.size() - 1;
  for (Eigen::Index k = n - 2; k >= 0; --k) {
    for (Eigen::Index j = 1; j <= order && k + j < n; ++j) {
      g.col(k) -= ar.coefficients(j) * g.col(k + j);
    }
  }
  return g;
}

namespace internal {

AdjointArOuterSum::AdjointArOuterSum(const AutoregressiveModel& ar, const Eigen::VectorXd& scales)
    : alpha_(ar.coefficients.tail(ar.coefficients.size() - 1)),
      inverse_(scales.cwiseInverse()),
      sum_(Eigen::MatrixXd::Zero(scales.size(), scales.size())),
      carry_(scales.size(), std::max<Eigen::Index>(alpha_.size(), 1)) {}

void AdjointArOuterSum::add_earlier(const Eigen::Ref<const Eigen::MatrixXd>& rows) {
  constexpr Eigen::Index kBlock = 1024;
  const Eigen::Index order = alpha_.size();
  if (g_.cols() == 0) g_.resize(inverse_.size(), kBlock);
  for (Eigen::Index end = rows.rows(); end > 0;) {
    const Eigen::Index start = std::max<Eigen::Index>(0, end - kBlock);
    const Eigen::Index length = end - start;
    // Newest first within the block; g_{s+j} is in this block or, past its end, in the carry
    // (while there is a newer row at all).
    for (Eigen::Index i = length - 1; i >= 0; --i) {
      g_.col(i) = rows.row(start + i).transpose().cwiseProduct(inverse_);
      for (Eigen::Index j = 1; j <= order; ++j) {
        if (i + j < length) {
          g_.col(i) -= alpha_(j - 1) * g_.col(i + j);
        } else if (i + j - length < carried_) {
          g_.col(i) -= alpha_(j - 1) * carry_.col(i + j - length);
        } else {
          break;
        }
      }
    }
    sum_.noalias() += g_.leftCols(length) * g_.leftCols(length).transpose();
    // The carry becomes the oldest `order` values: this block's, then the older carry's.
    const Eigen::Index from_block = std::min(order, length);
    const Eigen::Index kept = std::min(order - from_block, carried_);
    if (kept > 0) carry_.middleCols(from_block, kept) = carry_.leftCols(kept).eval();
    carry_.leftCols(from_block) = g_.leftCols(from_block);
    carried_ = from_block + kept;
    end = start;
  }
}

Eigen::MatrixXd covariance_from_gram(
    const Eigen::MatrixXd& gram, const Eigen::VectorXd& residual, int parameter_count,
    NoiseAssumption noise, int max_ar_order,
    const std::function<Eigen::MatrixXd(const AutoregressiveModel& ar,
                                        const Eigen::VectorXd& scales)>& adjoint_outer_sum) {
  const Eigen::Index n = residual.size();
  require(n > parameter_count, "instrumental_variable_covariance: ", n, " samples are too few for ",
          parameter_count, " parameters");
  // Columns scaled to unit norm (column_scales' rule) so that the inverse is formed on a
  // well-conditioned matrix; the scaling is applied to the q x q products.
  const Eigen::VectorXd s = scales_from_squared_norms(gram.diagonal());
  const Eigen::MatrixXd r = s.cwiseInverse().asDiagonal() * gram * s.cwiseInverse().asDiagonal();
  const Eigen::MatrixXd r_inv = r.completeOrthogonalDecomposition().pseudoInverse();
  Eigen::MatrixXd middle_inv;
  if (noise == NoiseAssumption::white) {
    const double sigma2 = residual.squaredNorm() / static_cast<double>(n - parameter_count);
    middle_inv = sigma2 * r_inv;
  } else {
    const AutoregressiveModel ar = fit_autoregressive(residual, max_ar_order);
    const double e2 =
        ar.innovation_variance * static_cast<double>(n) / static_cast<double>(n - parameter_count);
    const Eigen::MatrixXd q = e2 * adjoint_outer_sum(ar, s);
    middle_inv = r_inv * q * r_inv;
  }
  return s.cwiseInverse().asDiagonal() * middle_inv * s.cwiseInverse().asDiagonal();
}

}  // namespace internal

Eigen::MatrixXd instrumental_variable_covariance(const Eigen::MatrixXd& psi,
                                                 const Eigen::VectorXd& residual,
                                                 int parameter_count, NoiseAssumption noise,
                                                 int max_ar_order) {
  require(residual.size() == psi.rows(), "instrumental_variable_covariance: residual has ",
          residual.size(), " samples, psi has ", psi.rows());
  return internal::covariance_from_gram(
      psi.transpose() * psi, residual, parameter_count, noise, max_ar_order,
      [&](const AutoregressiveModel& ar, const Eigen::VectorXd& scales) {
        internal::AdjointArOuterSum sum(ar, scales);
        sum.add_earlier(psi);
        return sum.sum();
      });
}

namespace {

// (natural frequency, damping, gain) of every second-order mode, in submodel order.
std::vector<std::pair<int, ModalParameters>> modes_of(const AdditiveModel& model) {
  std::vector<std::pair<int, ModalParameters>> out;
  for (int i = 0; i < model.size(); ++i) {
    if (const auto m = model.modal_parameters(i)) out.emplace_back(i, *m);
  }
  return out;
}

ModalParameters nan_modal() {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return {nan, nan, nan};
}

}  // namespace

std::vector<ModalEstimate> modal_estimates(const AdditiveModel& model,
                                           const Eigen::MatrixXd& covariance, bool unfactored) {
  std::vector<ModalEstimate> out;
  const Eigen::VectorXd theta = model.parameters();
  const bool have_cov = covariance.rows() == theta.size() && covariance.cols() == theta.size();
  if (!unfactored) {
    std::vector<int> offset;
    int at = 0;
    for (const SubmodelOrder& o : model.orders()) {
      offset.push_back(at);
      at += o.n + o.m + 1;
    }
    for (const auto& [i, m] : modes_of(model)) {
      ModalEstimate e{i, m, nan_modal()};
      if (have_cov) {
        const int o = offset[static_cast<size_t>(i)];
        const double a1 = theta(o);
        const double a2 = theta(o + 1);
        // w = a2^-1/2, zeta = a1 / (2 sqrt(a2)), gain = b0.
        Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
        j(0, 1) = -0.5 * std::pow(a2, -1.5);
        j(1, 0) = 0.5 / std::sqrt(a2);
        j(1, 1) = -0.25 * a1 * std::pow(a2, -1.5);
        j(2, 2) = 1.0;
        const Eigen::Matrix3d c = j * covariance.block(o, o, 3, 3) * j.transpose();
        e.standard_error = {std::sqrt(c(0, 0)), std::sqrt(c(1, 1)), std::sqrt(c(2, 2))};
      }
      out.push_back(e);
    }
    return out;
  }
  // Unfactored: modes of the partial-fraction view, Jacobian by central differences. None
  // where the view has no split (e.g. a repeated pole).
  auto view_modes =
      [&](const Eigen::VectorXd& t) -> std::optional<std::vector<std::pair<int, ModalParameters>>> {
    if (!t.allFinite()) return std::nullopt;
    const std::optional<TransferFunction> g =
        internal::transfer_function_if_finite(AdditiveModel::from_parameters(model.orders(), t));
    const std::optional<AdditiveModel> view =
        g ? AdditiveModel::split_transfer_function(*g) : std::nullopt;
    if (!view) return std::nullopt;
    return modes_of(*view);
  };
  const std::optional<std::vector<std::pair<int, ModalParameters>>> base_or = view_modes(theta);
  if (!base_or) return out;
  const std::vector<std::pair<int, ModalParameters>>& base = *base_or;
  const Eigen::Index p = theta.size();
  const Eigen::Index q = static_cast<Eigen::Index>(3 * base.size());
  Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(q, p);
  bool ok = have_cov;
  for (Eigen::Index k = 0; ok && k < p; ++k) {
    const double step = 1e-6 * std::max(std::abs(theta(k)), 1e-6);
    Eigen::VectorXd plus = theta;
    Eigen::VectorXd minus = theta;
    plus(k) += step;
    minus(k) -= step;
    const auto mp_or = view_modes(plus);
    const auto mm_or = mp_or ? view_modes(minus) : std::nullopt;
    if (!mp_or || !mm_or) {
      ok = false;
      continue;
    }
    const auto& mp = *mp_or;
    const auto& mm = *mm_or;
    if (mp.size() != base.size() || mm.size() != base.size()) {
      ok = false;
      break;
    }
    for (size_t r = 0; r < base.size(); ++r) {
      const auto idx = static_cast<Eigen::Index>(3 * r);
      jac(idx, k) = (mp[r].second.natural_frequency - mm[r].second.natural_frequency) / (2 * step);
      jac(idx + 1, k) = (mp[r].second.damping_ratio - mm[r].second.damping_ratio) / (2 * step);
      jac(idx + 2, k) = (mp[r].second.gain - mm[r].second.gain) / (2 * step);
    }
  }
  Eigen::MatrixXd c;
  if (ok) c = jac * covariance * jac.transpose();
  for (size_t r = 0; r < base.size(); ++r) {
    ModalEstimate e{base[r].first, base[r].second, nan_modal()};
    if (ok) {
      const auto idx = static_cast<Eigen::Index>(3 * r);
      e.standard_error = {std::sqrt(c(idx, idx)), std::sqrt(c(idx + 1, idx + 1)),
                          std::sqrt(c(idx + 2, idx + 2))};
    }
    out.push_back(e);
  }
  return out;
}

}  // namespace ctid
