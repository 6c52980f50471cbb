// Starts from the data alone (initialization.h) on lightly damped modes, where a start from
// the resonance peaks of the record's FRF is what reaches the truth: the FRF start places
// every mode near its natural frequency, and the refined IV iteration started from the
// automatic choice converges to the exact model on noise-free data.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/identification/identification.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/simulation/excitation.h"
#include "ctid/simulation/simulate.h"

namespace ctid::initialization_test {
namespace {

using ::testing::HasSubstr;

constexpr double kH = 0.01;
constexpr int kN = 8192;

// theta = [a1, a2, b0] of a mode with natural frequency hz, damping zeta and static gain.
Eigen::VectorXd mode(double hz, double zeta, double gain) {
  const double w = 2.0 * M_PI * hz;
  Eigen::VectorXd theta(3);
  theta << 2.0 * zeta / w, 1.0 / (w * w), gain;
  return theta;
}

// Three lightly damped modes (zeta 2e-3 .. 5e-3) inside the band of the input.
AdditiveModel lightly_damped() {
  Eigen::VectorXd beta(9);
  beta << mode(1.5, 5e-3, 1.0), mode(4.0, 3e-3, 0.3), mode(11.0, 2e-3, 0.1);
  return AdditiveModel::from_parameters(std::vector<SubmodelOrder>(3, SubmodelOrder{2, 0, 0}),
                                        beta);
}

SampledData noise_free(const AdditiveModel& g, std::uint64_t seed) {
  const Eigen::VectorXd u = white_noise(kN, 1.0, seed);
  return SampledData(kH, u, simulate(g, u, kH));
}

std::vector<double> natural_frequencies_hz(const TransferFunction& g) {
  std::vector<double> hz;
  const Eigen::VectorXcd poles = g.poles();
  for (Eigen::Index i = 0; i < poles.size(); ++i) {
    if (poles(i).imag() > 0.0) hz.push_back(std::abs(poles(i)) / (2.0 * M_PI));
  }
  std::sort(hz.begin(), hz.end());
  return hz;
}

TEST(FrfPeakStart, PlacesEveryLightlyDampedModeNearItsNaturalFrequency) {
  for (std::uint64_t seed : {1U, 2U, 3U}) {
    const std::optional<TransferFunction> start =
        frf_peak_start(noise_free(lightly_damped(), seed), SubmodelOrder{6, 4, 0});
    ASSERT_TRUE(start.has_value()) << "seed " << seed;
    const std::vector<double> hz = natural_frequencies_hz(*start);
    ASSERT_EQ(hz.size(), 3U) << "seed " << seed;
    // Within the Welch FRF's resolution, 1 / (1024 h) ~ 0.1 Hz.
    EXPECT_NEAR(hz[0], 1.5, 0.1) << "seed " << seed;
    EXPECT_NEAR(hz[1], 4.0, 0.1) << "seed " << seed;
    EXPECT_NEAR(hz[2], 11.0, 0.1) << "seed " << seed;
  }
}

TEST(FrfPeakStart, IsNoneWhenTheFrfHasTooFewPeaks) {
  const AdditiveModel first_order({Submodel{Polynomial{1.0, 0.2}, Polynomial{1.0}, 0}});
  const SampledData data = noise_free(first_order, 4);
  EXPECT_FALSE(frf_peak_start(data, SubmodelOrder{2, 0, 0}).has_value());
  InitializationOptions options;
  options.method = StartMethod::frf;
  EXPECT_THAT(
      [&] {
        initial_transfer_function(data, SubmodelOrder{2, 0, 0}, options);
      },
      ::testing::ThrowsMessage<InvalidArgument>(
          HasSubstr("fewer resonance peaks than the 1 pole pairs")));
  // The other candidates still give a start. (Two poles on first-order data: some SRIVC
  // iterate loses A's leading coefficient; the engine must treat it as a failed step, which
  // the sanitizer build checks, not read past its filters.)
  options.method = StartMethod::automatic;
  EXPECT_NO_THROW(initial_transfer_function(data, SubmodelOrder{2, 0, 0}, options));
}

TEST(AutomaticStart, ReachesTheExactLightlyDampedModelFromTheDataAlone) {
  const AdditiveModel truth = lightly_damped();
  for (StartMethod method : {StartMethod::automatic, StartMethod::frf}) {
    for (std::uint64_t seed : {5U, 6U}) {
      IdentificationOptions options;
      options.refined_iv.start = method;
      options.refined_iv.compute_covariance = false;
      const IdentificationResult r =
          identify(noise_free(truth, seed), ModelStructure::modes(3), options);
      const std::string where = std::string(enum_name(method)) + ", seed " + std::to_string(seed);
      ASSERT_TRUE(r.estimate.converged()) << where << ": " << r.estimate.brief_report();
      const std::vector<double> hz = natural_frequencies_hz(r.estimate.transfer_function);
      ASSERT_EQ(hz.size(), 3U) << where;
      EXPECT_NEAR(hz[0], 1.5, 1.5e-7) << where;
      EXPECT_NEAR(hz[1], 4.0, 4e-7) << where;
      EXPECT_NEAR(hz[2], 11.0, 1.1e-6) << where;
    }
  }
}

TEST(AutomaticStart, TheAdditiveStartFromItsScreenedStartIsTheOneFromTheData) {
  // additive_model_from_start splits initial_additive_model after its screening, for callers
  // that fit from one screened start in two structures: bit for bit the same start, on a
  // record short enough to be screened whole and on one screened on its first part.
  const AdditiveModel truth = lightly_damped();
  const std::vector<SubmodelOrder> orders = truth.orders();
  for (int samples : {4000, 24000}) {
    const Eigen::VectorXd u = white_noise(samples, 1.0, 3);
    Eigen::VectorXd y = simulate(truth, u, 0.01) + white_noise(samples, 0.05, 4);
    const SampledData data(0.01, u, y);
    InitializationOptions options;
    options.screening_samples = 4000;
    const TransferFunction g = initial_transfer_function(data, unfactored_order(orders), options);
    EXPECT_EQ(additive_model_from_start(g, data, orders, options).parameters(),
              initial_additive_model(data, orders, options).parameters())
        << samples << " samples";
  }
}

TEST(AutomaticStart, ScreeningLengthIsTheFirstPartOfALongRecord) {
  InitializationOptions options;
  EXPECT_EQ(options.screening_length(10000), 10000);      // not longer: the whole record
  EXPECT_EQ(options.screening_length(10001), 10000);      // the first screening_samples
  EXPECT_EQ(options.screening_length(10000000), 312500);  // at least N / 32
  options.screening_samples = 0;
  EXPECT_EQ(options.screening_length(10000000), 10000000);  // 0: always the whole record
  options.screening_samples = 1;
  EXPECT_EQ(options.screening_length(1000), 100);  // never fewer than 100 samples
  options.screening_samples = -1;
  EXPECT_THAT([&] { options.validate(); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("screening_samples")));
}

TEST(AutomaticStart, ScreenedOnAPieceTheFitReachesTheWholeRecordsStationaryPoint) {
  // Two modes and output noise, 24 000 samples: the start screened on the first 4 000 is not
  // the one found on the whole record, but the fit it starts ends where the whole record's
  // start leads (the screening chooses the basin; the fit uses every sample).
  Eigen::VectorXd beta(6);
  beta << mode(2.0, 0.02, 1.0), mode(7.0, 0.01, 0.2);
  const AdditiveModel truth =
      AdditiveModel::from_parameters(std::vector<SubmodelOrder>(2, SubmodelOrder{2, 0, 0}), beta);
  const int n = 24000;
  const Eigen::VectorXd u = white_noise(n, 1.0, 21);
  const SampledData data(kH, u, simulate(truth, u, kH) + white_noise(n, 0.05, 22));
  const std::vector<SubmodelOrder> orders(2, SubmodelOrder{2, 0, 0});
  std::vector<Eigen::VectorXd> starts;
  std::vector<Eigen::VectorXd> fits;
  for (const int screening : {4000, 0}) {
    InitializationOptions init;
    init.screening_samples = screening;
    starts.push_back(initial_additive_model(data, orders, init).parameters());
    IdentificationOptions options;
    options.refined_iv.start_screening_samples = screening;
    options.refined_iv.compute_covariance = false;
    const IdentificationResult r = identify(data, ModelStructure::modes(2), options);
    ASSERT_TRUE(r.estimate.converged()) << screening << ": " << r.estimate.brief_report();
    Eigen::VectorXd theta = r.estimate.parameters;
    if (theta(1) < theta(4)) {  // slower mode first, whatever order the start gave
      theta.head(3).swap(theta.tail(3));
    }
    fits.push_back(theta);
  }
  EXPECT_GT((starts[0] - starts[1]).norm(), 1e-6 * starts[1].norm());
  for (Eigen::Index k = 0; k < 6; ++k) {
    EXPECT_NEAR(fits[0](k), fits[1](k), 1e-8 * std::abs(fits[1](k))) << "parameter " << k;
  }
}

}  // namespace
}  // namespace ctid::initialization_test
