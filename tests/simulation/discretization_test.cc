// Closed forms and properties of the exact ZOH / FOH discretisations.
#include "ctid/simulation/discretization.h"

#include <cmath>
#include <limits>

#include <Eigen/LU>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"

namespace ctid::discretization_test {
namespace {

using ::testing::HasSubstr;

TEST(DiscretizeZoh, DoubleIntegratorClosedForm) {
  Eigen::MatrixXd a(2, 2);
  a << 0.0, 1.0, 0.0, 0.0;
  Eigen::MatrixXd b(2, 1);
  b << 0.0, 1.0;
  for (double h : {1e-3, 0.05, 0.7, 3.0}) {
    const ZohDiscretization d = discretize_zoh(a, b, h);
    Eigen::MatrixXd phi(2, 2);
    phi << 1.0, h, 0.0, 1.0;
    Eigen::MatrixXd gamma(2, 1);
    gamma << h * h / 2.0, h;
    EXPECT_LT((d.phi - phi).norm(), 1e-14 * (1.0 + h)) << "h = " << h;
    EXPECT_LT((d.gamma - gamma).norm(), 1e-14 * (1.0 + h * h)) << "h = " << h;
  }
}

TEST(DiscretizeZoh, FirstOrderClosedForm) {
  // dx = -alpha x + beta u.
  for (double alpha : {0.01, 1.0, 37.0, 1e3}) {
    const double beta = 2.5;
    const double h = 0.05;
    Eigen::MatrixXd a = Eigen::MatrixXd::Constant(1, 1, -alpha);
    Eigen::MatrixXd b = Eigen::MatrixXd::Constant(1, 1, beta);
    const ZohDiscretization d = discretize_zoh(a, b, h);
    const double phi = std::exp(-alpha * h);
    const double gamma = beta * -std::expm1(-alpha * h) / alpha;
    EXPECT_NEAR(d.phi(0, 0), phi, 1e-14 * std::max(phi, 1e-300) + 1e-300) << alpha;
    EXPECT_NEAR(d.gamma(0, 0), gamma, 1e-13 * std::abs(gamma)) << alpha;
  }
}

Eigen::MatrixXd stable_test_matrix() {
  // Two lightly damped modes and a real pole, coupled so that A is not normal.
  Eigen::MatrixXd a(5, 5);
  a << -0.5, 9.99, 0.3, 0.0, 0.1,   //
      -9.99, -0.5, 0.0, 0.2, 0.0,   //
      0.0, 0.0, -0.17, 5.77, 0.4,   //
      0.0, 0.0, -5.77, -0.17, 0.0,  //
      0.0, 0.0, 0.0, 0.0, -2.0;
  return a;
}

TEST(DiscretizeZoh, SemigroupPhiOfTwoHEqualsPhiSquared) {
  const Eigen::MatrixXd a = stable_test_matrix();
  const Eigen::MatrixXd b = Eigen::MatrixXd::Ones(5, 1);
  for (double h : {0.01, 0.05, 0.4}) {
    const ZohDiscretization d1 = discretize_zoh(a, b, h);
    const ZohDiscretization d2 = discretize_zoh(a, b, 2.0 * h);
    EXPECT_LT((d2.phi - d1.phi * d1.phi).norm(), 1e-13 * d2.phi.norm()) << h;
    // Gamma(2h) = Phi(h) Gamma(h) + Gamma(h): two held steps of one unit input.
    EXPECT_LT((d2.gamma - (d1.phi * d1.gamma + d1.gamma)).norm(), 1e-13 * d2.gamma.norm()) << h;
  }
}

TEST(DiscretizeZoh, KeepsDcGain) {
  const Eigen::MatrixXd a = stable_test_matrix();
  Eigen::MatrixXd b(5, 1);
  b << 1.0, -2.0, 0.5, 3.0, 1.5;
  Eigen::RowVectorXd c(5);
  c << 0.3, 1.0, -1.0, 0.25, 2.0;
  const double continuous_gain = -(c * a.partialPivLu().solve(b))(0, 0);
  for (double h : {0.001, 0.05, 1.0}) {
    const ZohDiscretization d = discretize_zoh(a, b, h);
    const Eigen::MatrixXd i = Eigen::MatrixXd::Identity(5, 5);
    const double discrete_gain = (c * (i - d.phi).partialPivLu().solve(d.gamma))(0, 0);
    EXPECT_NEAR(discrete_gain, continuous_gain, 1e-11 * std::abs(continuous_gain)) << h;
  }
}

TEST(DiscretizeZoh, StateSpaceOverloadKeepsOutputEquation) {
  StateSpace model;
  model.a = stable_test_matrix();
  model.b = Eigen::VectorXd::LinSpaced(5, 1.0, 2.0);
  model.c = Eigen::RowVectorXd::LinSpaced(5, -1.0, 1.0);
  model.d = 0.75;
  const StateSpace discrete = discretize_zoh(model, 0.05);
  const ZohDiscretization d = discretize_zoh(model.a, Eigen::MatrixXd(model.b), 0.05);
  EXPECT_EQ(discrete.a, d.phi);
  EXPECT_EQ(Eigen::MatrixXd(discrete.b), d.gamma);
  EXPECT_EQ(discrete.c, model.c);
  EXPECT_EQ(discrete.d, 0.75);
}

TEST(DiscretizeFoh, IntegratorIsTrapezoidalRule) {
  const Eigen::MatrixXd a = Eigen::MatrixXd::Zero(1, 1);
  const Eigen::MatrixXd b = Eigen::MatrixXd::Constant(1, 1, 3.0);
  const double h = 0.05;
  const FohDiscretization d = discretize_foh(a, b, h);
  EXPECT_NEAR(d.phi(0, 0), 1.0, 1e-15);
  EXPECT_NEAR(d.gamma0(0, 0), 3.0 * h / 2.0, 1e-15);
  EXPECT_NEAR(d.gamma1(0, 0), 3.0 * h / 2.0, 1e-15);
}

TEST(DiscretizeFoh, DoubleIntegratorClosedForm) {
  Eigen::MatrixXd a(2, 2);
  a << 0.0, 1.0, 0.0, 0.0;
  Eigen::MatrixXd b(2, 1);
  b << 0.0, 1.0;
  const double h = 0.3;
  const FohDiscretization d = discretize_foh(a, b, h);
  Eigen::MatrixXd gamma0(2, 1);
  gamma0 << h * h / 3.0, h / 2.0;
  Eigen::MatrixXd gamma1(2, 1);
  gamma1 << h * h / 6.0, h / 2.0;
  EXPECT_LT((d.gamma0 - gamma0).norm(), 1e-15);
  EXPECT_LT((d.gamma1 - gamma1).norm(), 1e-15);
}

TEST(DiscretizeFoh, FirstOrderClosedForm) {
  const double alpha = 4.0;
  const double beta = 1.5;
  const double h = 0.1;
  const FohDiscretization d = discretize_foh(Eigen::MatrixXd::Constant(1, 1, -alpha),
                                             Eigen::MatrixXd::Constant(1, 1, beta), h);
  const double e = std::exp(-alpha * h);
  const double g0 = beta * (1.0 - e) / alpha;
  const double g1 =
      beta * ((1.0 - e) / alpha - (1.0 - e * (1.0 + alpha * h)) / (alpha * alpha * h));
  EXPECT_NEAR(d.phi(0, 0), e, 1e-15);
  EXPECT_NEAR(d.gamma1(0, 0), g1, 1e-14 * g1);
  EXPECT_NEAR(d.gamma0(0, 0), g0 - g1, 1e-14 * (g0 - g1));
}

TEST(DiscretizeFoh, FohAndZohAgreeOnConstantInput) {
  // A constant input is both piecewise constant and piecewise linear.
  const Eigen::MatrixXd a = stable_test_matrix();
  const Eigen::MatrixXd b = Eigen::MatrixXd::Ones(5, 1);
  const ZohDiscretization z = discretize_zoh(a, b, 0.05);
  const FohDiscretization f = discretize_foh(a, b, 0.05);
  EXPECT_LT((f.phi - z.phi).norm(), 1e-15);
  EXPECT_LT((f.gamma0 + f.gamma1 - z.gamma).norm(), 1e-15);
}

TEST(Discretize, RejectsBadArguments) {
  const Eigen::MatrixXd a = Eigen::MatrixXd::Identity(2, 2);
  const Eigen::MatrixXd b = Eigen::MatrixXd::Ones(2, 1);
  try {
    discretize_zoh(a, b, 0.0);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("sample time h must be positive"));
  }
  EXPECT_THROW(discretize_foh(a, b, -1.0), InvalidArgument);
  EXPECT_THROW(discretize_zoh(a, b, std::nan("")), InvalidArgument);
  EXPECT_THROW(discretize_zoh(Eigen::MatrixXd::Ones(2, 3), b, 0.1), InvalidArgument);
  EXPECT_THROW(discretize_zoh(a, Eigen::MatrixXd::Ones(3, 1), 0.1), InvalidArgument);
  Eigen::MatrixXd bad = a;
  bad(1, 0) = std::numeric_limits<double>::infinity();
  try {
    discretize_foh(bad, b, 0.1);
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("A has a non-finite entry"));
  }
}

}  // namespace
}  // namespace ctid::discretization_test
