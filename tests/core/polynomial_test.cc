#include "ctid/core/polynomial.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <optional>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/internal/polynomial_if_finite.h"
#include "ctid/core/error.h"

namespace ctid::polynomial_test {
namespace {

using ::testing::HasSubstr;

std::vector<std::complex<double>> sorted(const Eigen::VectorXcd& v) {
  std::vector<std::complex<double>> out(v.data(), v.data() + v.size());
  std::sort(out.begin(), out.end(), [](auto a, auto b) {
    return a.real() != b.real() ? a.real() < b.real() : a.imag() < b.imag();
  });
  return out;
}

TEST(Polynomial, AscendingCoefficientsAndEvaluation) {
  const Polynomial p({1.0, -3.0, 2.0});  // 1 - 3x + 2x^2
  EXPECT_EQ(p.degree(), 2);
  EXPECT_EQ(p[0], 1.0);
  EXPECT_EQ(p[2], 2.0);
  EXPECT_EQ(p[7], 0.0);
  EXPECT_DOUBLE_EQ(p(2.0), 1.0 - 6.0 + 8.0);
  const std::complex<double> j(0.0, 1.0);
  EXPECT_NEAR(std::abs(p(j) - (1.0 - 3.0 * j - 2.0)), 0.0, 1e-15);
}

TEST(Polynomial, ZeroPolynomial) {
  EXPECT_TRUE(Polynomial().is_zero());
  EXPECT_EQ(Polynomial().degree(), -1);
  EXPECT_TRUE(Polynomial({0.0}).is_zero());
  EXPECT_TRUE((Polynomial({1.0, 2.0}) - Polynomial({1.0, 2.0})).is_zero());
}

TEST(Polynomial, RejectsLeadingZeroAndNonFinite) {
  try {
    Polynomial({1.0, 2.0, 0.0});
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("leading coefficient"));
    EXPECT_THAT(e.what(), HasSubstr("trimmed"));
  }
  EXPECT_THAT(
      [] {
        Polynomial({1.0, NAN});
      },
      ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("coefficient 1")));
  EXPECT_THAT([] { Polynomial({INFINITY}); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("finite")));
  EXPECT_EQ(Polynomial::trimmed(Eigen::Vector3d(1.0, 2.0, 0.0)).degree(), 1);
  EXPECT_EQ(Polynomial::trimmed(Eigen::Vector3d(1.0, 2.0, 1e-14), 1e-12).degree(), 1);
}

TEST(Polynomial, RootsRecoverKnownRootsIncludingOriginAndWideSpread) {
  Eigen::VectorXcd roots(7);
  using C = std::complex<double>;
  roots << C(0.0), C(-0.25, 1.39), C(-0.25, -1.39), C(-3.0), C(-0.5, 9.99), C(-0.5, -9.99),
      C(-1000.0);
  const Polynomial p = Polynomial::from_roots(roots, 2.5);
  EXPECT_EQ(p.degree(), 7);
  EXPECT_DOUBLE_EQ(p.leading(), 2.5);
  EXPECT_EQ(p[0], 0.0);
  const auto expected = sorted(roots);
  const auto found = sorted(p.roots());
  ASSERT_EQ(found.size(), expected.size());
  for (size_t i = 0; i < found.size(); ++i) {
    EXPECT_NEAR(std::abs(found[i] - expected[i]), 0.0, 1e-10 * std::max(1.0, std::abs(expected[i])))
        << i;
  }
}

TEST(Polynomial, FromRootsRejectsUnpairedComplexRoot) {
  Eigen::VectorXcd roots(1);
  roots << std::complex<double>(1.0, 2.0);
  EXPECT_THAT([&] { Polynomial::from_roots(roots); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("conjugate")));
}

TEST(Polynomial, ArithmeticMatchesPointwiseEvaluation) {
  const Polynomial a({0.5, -1.0, 3.0, 2.0});
  const Polynomial b({-2.0, 0.25});
  for (double x : {-2.0, -0.3, 0.0, 0.7, 3.0}) {
    EXPECT_NEAR((a + b)(x), a(x) + b(x), 1e-12);
    EXPECT_NEAR((a - b)(x), a(x) - b(x), 1e-12);
    EXPECT_NEAR((a * b)(x), a(x) * b(x), 1e-12);
    EXPECT_NEAR((1.5 * a)(x), 1.5 * a(x), 1e-12);
    EXPECT_NEAR(a.scaled_argument(3.0)(x), a(3.0 * x), 1e-10);
  }
  EXPECT_EQ((a * b).degree(), 4);
}

TEST(Polynomial, DerivativeMatchesFiniteDifference) {
  const Polynomial a({0.5, -1.0, 3.0, 2.0});
  const Polynomial d = a.derivative();
  EXPECT_EQ(d, Polynomial({-1.0, 6.0, 6.0}));
  const double x = 0.37;
  const double step = 1e-6;
  EXPECT_NEAR(d(x), (a(x + step) - a(x - step)) / (2 * step), 1e-8);
  EXPECT_TRUE(Polynomial::constant(4.0).derivative().is_zero());
}

TEST(Polynomial, DivisionSatisfiesIdentity) {
  const Polynomial a({1.0, 2.0, -3.0, 0.5, 4.0});
  const Polynomial b({-1.0, 0.0, 2.0});
  const PolynomialDivision qr = divide(a, b);
  EXPECT_LT(qr.remainder.degree(), b.degree());
  const Polynomial back = qr.quotient * b + qr.remainder;
  for (double x : {-1.5, 0.0, 2.0}) EXPECT_NEAR(back(x), a(x), 1e-12);
  EXPECT_THROW(divide(a, Polynomial()), InvalidArgument);
}

TEST(Polynomial, MonicAntiMonicAndString) {
  const Polynomial p({2.0, 4.0, 8.0});
  EXPECT_EQ(p.monic(), Polynomial({0.25, 0.5, 1.0}));
  EXPECT_EQ(p.anti_monic(), Polynomial({1.0, 2.0, 4.0}));
  EXPECT_THROW(Polynomial({0.0, 1.0}).anti_monic(), InvalidArgument);
  // Issue 33: a leading (constant) coefficient too small to divide by is named, not the inf
  // the division would make of another coefficient.
  EXPECT_THAT(
      [] {
        Polynomial({1.0, 2.0, 1e-310}).monic();
      },
      ::testing::ThrowsMessage<InvalidArgument>(
          ::testing::AllOf(::testing::HasSubstr("its leading coefficient (of s^2) is 1e-310"),
                           ::testing::HasSubstr("dividing by it overflows"))));
  EXPECT_THAT(
      [] {
        Polynomial({1e-310, 2.0, 1.0}).anti_monic();
      },
      ::testing::ThrowsMessage<InvalidArgument>(
          ::testing::HasSubstr("its constant coefficient is 1e-310")));
  EXPECT_EQ(Polynomial({1.0, -1.0, 2.0}).to_string("p"), "2 p^2 - p + 1");
}

// The message `make` throws (empty if it does not throw).
template <typename Make>
std::string thrown_message(const Make& make) {
  try {
    make();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

// from_roots, the product and anti_monic as values (decision 0045): the same polynomial where
// the throwing functions give one, and none with the very reason they throw where they do not.
TEST(PolynomialValues, FromRootsIsTheSamePolynomialOrNoneWithTheReasonItThrows) {
  Eigen::VectorXcd roots(3);
  roots << -1.0, std::complex<double>(-2.0, 3.0), std::complex<double>(-2.0, -3.0);
  const std::optional<Polynomial> p = internal::polynomial_from_roots(roots, 2.0);
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(*p, Polynomial::from_roots(roots, 2.0));

  Eigen::VectorXcd not_finite = roots;
  not_finite(1) = std::complex<double>(std::nan(""), 0.0);
  Eigen::VectorXcd unpaired(1);
  unpaired << std::complex<double>(-1.0, 1.0);
  Eigen::VectorXcd overflowing(2);
  overflowing << -1e200, -1e200;  // constant coefficient 1e400
  for (const Eigen::VectorXcd& bad : {not_finite, unpaired, overflowing}) {
    std::string failure;
    EXPECT_FALSE(internal::polynomial_from_roots(bad, 1.0, &failure).has_value());
    EXPECT_FALSE(failure.empty());
    EXPECT_EQ(failure, thrown_message([&] { Polynomial::from_roots(bad); }));
  }
}

TEST(PolynomialValues, AntiMonicIsTheSamePolynomialOrNoneWithTheReasonItThrows) {
  const Polynomial p{4.0, 2.0, 1.0};
  ASSERT_TRUE(internal::anti_monic_if_finite(p).has_value());
  EXPECT_EQ(*internal::anti_monic_if_finite(p), p.anti_monic());
  for (const Polynomial& bad : {Polynomial{0.0, 1.0}, Polynomial{1e-300, 0.0, 1e10}}) {
    std::string failure;
    EXPECT_FALSE(internal::anti_monic_if_finite(bad, &failure).has_value());
    EXPECT_THAT(failure, ::testing::HasSubstr("constant coefficient"));
    EXPECT_EQ(failure, thrown_message([&] { bad.anti_monic(); }));
  }
}

TEST(PolynomialValues, ProductIsTheSamePolynomialOrNoneWhereItOverflows) {
  const Polynomial a{1.0, 3.0};
  const Polynomial b{2.0, 0.5, 1.0};
  ASSERT_TRUE(internal::product_if_finite(a, b).has_value());
  EXPECT_EQ(*internal::product_if_finite(a, b), a * b);
  EXPECT_TRUE(internal::product_if_finite(a, Polynomial())->is_zero());
  const Polynomial big{1.0, 1e200};
  EXPECT_FALSE(internal::product_if_finite(big, big).has_value());
  EXPECT_THAT(thrown_message([&] { (void)(big * big); }),
              ::testing::HasSubstr("coefficients must be finite"));
}

}  // namespace
}  // namespace ctid::polynomial_test
