// Judging a continuous-time model against sampled data, and checking data against the
// assumptions of the refined IV estimators (González et al., Assumptions 1 and 4): the
// model's exact ZOH response, fit %, persistency of excitation and the sampling-rate rule.
#pragma once

#include <string_view>
#include <tuple>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"

namespace ctid {

/// Exact sampled response (from rest) of the model to the ZOH input u with period h. The
/// model's input delay must be a whole number of samples (within 1e-9). Integrators and a
/// biproper submodel are allowed.
Eigen::VectorXd model_output(const AdditiveModel& model, const Eigen::VectorXd& input,
                             double sample_time);

/// 100 (1 - ||y - y_model|| / ||y - mean(y)||); 100 is a perfect fit. Sizes must agree.
double fit_percent(const Eigen::VectorXd& measured, const Eigen::VectorXd& modelled);

/// Residual statistics of a model on data (for `ctid validate`). Correlations are normalised
/// (means removed): r_ee(k) = sum e(t+k) e(t) / sum e(t)^2 at lags 1..max_lag, and
/// r_eu(k) = sum e(t+k) u(t) / sqrt(sum e^2 sum u^2) at lags -max_lag..max_lag; both are judged
/// against the 99 % band 2.58/sqrt(N) of a white residual independent of the input.
struct ValidationReport {
  double fit_percent = 0.0;
  double mean_squared_error = 0.0;
  double residual_mean = 0.0;
  double residual_std = 0.0;
  int max_lag = 0;                           ///< lags used: min(max_lag asked, N - 1)
  Eigen::VectorXd residual_autocorrelation;  ///< r_ee(1..max_lag)
  Eigen::VectorXd cross_correlation;         ///< r_eu(-max_lag..max_lag)
  double max_residual_autocorrelation = 0.0;
  double max_cross_correlation = 0.0;
  double whiteness_bound = 0.0;  ///< 2.58/sqrt(N)
  bool residual_white() const { return max_residual_autocorrelation <= whiteness_bound; }
  bool residual_uncorrelated_with_input() const { return max_cross_correlation <= whiteness_bound; }

  static constexpr std::string_view type_name = "ValidationReport";
  static constexpr auto fields() {
    using S = ValidationReport;
    return std::tuple{
        field("fit_percent", &S::fit_percent, "100 (1 - ||y - y_model|| / ||y - mean(y)||)."),
        field("mean_squared_error", &S::mean_squared_error, "Mean squared residual."),
        field("residual_mean", &S::residual_mean, "Mean of the residual."),
        field("residual_std", &S::residual_std, "Standard deviation of the residual."),
        field("max_lag", &S::max_lag, "Lags used: min(max_lag asked, N - 1)."),
        field("residual_autocorrelation", &S::residual_autocorrelation,
              "Normalised residual autocorrelation r_ee at lags 1..max_lag."),
        field("cross_correlation", &S::cross_correlation,
              "Normalised residual-input cross-correlation r_eu at lags -max_lag..max_lag."),
        field("max_residual_autocorrelation", &S::max_residual_autocorrelation,
              "Largest |r_ee| at lags 1..max_lag."),
        field("max_cross_correlation", &S::max_cross_correlation,
              "Largest |r_eu| at lags -max_lag..max_lag."),
        field("whiteness_bound", &S::whiteness_bound, "The 99 % band 2.58/sqrt(N)."),
    };
  }
};
/// max_lag >= 1; 20 by default.
ValidationReport validate_model(const AdditiveModel& model, const SampledData& data,
                                int max_lag = 20);

/// The same statistics for any model whose simulated output on `data` is `modelled` (e.g. a
/// closed loop with delayed feedback). max_lag >= 1; sizes must agree.
ValidationReport residual_report(const SampledData& data, const Eigen::VectorXd& modelled,
                                 int max_lag = 20);

/// Largest n <= max_order for which the sample matrix sum_k phi_k phi_k' of the windows
/// phi_k = [x_k, x_{k-d}, ..., x_{k-(n-1)d}] is numerically non-singular (smallest over
/// largest eigenvalue above `tolerance`) for some lag spacing d in {1, 2, 3, 4, 6, 8, 12, 16}:
/// the order of persistency of excitation seen in the record. A constant gives 1, one
/// sinusoid 2, white noise and band-limited rich signals (multisines) max_order.
int persistent_excitation_order(const Eigen::VectorXd& x, int max_order, double tolerance = 1e-9);

/// Largest |imaginary part| of the model's poles in rad/s (0 for real poles).
double largest_pole_frequency(const AdditiveModel& model);

}  // namespace ctid
