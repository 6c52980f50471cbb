// Real polynomials with coefficients in ASCENDING powers: c[0] + c[1] x + ... + c[n] x^n.
// This is the one coefficient convention of ctid (docs/conventions.md). It matches the
// papers' anti-monic denominators A(p) = 1 + a_1 p + ... + a_n p^n (González et al.,
// eq. 2), whose parameter vectors also list the coefficient of p first.
#pragma once

#include <complex>
#include <initializer_list>
#include <string>

#include <Eigen/Core>

namespace ctid {

class Polynomial {
 public:
  /// The zero polynomial (degree -1).
  Polynomial();
  /// From ascending coefficients. Throws InvalidArgument on non-finite values or a zero
  /// leading coefficient (use `trimmed` to drop leading zeros explicitly). An empty vector
  /// or a single 0 gives the zero polynomial.
  explicit Polynomial(Eigen::VectorXd ascending);
  Polynomial(std::initializer_list<double> ascending);

  /// Drops leading coefficients with |c| <= tolerance * max|c| (exact zeros by default).
  static Polynomial trimmed(Eigen::VectorXd ascending, double tolerance = 0.0);
  /// leading * prod (x - r_i). Complex roots must come in conjugate pairs (to 1e-9
  /// relative); the result's imaginary rounding is discarded.
  static Polynomial from_roots(const Eigen::VectorXcd& roots, double leading = 1.0);
  static Polynomial constant(double value);
  /// x^k.
  static Polynomial monomial(int k, double coefficient = 1.0);

  /// Degree; -1 for the zero polynomial.
  int degree() const { return static_cast<int>(coefficients_.size()) - 1; }
  bool is_zero() const { return coefficients_.size() == 0; }
  /// Ascending coefficients, size degree() + 1 (empty for the zero polynomial).
  const Eigen::VectorXd& coefficients() const { return coefficients_; }
  /// Coefficient of x^k; 0 beyond the degree.
  double coefficient(int k) const;
  double operator[](int k) const { return coefficient(k); }
  double leading() const;

  double operator()(double x) const;
  std::complex<double> operator()(std::complex<double> x) const;

  /// Roots as eigenvalues of the balanced companion matrix. Size degree().
  Eigen::VectorXcd roots() const;
  Polynomial derivative() const;
  /// The polynomial divided by its leading coefficient.
  Polynomial monic() const;
  /// The polynomial divided by its constant coefficient (requires c[0] != 0).
  Polynomial anti_monic() const;
  /// p(x) -> p(scale * x).
  Polynomial scaled_argument(double scale) const;

  Polynomial operator-() const;
  friend Polynomial operator+(const Polynomial& a, const Polynomial& b);
  friend Polynomial operator-(const Polynomial& a, const Polynomial& b);
  friend Polynomial operator*(const Polynomial& a, const Polynomial& b);
  friend Polynomial operator*(double s, const Polynomial& p);
  friend Polynomial operator*(const Polynomial& p, double s) { return s * p; }
  Polynomial& operator+=(const Polynomial& other) { return *this = *this + other; }
  Polynomial& operator*=(const Polynomial& other) { return *this = *this * other; }
  /// Exact equality of coefficients.
  friend bool operator==(const Polynomial& a, const Polynomial& b);

  /// The printed form of every polynomial ctid shows a person (docs/conventions.md): highest
  /// power first, coefficients to 6 significant digits (format_brief), in `variable` ("s" for
  /// continuous time, "q" for the shift operator), e.g. "2 s^2 + 0.5 s + 1".
  std::string to_string(const std::string& variable = "s") const;

 private:
  Eigen::VectorXd coefficients_;
};

/// Polynomial long division: a = q b + r with deg r < deg b.
struct PolynomialDivision {
  Polynomial quotient;
  Polynomial remainder;
};
PolynomialDivision divide(const Polynomial& a, const Polynomial& b);

}  // namespace ctid
