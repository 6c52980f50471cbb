#include "ctid/estimation/prediction.h"

#include <algorithm>

#include "ctid/core/error.h"
#include "ctid/estimation/validation.h"
#include "estimation/internal/difference_equation.h"

namespace ctid {

PredictionReport predict_ahead(const AdditiveModel& model, const ArmaModel& noise,
                               const SampledData& data, int horizon) {
  const Eigen::Index n = data.size();
  require(horizon >= 1 && horizon < n, "predict_ahead: the horizon ", horizon,
          " must be at least 1 and below the record's ", n, " samples");
  require(noise.ar.size() >= 1 && noise.ma.size() >= 1 && noise.ar(0) == 1.0 &&
              noise.ma(0) == 1.0 && noise.ar.allFinite() && noise.ma.allFinite(),
          "predict_ahead: the noise model's D and C must be finite and start with 1");
  const Eigen::VectorXd simulated =
      model_output(model, data.input(), data.sample_time(), data.input_hold());
  const Eigen::VectorXd xi = data.output() - simulated;
  // H_k: the first k terms of C/D's impulse response.
  Eigen::VectorXd impulse = Eigen::VectorXd::Zero(horizon);
  impulse(0) = 1.0;
  const Eigen::VectorXd h = internal::filter_from_rest(noise.ma, noise.ar, impulse);
  // H_k D, a polynomial in q^-1 of degree k - 1 + p.
  Eigen::VectorXd hd = Eigen::VectorXd::Zero(horizon + noise.ar.size() - 1);
  for (int i = 0; i < horizon; ++i) hd.segment(i, noise.ar.size()) += h(i) * noise.ar;
  PredictionReport report;
  report.horizon = horizon;
  report.prediction = simulated + xi - internal::filter_from_rest(hd, noise.ma, xi);
  const Eigen::VectorXd error = data.output() - report.prediction;
  report.mean_squared_error = error.squaredNorm() / static_cast<double>(n);
  report.fit_percent = fit_percent(data.output(), report.prediction);
  report.simulation_fit_percent = fit_percent(data.output(), simulated);
  return report;
}

}  // namespace ctid
