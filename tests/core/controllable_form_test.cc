#include "ctid/core/controllable_form.h"

#include <complex>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "ctid/core/polynomial.h"

namespace ctid::controllable_form_test {
namespace {

std::complex<double> realised(const StateSpace& ss, std::complex<double> x) {
  const Eigen::Index n = ss.a.rows();
  if (n == 0) return ss.d;
  const Eigen::MatrixXcd m =
      x * Eigen::MatrixXcd::Identity(n, n) - ss.a.cast<std::complex<double>>();
  const Eigen::VectorXcd v = m.partialPivLu().solve(ss.b.cast<std::complex<double>>());
  return (ss.c.cast<std::complex<double>>() * v)(0) + ss.d;
}

std::complex<double> ratio(const Eigen::VectorXd& num, const Eigen::VectorXd& den,
                           std::complex<double> x) {
  std::complex<double> n = 0.0;
  std::complex<double> d = 0.0;
  for (Eigen::Index k = num.size() - 1; k >= 0; --k) n = n * x + num(k);
  for (Eigen::Index k = den.size() - 1; k >= 0; --k) d = d * x + den(k);
  return n / d;
}

TEST(ControllableForm, RealisesTheRatioStrictlyProperAndBiproper) {
  const Eigen::VectorXd den = (Eigen::VectorXd(4) << 3.0, 2.0, 3.0, 2.0).finished();  // not monic
  for (const Eigen::VectorXd& num :
       {Eigen::VectorXd((Eigen::VectorXd(3) << 2.0, 1.0, 2.0).finished()),
        Eigen::VectorXd((Eigen::VectorXd(4) << 1.0, -1.0, 0.5, 4.0).finished()),
        Eigen::VectorXd((Eigen::VectorXd(1) << 5.0).finished())}) {
    const StateSpace ss = controllable_form(num, den);
    ASSERT_EQ(ss.a.rows(), 3);
    EXPECT_EQ(ss.a(0, 1), 1.0);
    EXPECT_EQ(ss.a(2, 0), -1.5);  // -D_0 / D_3
    EXPECT_EQ(ss.b(2), 1.0);
    for (const std::complex<double> x :
         {std::complex<double>(0.3, 1.1), std::complex<double>(-2.0, 0.5)}) {
      EXPECT_LT(std::abs(realised(ss, x) - ratio(num, den, x)),
                1e-13 * std::abs(ratio(num, den, x)));
    }
  }
  // deg D = 0: a static gain.
  const StateSpace gain =
      controllable_form(Eigen::VectorXd::Constant(1, 6.0), Eigen::VectorXd::Constant(1, 2.0));
  EXPECT_EQ(gain.a.rows(), 0);
  EXPECT_EQ(gain.d, 3.0);
}

}  // namespace
}  // namespace ctid::controllable_form_test
