// k-step-ahead prediction of a Box-Jenkins model (estimation/prediction.h): with the true plant
// and noise model the prediction error is H_k e, whose variance sigma^2 sum_{i<k} h_i^2 the
// seeded record matches; a white noise model predicts the simulation, and so does a long
// horizon; bad horizons and noise models are refused by name.
#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/estimation/prediction.h"
#include "ctid/estimation/validation.h"
#include "ctid/simulation/noise.h"

namespace ctid::prediction_test {
namespace {

using ::testing::HasSubstr;

constexpr double kH = 0.1;

AdditiveModel plant() {
  return AdditiveModel({{Polynomial({1.0, 0.8, 0.5}), Polynomial({1.5}), 0}});
}

// D = 1 - 0.9 q^-1, C = 1 + 0.5 q^-1, sigma_e = 0.2.
ArmaModel noise() {
  ArmaModel m;
  m.ar = Eigen::Vector2d(1.0, -0.9);
  m.ma = Eigen::Vector2d(1.0, 0.5);
  m.innovation_variance = 0.04;
  return m;
}

SampledData record(int n) {
  const Eigen::VectorXd u = white_noise(n, 1.0, 7);
  const DiscreteTransferFunction h(Polynomial({0.5, 1.0}), Polynomial({-0.9, 1.0}), kH);
  const Eigen::VectorXd v = colored_noise(h, n, 0.04, 8);
  return SampledData(kH, u, model_output(plant(), u, kH, Hold::zero_order_hold) + v);
}

TEST(PredictAhead, ErrorVarianceIsTheClosedForm) {
  const SampledData data = record(40000);
  // h_0 = 1, h_i = (0.9 + 0.5) 0.9^(i-1) for i >= 1.
  for (int k : {1, 3, 10}) {
    double sum = 1.0;
    for (int i = 1; i < k; ++i) sum += std::pow(1.4 * std::pow(0.9, i - 1), 2);
    const PredictionReport p = predict_ahead(plant(), noise(), data, k);
    EXPECT_NEAR(p.mean_squared_error / (0.04 * sum), 1.0, 0.03) << "k = " << k;
    EXPECT_GT(p.fit_percent, p.simulation_fit_percent);
  }
}

TEST(PredictAhead, AWhiteNoiseModelAndALongHorizonPredictTheSimulation) {
  const SampledData data = record(2000);
  const Eigen::VectorXd simulated = model_output(plant(), data.input(), kH, Hold::zero_order_hold);
  ArmaModel white;
  white.ar = Eigen::VectorXd::Ones(1);
  white.ma = Eigen::VectorXd::Ones(1);
  // G u + xi - xi: the simulation to rounding.
  EXPECT_LT((predict_ahead(plant(), white, data, 1).prediction - simulated).cwiseAbs().maxCoeff(),
            1e-12);
  // 0.9^400 ~ 5e-19: the noise's memory is gone.
  const PredictionReport far = predict_ahead(plant(), noise(), data, 400);
  EXPECT_LT((far.prediction - simulated).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(PredictAhead, BadHorizonsAndNoiseModelsAreNamed) {
  const SampledData data = record(100);
  EXPECT_THAT([&] { (void)predict_ahead(plant(), noise(), data, 0); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("the horizon 0")));
  EXPECT_THAT([&] { (void)predict_ahead(plant(), noise(), data, 100); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("below the record's 100")));
  ArmaModel bad = noise();
  bad.ar(0) = 2.0;
  EXPECT_THAT([&] { (void)predict_ahead(plant(), bad, data, 1); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("start with 1")));
}

}  // namespace
}  // namespace ctid::prediction_test
