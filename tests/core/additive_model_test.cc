#include "ctid/core/additive_model.h"

#include <cmath>
#include <optional>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/internal/finite_transfer_function.h"
#include "ctid/core/error.h"
#include "support/paper_systems.h"

namespace ctid::additive_model_test {
namespace {

using ::testing::HasSubstr;

TEST(AdditiveModel, ParametersFollowThePapersLayout) {
  const AdditiveModel g = testing::closed_loop_two_modes();
  Eigen::VectorXd expected(6);
  expected << 0.25, 0.25, 3.0, 0.01, 0.025, 1.0;  // beta* of Section 6.2
  EXPECT_EQ(g.parameters(), expected);
  EXPECT_EQ(g.parameter_count(), 6);
  const AdditiveModel same = AdditiveModel::from_parameters(g.orders(), expected);
  EXPECT_EQ(same.parameters(), expected);
  const AdditiveModel moved = g.with_parameters(2.0 * expected);
  EXPECT_EQ(moved[1].a, Polynomial({1.0, 0.02, 0.05}));
}

TEST(AdditiveModel, ZeroLeadingParameterKeepsTheLayout) {
  const std::vector<SubmodelOrder> orders{{2, 1, 0}};
  const Eigen::Vector4d theta(0.5, 0.1, 2.0, 0.0);
  const AdditiveModel g = AdditiveModel::from_parameters(orders, theta);
  EXPECT_EQ(g.parameters(), Eigen::VectorXd(theta));
}

TEST(AdditiveModel, SumEqualsUnfactoredTransferFunction) {
  const AdditiveModel g = testing::open_loop_four_modes();
  const TransferFunction tf = g.to_transfer_function();
  EXPECT_EQ(tf.denominator().degree(), 8);
  EXPECT_EQ(tf.numerator().degree(), 6);  // max_i(m_i + sum_{j!=i} n_j)
  for (double w : {0.01, 1.0, 1.39, 3.16, 7.0, 100.0}) {
    const std::complex<double> a = g.frequency_response(w);
    EXPECT_NEAR(std::abs(a - tf.frequency_response(w)), 0.0, 1e-12 * std::abs(a)) << w;
  }
}

TEST(AdditiveModel, PartialFractionsRecoverThePapersModes) {
  const AdditiveModel g = testing::open_loop_four_modes();
  const AdditiveModel split = AdditiveModel::from_transfer_function(g.to_transfer_function());
  ASSERT_EQ(split.size(), 4);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(split[i].n(), 2);
    for (int k = 0; k <= 2; ++k) EXPECT_NEAR(split[i].a[k], g[i].a[k], 1e-9 * std::abs(g[i].a[k]));
    EXPECT_NEAR(split[i].b[0], g[i].b[0], 1e-9 * std::abs(g[i].b[0]));
    EXPECT_NEAR(split[i].b[1], 0.0, 1e-9);
  }
}

TEST(AdditiveModel, PartialFractionsWithIntegratorAndFeedthrough) {
  // 0.3696/(s (s + 2.14)) + 0.5 = (0.5 s^2 + 1.07 s + 0.3696) / (s^2 + 2.14 s).
  const TransferFunction g(Polynomial({0.3696, 1.07, 0.5}), Polynomial({0.0, 2.14, 1.0}));
  const AdditiveModel split = AdditiveModel::from_transfer_function(g);
  ASSERT_EQ(split.size(), 2);
  EXPECT_EQ(split[0].integrators, 1);
  EXPECT_TRUE(split[0].is_biproper());  // feedthrough joins the lowest-frequency submodel
  EXPECT_NEAR(split[1].a[1], 1.0 / 2.14, 1e-14);
  for (double w : {0.1, 1.0, 10.0}) {
    EXPECT_NEAR(std::abs(split.frequency_response(w) - g.frequency_response(w)), 0.0,
                1e-12 * std::abs(g.frequency_response(w)));
  }
  EXPECT_NEAR(split[0].b[0], 0.3696 / 2.14, 1e-14);
}

TEST(AdditiveModel, RepeatedPolesAreRejected) {
  const TransferFunction g(Polynomial({1.0}), Polynomial({1.0, 2.0, 1.0}));
  EXPECT_THAT([&] { AdditiveModel::from_transfer_function(g); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("repeated pole")));
}

// The split as a value (decision 0045): none, with the reason from_transfer_function throws,
// for a repeated pole, an improper or a constant model; the same model where it splits.
TEST(AdditiveModel, SplitIsAValueWhereThePolesDoNotSplit) {
  std::string why;
  EXPECT_FALSE(AdditiveModel::split_transfer_function(
                   TransferFunction(Polynomial({1.0}), Polynomial({1.0, 2.0, 1.0})), 1e-8, &why)
                   .has_value());
  EXPECT_THAT(why, HasSubstr("repeated pole"));
  EXPECT_FALSE(
      AdditiveModel::split_transfer_function(
          TransferFunction(Polynomial({1.0, 1.0, 1.0}), Polynomial({1.0, 1.0})), 1e-8, &why)
          .has_value());
  EXPECT_THAT(why, HasSubstr("improper"));
  EXPECT_FALSE(
      AdditiveModel::split_transfer_function(TransferFunction(Polynomial({2.0}), Polynomial({1.0})))
          .has_value());
  const TransferFunction g = testing::open_loop_four_modes().to_transfer_function();
  const std::optional<AdditiveModel> split = AdditiveModel::split_transfer_function(g);
  ASSERT_TRUE(split.has_value());
  EXPECT_EQ(split->parameters(), AdditiveModel::from_transfer_function(g).parameters());
  EXPECT_EQ(split->size(), AdditiveModel::from_transfer_function(g).size());
}

// A pole so close to the origin that 1 / p overflows: none, where the thrown split names it.
TEST(AdditiveModel, SplitOfAnOverflowingPoleIsNone) {
  const TransferFunction g(Polynomial({1.0}), Polynomial({1e-320, 1.0}));
  EXPECT_FALSE(AdditiveModel::split_transfer_function(g).has_value());
  EXPECT_THAT([&] { AdditiveModel::from_transfer_function(g); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("not finite")));
}

// The sum of the submodels as a value: the transfer function where its coefficients are
// finite, none where they overflow (to_transfer_function throws there).
TEST(AdditiveModel, TransferFunctionIfFiniteIsNoneOnOverflow) {
  const AdditiveModel g = testing::open_loop_four_modes();
  const std::optional<TransferFunction> sum = internal::transfer_function_if_finite(g);
  ASSERT_TRUE(sum.has_value());
  EXPECT_EQ(sum->denominator(), g.to_transfer_function().denominator());
  EXPECT_EQ(sum->numerator(), g.to_transfer_function().numerator());
  const AdditiveModel huge({{Polynomial({1.0, 1e200}), Polynomial({1.0}), 0},
                            {Polynomial({1.0, 1e200}), Polynomial({1.0}), 0}});
  EXPECT_FALSE(internal::transfer_function_if_finite(huge).has_value());
  EXPECT_THAT([&] { (void)huge.to_transfer_function(); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("overflows")));
}

TEST(AdditiveModel, ModalParametersClosedForm) {
  const AdditiveModel g = testing::open_loop_four_modes();
  const auto modal = g.modal_parameters(0);
  ASSERT_TRUE(modal.has_value());
  const double wn = std::hypot(0.25, 1.39);
  EXPECT_NEAR(modal->natural_frequency, wn, 1e-14);
  EXPECT_NEAR(modal->damping_ratio, 0.25 / wn, 1e-14);
  EXPECT_DOUBLE_EQ(modal->gain, 3.0);
  const AdditiveModel first_order({{Polynomial({1.0, 0.5}), Polynomial({1.0}), 0}});
  EXPECT_FALSE(first_order.modal_parameters(0).has_value());
}

TEST(AdditiveModel, ValidationNamesTheRule) {
  EXPECT_THAT(
      [] {
        AdditiveModel({{Polynomial({2.0, 1.0}), Polynomial({1.0}), 0}});
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("anti-monic")));
  EXPECT_THAT(
      [] {
        AdditiveModel({{Polynomial({1.0, 1.0}), Polynomial({1.0, 1.0}), 0},
                       {Polynomial({1.0, 2.0}), Polynomial({1.0, 1.0}), 0}});
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("at most one biproper")));
  EXPECT_THAT(
      [] {
        AdditiveModel({{Polynomial({1.0}), Polynomial({1.0}), 1},
                       {Polynomial({1.0, 2.0}), Polynomial({1.0}), 2}});
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("poles at the origin")));
  EXPECT_THAT(
      [] {
        AdditiveModel({{Polynomial({1.0, 1.0}), Polynomial({1.0, 1.0, 1.0}), 0}});
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("proper")));
  EXPECT_THAT([] { AdditiveModel(std::vector<Submodel>{}); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("at least one")));
  EXPECT_THAT(
      [] {
        AdditiveModel::from_parameters({{2, 0, 0}}, Eigen::Vector2d(1.0, 2.0));
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("orders need 3")));
}

TEST(AdditiveModel, IntegratorSubmodelTransferFunction) {
  // 1/(p (1 + 0.5 p)) + 2/(1 + p).
  const AdditiveModel g({{Polynomial({1.0, 0.5}), Polynomial({1.0}), 1},
                         {Polynomial({1.0, 1.0}), Polynomial({2.0}), 0}});
  const std::complex<double> s(0.0, 2.0);
  const std::complex<double> expected = 1.0 / (s * (1.0 + 0.5 * s)) + 2.0 / (1.0 + s);
  EXPECT_NEAR(std::abs(g.to_transfer_function()(s) - expected), 0.0, 1e-14);
  EXPECT_NEAR(std::abs(g.frequency_response(2.0) - expected), 0.0, 1e-14);
}

}  // namespace
}  // namespace ctid::additive_model_test
