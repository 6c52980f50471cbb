// Frequency responses: closed forms, conjugate symmetry, and the additive response against
// its submodels and its unfactored equivalent.
#include "ctid/frequency/response.h"

#include <cmath>
#include <complex>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "support/paper_systems.h"

namespace ctid::response_test {
namespace {

using ::testing::HasSubstr;
using Complex = std::complex<double>;

TEST(LogFrequencyGrid, EndpointsAndConstantRatio) {
  const Eigen::VectorXd grid = log_frequency_grid(0.1, 1000.0, 41);
  ASSERT_EQ(grid.size(), 41);
  EXPECT_EQ(grid(0), 0.1);
  EXPECT_EQ(grid(40), 1000.0);
  for (int i = 1; i < 41; ++i) EXPECT_NEAR(grid(i) / grid(i - 1), std::pow(10.0, 0.1), 1e-13);
  try {
    log_frequency_grid(0.0, 1.0, 10);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("omega_min must be positive"));
  }
  EXPECT_THROW(log_frequency_grid(1.0, 0.5, 10), InvalidArgument);
  EXPECT_THROW(log_frequency_grid(1.0, 2.0, 1), InvalidArgument);
}

TEST(FrequencyResponse, FirstOrderWithDelayClosedForm) {
  const double time_constant = 0.5;
  const double tau = 0.2;
  const TransferFunction g(Polynomial{2.0}, Polynomial{1.0, time_constant}, tau);
  const Eigen::VectorXd omegas = log_frequency_grid(0.01, 100.0, 30);
  const Eigen::VectorXcd response = frequency_response(g, omegas);
  for (int i = 0; i < omegas.size(); ++i) {
    const double w = omegas(i);
    const Complex expected = 2.0 / Complex(1.0, w * time_constant) * std::polar(1.0, -w * tau);
    EXPECT_LT(std::abs(response(i) - expected), 1e-14 * std::abs(expected)) << w;
  }
}

TEST(FrequencyResponse, DiscreteClosedForm) {
  const DiscreteTransferFunction g = testing::open_loop_noise_filter();  // (q + 0.5)/(q - 0.85)
  const double h = g.sample_time();
  Eigen::VectorXd omegas(4);
  omegas << 0.0, 1.0, 10.0, std::numbers::pi / h;
  const Eigen::VectorXcd response = frequency_response(g, omegas);
  for (int i = 0; i < 4; ++i) {
    const Complex z = std::polar(1.0, omegas(i) * h);
    const Complex expected = (z + 0.5) / (z - 0.85);
    EXPECT_LT(std::abs(response(i) - expected), 1e-14 * std::abs(expected)) << omegas(i);
  }
  EXPECT_NEAR(response(0).real(), 1.5 / 0.15, 1e-12);
  EXPECT_NEAR(response(3).real(), 0.5 / 1.85, 1e-14);  // z = -1 at Nyquist
}

TEST(FrequencyResponse, NegativeFrequencyGivesConjugate) {
  const Eigen::VectorXd omegas = log_frequency_grid(0.05, 50.0, 25);
  const AdditiveModel additive = testing::open_loop_four_modes().with_input_delay(0.15);
  const TransferFunction tf(Polynomial{1.0, -0.3, 0.02}, Polynomial{1.0, 0.7, 0.2, 0.01}, 0.1);
  const DiscreteTransferFunction dtf(Polynomial{0.1, 0.2}, Polynomial{0.3, -1.1, 1.0}, 0.05);
  const auto check = [&](const Eigen::VectorXcd& plus, const Eigen::VectorXcd& minus) {
    for (int i = 0; i < omegas.size(); ++i) {
      EXPECT_LT(std::abs(minus(i) - std::conj(plus(i))), 1e-14 * std::abs(plus(i))) << i;
    }
  };
  check(frequency_response(tf, omegas), frequency_response(tf, Eigen::VectorXd(-omegas)));
  check(frequency_response(dtf, omegas), frequency_response(dtf, Eigen::VectorXd(-omegas)));
  check(frequency_response(additive, omegas),
        frequency_response(additive, Eigen::VectorXd(-omegas)));
}

TEST(FrequencyResponse, AdditiveIsSumOfSubmodelsAndEqualsUnfactored) {
  const AdditiveModel additive = testing::open_loop_four_modes().with_input_delay(0.1);
  const Eigen::VectorXd omegas = log_frequency_grid(0.01, 100.0, 200);
  const Eigen::VectorXcd response = frequency_response(additive, omegas);
  const Eigen::MatrixXcd parts = submodel_frequency_responses(additive, omegas);
  const TransferFunction unfactored = additive.to_transfer_function();
  const Eigen::VectorXcd unfactored_response = frequency_response(unfactored, omegas);
  for (int i = 0; i < omegas.size(); ++i) {
    const double w = omegas(i);
    // Sum of the submodels evaluated independently, from their modal form.
    Complex sum = 0.0;
    for (int k = 0; k < additive.size(); ++k) {
      const Submodel& s = additive[k];
      sum += s.b[0] / (1.0 + s.a[1] * Complex(0.0, w) + s.a[2] * Complex(-w * w, 0.0));
    }
    sum *= std::polar(1.0, -w * 0.1);
    EXPECT_LT(std::abs(response(i) - sum), 1e-13 * std::abs(sum)) << w;
    EXPECT_LT(std::abs(parts.row(i).sum() * std::polar(1.0, -w * 0.1) - sum), 1e-13 * std::abs(sum))
        << w;
    EXPECT_LT(std::abs(unfactored_response(i) - sum), 1e-10 * std::abs(sum)) << w;
    EXPECT_LT(std::abs(additive.frequency_response(w) - sum), 1e-12 * std::abs(sum)) << w;
  }
}

TEST(FrequencyResponse, RejectsNonFiniteFrequency) {
  Eigen::VectorXd omegas(3);
  omegas << 1.0, std::nan(""), 2.0;
  try {
    frequency_response(TransferFunction(Polynomial{1.0}, Polynomial{1.0, 1.0}), omegas);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("omega[1]"));
  }
}

}  // namespace
}  // namespace ctid::response_test
