#include "ctid/core/polynomial.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <utility>

#include <Eigen/Eigenvalues>

#include "core/internal/balance.h"
#include "core/internal/polynomial_if_finite.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"

namespace ctid {

namespace {

// "1", "s", "s^k": the term whose coefficient a message names.
std::string power_of_s(Eigen::Index k) {
  return k == 0 ? "1" : k == 1 ? "s" : "s^" + std::to_string(k);
}

// What require_finite says of coefficient k.
std::string coefficient_not_finite(const Eigen::VectorXd& c, Eigen::Index k) {
  return internal::concat("polynomial coefficient ", k, " (of ", power_of_s(k), ") is ", c(k),
                          "; coefficients must be finite");
}

// The coefficients of the product of two non-zero polynomials, untrimmed.
Eigen::VectorXd product_coefficients(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(a.size() + b.size() - 1);
  for (Eigen::Index i = 0; i < a.size(); ++i) c.segment(i, b.size()) += a(i) * b;
  return c;
}

void require_finite(const Eigen::VectorXd& c) {
  for (Eigen::Index k = 0; k < c.size(); ++k) {
    if (!std::isfinite(c(k))) throw InvalidArgument(coefficient_not_finite(c, k));
  }
}

// Index of the highest non-negligible coefficient, or -1.
Eigen::Index last_significant(const Eigen::VectorXd& c, double tolerance) {
  const double threshold = c.size() > 0 ? tolerance * c.cwiseAbs().maxCoeff() : 0.0;
  Eigen::Index k = c.size() - 1;
  while (k >= 0 && std::abs(c(k)) <= threshold) --k;
  return k;
}

}  // namespace

Polynomial::Polynomial() = default;

Polynomial::Polynomial(Eigen::VectorXd ascending) : coefficients_(std::move(ascending)) {
  require_finite(coefficients_);
  if (coefficients_.size() == 1 && coefficients_(0) == 0.0) {
    coefficients_.resize(0);
    return;
  }
  if (coefficients_.size() > 0) {
    require(coefficients_(coefficients_.size() - 1) != 0.0, "polynomial leading coefficient (of ",
            power_of_s(coefficients_.size() - 1),
            ") is zero; drop leading zeros explicitly with Polynomial::trimmed");
  }
}

Polynomial::Polynomial(std::initializer_list<double> ascending)
    : Polynomial(Eigen::Map<const Eigen::VectorXd>(ascending.begin(),
                                                   static_cast<Eigen::Index>(ascending.size()))) {}

Polynomial Polynomial::trimmed(Eigen::VectorXd ascending, double tolerance) {
  require_finite(ascending);
  require(tolerance >= 0.0 && tolerance < 1.0, "trim tolerance is ", tolerance,
          "; it must lie in [0, 1)");
  const Eigen::Index last = last_significant(ascending, tolerance);
  return Polynomial(Eigen::VectorXd(ascending.head(last + 1)));
}

Polynomial Polynomial::from_roots(const Eigen::VectorXcd& roots, double leading) {
  std::string failure;
  std::optional<Polynomial> p = internal::polynomial_from_roots(roots, leading, &failure);
  if (!p) throw InvalidArgument(failure);
  return std::move(*p);
}

Polynomial Polynomial::constant(double value) { return Polynomial({value}); }

Polynomial Polynomial::monomial(int k, double coefficient) {
  require(k >= 0, "monomial degree is ", k, "; it must be >= 0");
  Eigen::VectorXd c = Eigen::VectorXd::Zero(k + 1);
  c(k) = coefficient;
  return Polynomial::trimmed(c);
}

double Polynomial::coefficient(int k) const {
  return (k >= 0 && k < coefficients_.size()) ? coefficients_(k) : 0.0;
}

double Polynomial::leading() const {
  return is_zero() ? 0.0 : coefficients_(coefficients_.size() - 1);
}

double Polynomial::operator()(double x) const {
  double value = 0.0;  // Horner, highest power first
  for (Eigen::Index k = coefficients_.size() - 1; k >= 0; --k) value = value * x + coefficients_(k);
  return value;
}

std::complex<double> Polynomial::operator()(std::complex<double> x) const {
  std::complex<double> value = 0.0;
  for (Eigen::Index k = coefficients_.size() - 1; k >= 0; --k) value = value * x + coefficients_(k);
  return value;
}

Eigen::VectorXcd Polynomial::roots() const {
  const int n = degree();
  if (n <= 0) return Eigen::VectorXcd(0);
  // Roots at the origin are exact: factor them out before the eigenvalue problem.
  int zeros = 0;
  while (coefficients_(zeros) == 0.0) ++zeros;
  const int m = n - zeros;
  Eigen::VectorXcd result = Eigen::VectorXcd::Zero(n);
  if (m == 0) return result;
  const Eigen::VectorXd c = coefficients_.segment(zeros, m + 1) / coefficients_(n);
  if (m == 1) {
    result(zeros) = -c(0);
    return result;
  }
  // Companion matrix with the monic coefficients in its last row.
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(m, m);
  companion.diagonal(1).setOnes();
  companion.row(m - 1) = -c.head(m).transpose();
  internal::balance_in_place(companion);
  Eigen::EigenSolver<Eigen::MatrixXd> solver(companion, /*computeEigenvectors=*/false);
  if (solver.info() != Eigen::Success) {
    throw ComputationError("polynomial root finding failed to converge for " + to_string());
  }
  result.tail(m) = solver.eigenvalues();
  return result;
}

Polynomial Polynomial::derivative() const {
  if (degree() <= 0) return Polynomial();
  Eigen::VectorXd d(degree());
  for (int k = 1; k <= degree(); ++k) d(k - 1) = k * coefficients_(k);
  return Polynomial(d);
}

Polynomial Polynomial::monic() const {
  require(!is_zero(), "the zero polynomial cannot be made monic");
  Eigen::VectorXd c = coefficients_ / leading();
  require(c.allFinite(), "polynomial ", to_string(), ": its leading coefficient (of ",
          power_of_s(degree()), ") is ", leading(),
          ", so small against the others that dividing by it overflows; if the degree is "
          "lower, leave that coefficient out");
  return Polynomial(std::move(c));
}

Polynomial Polynomial::anti_monic() const {
  std::string failure;
  std::optional<Polynomial> p = internal::anti_monic_if_finite(*this, &failure);
  if (!p) throw InvalidArgument(failure);
  return std::move(*p);
}

Polynomial Polynomial::scaled_argument(double scale) const {
  require(std::isfinite(scale) && scale != 0.0, "argument scale is ", scale,
          "; it must be finite and non-zero");
  Eigen::VectorXd c = coefficients_;
  double power = 1.0;
  for (Eigen::Index k = 0; k < c.size(); ++k, power *= scale) c(k) *= power;
  return Polynomial::trimmed(c);
}

Polynomial Polynomial::operator-() const { return Polynomial(Eigen::VectorXd(-coefficients_)); }

Polynomial operator+(const Polynomial& a, const Polynomial& b) {
  const Eigen::Index n = std::max(a.coefficients_.size(), b.coefficients_.size());
  Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
  c.head(a.coefficients_.size()) += a.coefficients_;
  c.head(b.coefficients_.size()) += b.coefficients_;
  return Polynomial::trimmed(c);
}

Polynomial operator-(const Polynomial& a, const Polynomial& b) { return a + (-b); }

Polynomial operator*(const Polynomial& a, const Polynomial& b) {
  if (a.is_zero() || b.is_zero()) return Polynomial();
  return Polynomial::trimmed(product_coefficients(a.coefficients_, b.coefficients_));
}

Polynomial operator*(double s, const Polynomial& p) {
  require(std::isfinite(s), "polynomial scale factor is not finite");
  if (s == 0.0) return Polynomial();
  return Polynomial(Eigen::VectorXd(s * p.coefficients_));
}

bool operator==(const Polynomial& a, const Polynomial& b) {
  return a.coefficients_.size() == b.coefficients_.size() && a.coefficients_ == b.coefficients_;
}

std::string Polynomial::to_string(const std::string& variable) const {
  if (is_zero()) return "0";
  std::ostringstream out;
  bool first = true;
  for (int k = degree(); k >= 0; --k) {
    const double c = coefficients_(k);
    if (c == 0.0) continue;
    if (!first)
      out << (c < 0 ? " - " : " + ");
    else if (c < 0)
      out << "-";
    // A coefficient that prints as 1 is left out of its term ("s^2", not "1 s^2").
    const std::string magnitude = format_brief(std::abs(c));
    const bool shown = k == 0 || magnitude != "1";
    if (shown) out << magnitude;
    if (k > 0) {
      if (shown) out << " ";
      out << variable;
      if (k > 1) out << "^" << k;
    }
    first = false;
  }
  return out.str();
}

PolynomialDivision divide(const Polynomial& a, const Polynomial& b) {
  require(!b.is_zero(), "polynomial division by the zero polynomial");
  if (a.degree() < b.degree()) return {Polynomial(), a};
  Eigen::VectorXd r = a.coefficients();
  const int nb = b.degree();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(a.degree() - nb + 1);
  for (int k = a.degree(); k >= nb; --k) {
    const double factor = r(k) / b.leading();
    q(k - nb) = factor;
    r.segment(k - nb, nb + 1) -= factor * b.coefficients();
    r(k) = 0.0;
  }
  return {Polynomial::trimmed(q), Polynomial::trimmed(Eigen::VectorXd(r.head(std::max(nb, 0))))};
}

namespace internal {

std::optional<Polynomial> polynomial_from_roots(const Eigen::VectorXcd& roots, double leading,
                                                std::string* failure) {
  require(std::isfinite(leading) && leading != 0.0, "leading coefficient is ", leading,
          "; it must be finite and non-zero");
  const auto fail = [failure](std::string reason) -> std::optional<Polynomial> {
    if (failure != nullptr) *failure = std::move(reason);
    return std::nullopt;
  };
  Eigen::VectorXcd c = Eigen::VectorXcd::Zero(roots.size() + 1);
  c(0) = 1.0;
  // Multiply by (x - r) one root at a time: c_new[k] = c[k-1] - r c[k].
  for (Eigen::Index i = 0; i < roots.size(); ++i) {
    if (!std::isfinite(roots(i).real()) || !std::isfinite(roots(i).imag())) {
      return fail(concat("root ", i, " is not finite"));
    }
    for (Eigen::Index k = i + 1; k > 0; --k) c(k) = c(k - 1) - roots(i) * c(k);
    c(0) = -roots(i) * c(0);
  }
  const double size = c.cwiseAbs().maxCoeff();
  if (!(c.imag().cwiseAbs().maxCoeff() <= 1e-9 * size)) {
    return fail("roots must come in complex-conjugate pairs for a real polynomial");
  }
  Eigen::VectorXd real = leading * c.real();
  for (Eigen::Index k = 0; k < real.size(); ++k) {
    if (!std::isfinite(real(k))) return fail(coefficient_not_finite(real, k));
  }
  return Polynomial(std::move(real));
}

std::optional<Polynomial> product_if_finite(const Polynomial& a, const Polynomial& b) {
  if (a.is_zero() || b.is_zero()) return Polynomial();
  Eigen::VectorXd c = product_coefficients(a.coefficients(), b.coefficients());
  if (!c.allFinite()) return std::nullopt;
  return Polynomial::trimmed(std::move(c));
}

std::optional<Polynomial> anti_monic_if_finite(const Polynomial& p, std::string* failure) {
  const Eigen::VectorXd& coefficients = p.coefficients();
  if (p.is_zero() || coefficients(0) == 0.0) {
    if (failure != nullptr) {
      *failure = concat("polynomial ", p.to_string(),
                        " has a zero constant coefficient and cannot be made anti-monic");
    }
    return std::nullopt;
  }
  Eigen::VectorXd c = coefficients / coefficients(0);
  if (!c.allFinite()) {
    if (failure != nullptr) {
      *failure =
          concat("polynomial ", p.to_string(), ": its constant coefficient is ", coefficients(0),
                 ", so small against the others that dividing by it overflows; if the "
                 "polynomial has a root at s = 0, give it as such");
    }
    return std::nullopt;
  }
  return Polynomial(std::move(c));
}

}  // namespace internal

}  // namespace ctid
