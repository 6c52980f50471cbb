// sampled_frequency_response (frequency/response.h) against the time domain: a periodic
// multisine run through the exact ZOH simulation (ctid::simulate) or the exact FOH response
// (model_output), its last period's DFT ratio Y/U at the excited lines. Lives with the
// refined IV tests because it needs both the frequency and the estimation layers.
#include <cmath>
#include <complex>

#include <unsupported/Eigen/FFT>

#include <gtest/gtest.h>

#include "ctid/estimation/validation.h"
#include "ctid/frequency/response.h"
#include "ctid/simulation/simulate.h"

namespace ctid::sampled_response_test {
namespace {

TEST(SampledFrequencyResponse, EqualsTheSteadyStateRatioOfSimulatedSamples) {
  const double h = 0.1;
  const int period = 256;
  const int periods = 40;  // the transient (slowest time constant 2 s) dies out first
  // A mode and a biproper real pole, with a delay of 2.3 samples.
  const AdditiveModel g({Submodel{Polynomial{1.0, 0.4, 0.16}, Polynomial{1.5}, 0},
                         Submodel{Polynomial{1.0, 2.0}, Polynomial{0.5, 0.3}, 0}},
                        2.3 * h);
  Eigen::VectorXd u(period * periods);
  const int lines[] = {3, 11, 29, 60, 101};
  for (int k = 0; k < u.size(); ++k) {
    u(k) = 0.0;
    for (int l : lines) u(k) += std::cos(2.0 * M_PI * l * k / period + 0.3 * l);
  }
  Eigen::VectorXd omegas(5);
  for (int i = 0; i < 5; ++i) omegas(i) = 2.0 * M_PI * lines[i] / (period * h);
  for (Hold hold : {Hold::zero_order_hold, Hold::first_order_hold}) {
    const Eigen::VectorXd y =
        hold == Hold::zero_order_hold ? simulate(g, u, h) : model_output(g, u, h, hold);
    Eigen::FFT<double> fft;
    Eigen::VectorXcd uf;
    Eigen::VectorXcd yf;
    fft.fwd(uf, Eigen::VectorXd(u.tail(period)));
    fft.fwd(yf, Eigen::VectorXd(y.tail(period)));
    const Eigen::VectorXcd response = sampled_frequency_response(g, omegas, h, hold);
    for (int i = 0; i < 5; ++i) {
      // The last period starts at sample (periods - 1) period: the DFT's phase reference.
      const std::complex<double> measured = yf(lines[i]) / uf(lines[i]);
      EXPECT_LT(std::abs(response(i) - measured), 1e-9 * std::abs(measured))
          << (hold == Hold::zero_order_hold ? "zoh" : "foh") << ", line " << lines[i];
    }
  }
  // The ZOH and FOH responses differ (the hold matters), and at low frequency both approach
  // G(j omega) with its delay.
  const Eigen::VectorXd low = (Eigen::VectorXd(1) << 0.01).finished();
  const std::complex<double> ct = frequency_response(g, low)(0);
  EXPECT_LT(std::abs(sampled_frequency_response(g, low, h, Hold::first_order_hold)(0) - ct),
            1e-3 * std::abs(ct));
  EXPECT_GT(std::abs(sampled_frequency_response(g, omegas, h, Hold::zero_order_hold)(3) -
                     sampled_frequency_response(g, omegas, h, Hold::first_order_hold)(3)),
            1e-2);
}

}  // namespace
}  // namespace ctid::sampled_response_test
