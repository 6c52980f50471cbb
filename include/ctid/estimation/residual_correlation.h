// Correlations of a model's residual, the classical whiteness and independence checks of a
// fit (Ljung, System Identification, 2nd ed., Section 16.6): after removing the means,
// r_ee(k) = sum_t e_t e_{t+k} / sum e^2 for k = 0..max_lag and
// r_eu(k) = sum_t e_{t+k} u_t / sqrt(sum e^2 sum u^2) for k = -max_lag..max_lag, so a peak of
// r_eu at k > 0 means the input leads the residual. validate_model's report holds r_ee at lags
// 1..max_lag and r_eu; the Python plots draw these.
#pragma once

#include <Eigen/Core>

namespace ctid {

struct ResidualCorrelations {
  Eigen::VectorXd autocorrelation;    ///< r_ee(0..max_lag); r_ee(0) = 1 (all 0 if e is constant)
  Eigen::VectorXd cross_correlation;  ///< r_eu(-max_lag..max_lag) (all 0 if e or u is constant)
};

/// The correlations of `residual` and `input` (the same length N, 1 <= max_lag <= N - 1);
/// throws InvalidArgument naming what does not fit.
ResidualCorrelations residual_correlations(const Eigen::VectorXd& residual,
                                           const Eigen::VectorXd& input, int max_lag);

}  // namespace ctid
