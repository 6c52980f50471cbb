// The modes of a shared-pole MIMO model in the parameter layout of its estimator (mimo_layout.h),
// shared by mimo_srivc (refined_iv) and frf_matrix_fit (frf_fit). Private to the estimator
// modules (decision 0045).
#pragma once

#include <complex>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/mimo_model.h"
#include "ctid/estimation/mimo_modes.h"
#include "estimation/internal/mimo_layout.h"

namespace ctid::internal {

/// The root with a non-negative imaginary part of 1 + a1 s + a2 s^2.
std::complex<double> upper_pole(double a1, double a2);

/// Every second-order submodel (a complex pair, no integrators) of `model` as a MimoMode, with
/// delta-method standard errors when `covariance` (in `layout`'s parameter order) is not empty:
/// numerical derivatives of the shape with respect to the submodel's own parameters.
std::vector<MimoMode> modes_of(const MimoLayout& layout, const MimoAdditiveModel& model,
                               const Eigen::MatrixXd& covariance);

}  // namespace ctid::internal
