#include "ctid/process_model/process_response.h"

#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"

namespace ctid::process_response_test {
namespace {

using ::testing::HasSubstr;

// P1D: K e^{-Td s} / (1 + Tp1 s), with a covariance that couples Tp1 and Td.
ProcessModelResult p1d(double k, double tp1, double td) {
  ProcessModelResult r;
  r.structure = "P1D";
  r.parameter_names = {"K", "Tp1", "Td"};
  r.parameters = Eigen::Vector3d(k, tp1, td);
  r.covariance.resize(3, 3);
  r.covariance << 4e-4, 1e-5, 0.0,  //
      1e-5, 9e-4, -3e-4,            //
      0.0, -3e-4, 2.5e-4;
  r.standard_errors = r.covariance.diagonal().cwiseSqrt();
  return r;
}

// Closed forms of a first-order step with dead time: rise time Tp1 ln 9, settling time
// Td + Tp1 ln(1 / band), DC gain K, and their delta-method errors with the correlation of Tp1
// and Td, which a covariance of the transfer function's coefficients alone would lose.
TEST(ProcessResponse, FirstOrderWithDeadTimeMatchesItsClosedForms) {
  const ProcessModelResult r = p1d(2.0, 1.5, 0.3);
  TimeResponseOptions options;
  options.final_time = 10.0;
  options.points = 1001;
  const TimeResponse response = process_time_response(r, options);
  const StepCharacteristics& c = response.characteristics;
  const Eigen::MatrixXd& P = r.covariance;
  EXPECT_NEAR(c.dc_gain.value, 2.0, 1e-12);
  EXPECT_NEAR(c.dc_gain.standard_error, std::sqrt(P(0, 0)), 1e-8);
  EXPECT_NEAR(c.rise_time.value, 1.5 * std::log(9.0), 1e-6);
  EXPECT_NEAR(c.rise_time.standard_error, std::log(9.0) * std::sqrt(P(1, 1)), 1e-5);
  const double l = std::log(1.0 / 0.02);
  EXPECT_NEAR(c.settling_time.value, 0.3 + 1.5 * l, 1e-5);
  const double settling_variance = l * l * P(1, 1) + P(2, 2) + 2.0 * l * P(1, 2);
  EXPECT_NEAR(c.settling_time.standard_error, std::sqrt(settling_variance), 1e-5);

  // y(t) = K (1 - e^{-(t - Td) / Tp1}) after the dead time: the band's gradient in closed form.
  for (const Eigen::Index k : {Eigen::Index{100}, Eigen::Index{250}, Eigen::Index{800}}) {
    const double t = response.time(k);
    const double e = std::exp(-(t - 0.3) / 1.5);
    EXPECT_NEAR(response.output(k), 2.0 * (1.0 - e), 1e-10);
    Eigen::Vector3d g(1.0 - e, -2.0 * e * (t - 0.3) / (1.5 * 1.5), -2.0 * e / 1.5);
    const double std_closed = std::sqrt(g.dot(P * g));
    EXPECT_NEAR(response.standard_deviation(k), std_closed, 1e-6 * std_closed + 1e-12) << t;
    EXPECT_NEAR(response.upper(k) - response.output(k), response.z * std_closed,
                1e-6 * response.z * std_closed + 1e-12);
  }
}

TEST(ProcessResponse, WithoutACovarianceThereIsNoBand) {
  ProcessModelResult r = p1d(1.0, 0.5, 0.0);
  r.covariance.resize(0, 0);
  const TimeResponse response = process_time_response(r);
  EXPECT_EQ(response.standard_deviation.size(), 0);
  EXPECT_NEAR(response.characteristics.dc_gain.value, 1.0, 1e-12);
  EXPECT_TRUE(std::isnan(response.characteristics.dc_gain.standard_error));
}

TEST(ProcessResponse, AResultThatDoesNotAgreeWithItsStructureIsNamed) {
  ProcessModelResult r = p1d(1.0, 0.5, 0.1);
  r.parameters = Eigen::Vector2d(1.0, 0.5);
  EXPECT_THAT([&] { (void)process_time_response(r); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("P1D has 3 parameters but the result holds 2")));
  r = p1d(1.0, 0.5, 0.1);
  r.covariance = Eigen::MatrixXd::Identity(2, 2);
  EXPECT_THAT([&] { (void)process_time_response(r); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("finite 3 x 3 matrix")));
}

}  // namespace
}  // namespace ctid::process_response_test
