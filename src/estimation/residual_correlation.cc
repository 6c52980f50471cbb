#include "ctid/estimation/residual_correlation.h"

#include <cmath>
#include <cstdlib>

#include "ctid/core/error.h"

namespace ctid {

ResidualCorrelations residual_correlations(const Eigen::VectorXd& residual,
                                           const Eigen::VectorXd& input, int max_lag) {
  const Eigen::Index n = residual.size();
  require(input.size() == n, "residual_correlations: the residual has ", n,
          " samples but the input has ", input.size());
  require(max_lag >= 1 && max_lag <= n - 1, "residual_correlations: max_lag = ", max_lag,
          " must lie in [1, ", n - 1, "] for ", n, " samples");
  const Eigen::VectorXd c = residual.array() - residual.mean();
  const Eigen::VectorXd u = input.array() - input.mean();
  const double c0 = c.squaredNorm();
  const double cross_scale = std::sqrt(c0 * u.squaredNorm());
  ResidualCorrelations r;
  r.autocorrelation = Eigen::VectorXd::Zero(max_lag + 1);
  r.cross_correlation = Eigen::VectorXd::Zero(2 * max_lag + 1);
  if (c0 > 0.0) r.autocorrelation(0) = 1.0;
  for (int k = 1; k <= max_lag && c0 > 0.0; ++k) {
    r.autocorrelation(k) = c.head(n - k).dot(c.tail(n - k)) / c0;
  }
  for (int k = -max_lag; k <= max_lag && cross_scale > 0.0; ++k) {
    const Eigen::Index m = n - std::abs(k);
    const double sum = k >= 0 ? c.tail(m).dot(u.head(m)) : c.head(m).dot(u.tail(m));
    r.cross_correlation(k + max_lag) = sum / cross_scale;
  }
  return r;
}

}  // namespace ctid
