// The modes of a shared-pole MIMO model, in estimation (decision 0045): frequency, damping,
// shape, participation and standard errors from the parameter layout's covariance, and the MAC.
#include "ctid/estimation/mimo_modes.h"

#include <cmath>
#include <complex>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/core/mimo_model.h"

namespace ctid::mimo_modes_test {
namespace {

// One mode (w_n = 2 rad/s, zeta = 0.05) seen by two outputs from one input with constant
// numerators 3 and -4, and a first-order submodel that is not a mode.
MimoAdditiveModel one_mode_model() {
  const double w = 2.0;
  const double zeta = 0.05;
  MimoSubmodel mode{Polynomial({1.0, 2.0 * zeta / w, 1.0 / (w * w)}),
                    {Polynomial({3.0}), Polynomial({-4.0})}};
  MimoSubmodel real{Polynomial({1.0, 0.5}), {Polynomial({1.0}), Polynomial({1.0})}};
  return MimoAdditiveModel(1, 2, {mode, real});
}

TEST(MimoModes, FrequencyDampingAndShapeOfTheResidue) {
  const std::vector<MimoMode> modes =
      mimo_modes(one_mode_model(), {SubmodelOrder{2, 0}, SubmodelOrder{1, 0}});
  ASSERT_EQ(modes.size(), 1U);  // the first-order submodel is no mode
  const MimoMode& m = modes[0];
  EXPECT_EQ(m.submodel, 0);
  EXPECT_NEAR(m.natural_frequency, 2.0, 1e-14);
  EXPECT_NEAR(m.damping_ratio, 0.05, 1e-14);
  // The residue is (3, -4) / A'(p): the shape is its direction, unit length, largest entry
  // real and positive; a rank-one residue is all shape.
  ASSERT_EQ(m.shape.size(), 2);
  EXPECT_NEAR(m.shape(0).real(), -0.6, 1e-12);
  EXPECT_NEAR(m.shape(1).real(), 0.8, 1e-12);
  EXPECT_NEAR(m.shape.imag().norm(), 0.0, 1e-12);
  EXPECT_NEAR(m.rank_one_share, 1.0, 1e-12);
  // Without a covariance the standard errors are NaN.
  EXPECT_TRUE(std::isnan(m.natural_frequency_se));
  EXPECT_TRUE(std::isnan(m.shape_se_real(0)));
  EXPECT_NEAR(modal_assurance(m.shape, Eigen::Vector2cd(3.0, -4.0)), 1.0, 1e-12);
  EXPECT_NEAR(modal_assurance(m.shape, Eigen::Vector2cd(4.0, 3.0)), 0.0, 1e-12);
}

// Standard errors by the delta method: with variance v on a_2 alone, se(w_n) is
// |d w_n / d a_2| sqrt(v) = 0.5 a_2^(-3/2) sqrt(v).
TEST(MimoModes, StandardErrorsFromTheLayoutsCovariance) {
  // Layout: a_11, a_12, a_21, then per output the numerators b (submodel 1, then 2).
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(7, 7);
  covariance(1, 1) = 1e-6;
  const std::vector<MimoMode> modes =
      mimo_modes(one_mode_model(), {SubmodelOrder{2, 0}, SubmodelOrder{1, 0}}, covariance);
  ASSERT_EQ(modes.size(), 1U);
  const double a2 = 0.25;
  EXPECT_NEAR(modes[0].natural_frequency_se, 0.5 * std::pow(a2, -1.5) * 1e-3, 1e-12);
  EXPECT_TRUE(std::isfinite(modes[0].damping_ratio_se));
  EXPECT_THAT(
      [&] {
        mimo_modes(one_mode_model(), {SubmodelOrder{2, 0}});
      },
      ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("1 orders")));
}

}  // namespace
}  // namespace ctid::mimo_modes_test
