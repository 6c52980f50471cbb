// Smoke test of an installed ctid: evaluates and factors a polynomial with known roots.
// Exits 0 when the results match the closed form, 1 otherwise.
#include <cmath>
#include <complex>
#include <iostream>

#include <ctid/ctid.h>  // the umbrella header: every public header compiles when installed

int main() {
  // 2 - 3x + x^2 = (x - 1)(x - 2), ascending coefficients.
  const ctid::Polynomial p{2.0, -3.0, 1.0};
  const double at_three = p(3.0);                                       // (3 - 1)(3 - 2) = 2
  const std::complex<double> at_i = p(std::complex<double>(0.0, 1.0));  // 1 - 3i
  const Eigen::VectorXcd roots = p.roots();
  double low = std::min(roots(0).real(), roots(1).real());
  double high = std::max(roots(0).real(), roots(1).real());

  const bool ok = p.degree() == 2 && std::abs(at_three - 2.0) < 1e-12 &&
                  std::abs(at_i - std::complex<double>(1.0, -3.0)) < 1e-12 &&
                  std::abs(low - 1.0) < 1e-10 && std::abs(high - 2.0) < 1e-10;
  std::cout << "consumer: p(x) = " << p.to_string("x") << ", p(3) = " << at_three << ", roots "
            << low << ", " << high << (ok ? " (ok)" : " (WRONG)") << "\n";
  return ok ? 0 : 1;
}
