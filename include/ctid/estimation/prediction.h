// k-step-ahead prediction of a hybrid Box-Jenkins model: a continuous-time plant G and a
// discrete-time ARMA noise model H = C/D (estimation/arma.h, RIVC's result). With
// xi = y - G u, the predictor of y(t) from the data up to t - k is
//   y_hat(t | t - k) = G u(t) + (1 - H_k D / C) xi(t),
// H_k the first k terms of H's impulse response (Ljung, System Identification, 2nd ed.,
// Section 3.2): k = 1 is the one-step predictor, and as k grows it tends to the simulation
// G u. Every filter runs from rest at the first sample.
#pragma once

#include <string_view>
#include <tuple>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"
#include "ctid/estimation/arma.h"

namespace ctid {

struct PredictionReport {
  int horizon = 1;                  ///< k [samples]
  double fit_percent = 0.0;         ///< 100 (1 - ||y - y_hat|| / ||y - mean y||)
  double mean_squared_error = 0.0;  ///< mean (y - y_hat)^2
  /// The same fit of the simulation G u (the predictor as k grows), for comparison.
  double simulation_fit_percent = 0.0;
  Eigen::VectorXd prediction;  ///< y_hat(t | t - k) at every sample

  static constexpr std::string_view type_name = "PredictionReport";
  static constexpr auto fields() {
    using S = PredictionReport;
    return std::tuple{
        field("horizon", &S::horizon, "k [samples]."),
        field("fit_percent", &S::fit_percent, "100 (1 - ||y - y_hat|| / ||y - mean y||)."),
        field("mean_squared_error", &S::mean_squared_error, "Mean (y - y_hat)^2."),
        field("simulation_fit_percent", &S::simulation_fit_percent,
              "The same fit of the simulation G u."),
        field("prediction", &S::prediction, "y_hat(t | t - k) at every sample."),
    };
  }
};

/// The k-step-ahead prediction of `data`'s output by the plant `model` (input held as the
/// record says) and the noise model `noise`. Throws InvalidArgument for a horizon below 1 or
/// not shorter than the record, or a noise model whose D or C does not start with 1.
PredictionReport predict_ahead(const AdditiveModel& model, const ArmaModel& noise,
                               const SampledData& data, int horizon);

}  // namespace ctid
