// Prints results of the C++ library for fixed inputs and seeds, in hexadecimal floating point
// ("key count v1 v2 ..." per line), so tests/test_bit_equality.py can check that the Python
// bindings return the same bits. The inputs here are mirrored in that test; keep them equal.
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/sampled_data.h"
#include "ctid/core/transfer_function.h"
#include "ctid/frequency/frf.h"
#include "ctid/frequency/response.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/srivc.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace {

void print(const std::string& key, const Eigen::VectorXd& values) {
  std::printf("%s %ld", key.c_str(), static_cast<long>(values.size()));
  for (double v : values) std::printf(" %a", v);
  std::printf("\n");
}

void print(const std::string& key, const Eigen::VectorXcd& values) {
  print(key + ".real", values.real().eval());
  print(key + ".imag", values.imag().eval());
}

}  // namespace

int main() {
  using namespace ctid;
  // A resonant second-order model sampled at 20 Hz, driven by a seeded multisine.
  const TransferFunction g(Polynomial{4.0}, Polynomial{4.0, 0.8, 1.0});
  const double h = 0.05;
  MultisineOptions ms;
  ms.period_length = 256;
  ms.sample_time = h;
  ms.max_frequency = 4.0;
  ms.periods = 4;
  ms.seed = 7;
  const Multisine u = multisine(ms);
  const Eigen::VectorXd y0 = simulate(g, u.signal, h);
  const Eigen::VectorXd noise = white_noise(static_cast<int>(y0.size()), 0.01, 99);
  const Eigen::VectorXd y = y0 + noise;
  print("multisine", u.signal);
  print("simulate", y0);
  print("white_noise", noise);

  const SampledData data(h, u.signal, y);
  PeriodicFrfOptions po;
  po.period_length = 256;
  po.transient_periods = 1;
  const Frf frf = periodic_frf(data, po);
  print("periodic_frf.response", frf.response);
  print("periodic_frf.variance", frf.variance);

  WelchOptions wo;
  wo.segment_length = 128;
  wo.overlap = 0.5;
  const Frf welch = welch_frf(data, wo);
  print("welch_frf.response", welch.response);
  print("welch_frf.coherence", welch.coherence);

  print("frequency_response", frequency_response(g, log_frequency_grid(0.1, 50.0, 40)));

  RefinedIvOptions ro;
  ro.max_iterations = 30;
  const EstimationResult fit = srivc(data, SubmodelOrder{2, 0, 0}, ro);
  print("srivc.parameters", fit.parameters);
  print("srivc.covariance",
        Eigen::Map<const Eigen::VectorXd>(fit.covariance.data(), fit.covariance.size()).eval());
  const EstimationResult additive = additive_srivc(data, {SubmodelOrder{2, 0, 0}}, ro);
  print("additive_srivc.parameters", additive.parameters);
  return 0;
}
