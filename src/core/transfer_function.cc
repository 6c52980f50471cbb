#include "ctid/core/transfer_function.h"

#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "core/internal/balance.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"

namespace ctid {

namespace {

Polynomial characteristic_polynomial(const Eigen::MatrixXd& a) {
  if (a.rows() == 0) return Polynomial::constant(1.0);
  Eigen::MatrixXd balanced = a;
  internal::balance_in_place(balanced);
  Eigen::EigenSolver<Eigen::MatrixXd> solver(balanced, /*computeEigenvectors=*/false);
  if (solver.info() != Eigen::Success) {
    throw ComputationError("eigenvalues of the state matrix did not converge");
  }
  return Polynomial::from_roots(solver.eigenvalues());
}

}  // namespace

TransferFunction::TransferFunction(Polynomial numerator, Polynomial denominator, double input_delay)
    : numerator_(std::move(numerator)),
      denominator_(std::move(denominator)),
      input_delay_(input_delay) {
  require(!denominator_.is_zero(), "transfer function denominator is the zero polynomial");
  require(std::isfinite(input_delay_) && input_delay_ >= 0.0, "input delay is ", input_delay_,
          " s; it must be finite and >= 0");
}

TransferFunction TransferFunction::with_input_delay(double tau) const {
  return TransferFunction(numerator_, denominator_, tau);
}

double TransferFunction::dc_gain() const {
  const double n0 = numerator_(0.0);
  const double d0 = denominator_(0.0);
  if (d0 == 0.0) {
    if (n0 == 0.0) return std::numeric_limits<double>::quiet_NaN();
    return std::copysign(std::numeric_limits<double>::infinity(), n0);
  }
  return n0 / d0;
}

std::complex<double> TransferFunction::operator()(std::complex<double> s) const {
  std::complex<double> value = numerator_(s) / denominator_(s);
  if (input_delay_ != 0.0) value *= std::exp(-s * input_delay_);
  return value;
}

std::complex<double> TransferFunction::frequency_response(double omega) const {
  return (*this)(std::complex<double>(0.0, omega));
}

bool TransferFunction::is_stable() const {
  const Eigen::VectorXcd p = poles();
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    if (!(p(i).real() < 0.0)) return false;
  }
  return true;
}

TransferFunction TransferFunction::normalized() const {
  Polynomial monic = denominator_.monic();  // refuses a leading coefficient too small to divide by
  const double inverse = 1.0 / denominator_.leading();
  require(std::isfinite(inverse) && (inverse * numerator_.coefficients()).allFinite(),
          "transfer function ", to_string(), ": the denominator's leading coefficient ",
          denominator_.leading(), " is so small that dividing the numerator by it overflows");
  return TransferFunction(inverse * numerator_, std::move(monic), input_delay_);
}

StateSpace TransferFunction::to_state_space() const {
  require(is_proper(), "cannot realise an improper transfer function (numerator degree ",
          numerator_.degree(), " > denominator degree ", denominator_.degree(), ")");
  const int n = denominator_.degree();
  StateSpace ss;
  const double lead = denominator_.leading();
  ss.d = n >= 0 ? numerator_.coefficient(n) / lead : 0.0;
  if (n == 0) {
    ss.a.resize(0, 0);
    ss.b.resize(0);
    ss.c.resize(0);
    return ss;
  }
  // Time scale w0 bounds every pole: with D monic, w0 = max_k |d_k|^(1/(n-k)) makes the
  // scaled coefficients d_k / w0^(n-k) at most 1 in magnitude.
  const Polynomial monic_den = denominator_.monic();
  double w0 = 0.0;
  for (int k = 0; k < n; ++k) {
    w0 = std::max(w0, std::pow(std::abs(monic_den[k]), 1.0 / (n - k)));
  }
  if (!(w0 > 0.0) || !std::isfinite(w0)) w0 = 1.0;
  require(std::isfinite(std::pow(w0, n)) && std::pow(w0, n) > 0.0, "transfer function ",
          to_string(), ": its poles reach about ", format_brief(w0),
          " rad/s, too far apart for a state-space realisation in double precision; if the "
          "denominator's leading coefficient ",
          lead, " is not meant, leave it out");
  // G(w0 sigma) = R(w0 sigma)/D(w0 sigma) + d, realised in companion form in sigma, then
  // A = w0 A_sigma, B = w0 B_sigma, C = C_sigma.
  const Polynomial remainder = numerator_ - ss.d * denominator_;
  const Polynomial den_sigma = monic_den.scaled_argument(w0);
  const double den_scale = den_sigma.leading();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  a.diagonal(1).setOnes();
  for (int k = 0; k < n; ++k) a(n - 1, k) = -den_sigma[k] / den_scale;
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  b(n - 1) = 1.0;
  Eigen::RowVectorXd c(n);
  double power = 1.0;
  const double scale = 1.0 / (lead * den_scale);
  for (int k = 0; k < n; ++k, power *= w0) c(k) = remainder[k] * power * scale;
  // Balance the companion matrix; the same similarity applies to B and C.
  const Eigen::VectorXd t = internal::balance_in_place(a);
  b = b.cwiseQuotient(t);
  c = c.cwiseProduct(t.transpose());
  ss.a = w0 * a;
  ss.b = w0 * b;
  ss.c = c;
  return ss;
}

TransferFunction TransferFunction::from_state_space(const StateSpace& model) {
  model.validate();
  if (model.order() == 0) return TransferFunction(Polynomial::constant(model.d), {1.0});
  // C (sI - A)^{-1} B = (det(sI - A + B C) - det(sI - A)) / det(sI - A).
  const Polynomial den = characteristic_polynomial(model.a);
  const Polynomial feedback = characteristic_polynomial(model.a - model.b * model.c);
  Eigen::VectorXd num = (feedback - den + model.d * den).coefficients();
  if (num.size() == 0) return TransferFunction(Polynomial(), den);
  // The subtraction cancels the leading terms only up to rounding: drop what is rounding.
  const double size = std::max(num.cwiseAbs().maxCoeff(), den.coefficients().cwiseAbs().maxCoeff());
  Eigen::Index last = num.size() - 1;
  while (last >= 0 && std::abs(num(last)) <= 1e-12 * size) --last;
  return TransferFunction(Polynomial(Eigen::VectorXd(num.head(last + 1))), den);
}

std::string TransferFunction::to_string() const {
  std::string text = "(" + numerator_.to_string("s") + ") / (" + denominator_.to_string("s") + ")";
  if (input_delay_ != 0.0) text += " * exp(-" + format_brief(input_delay_) + " s)";
  return text;
}

TransferFunction operator+(const TransferFunction& a, const TransferFunction& b) {
  require(a.input_delay() == b.input_delay(),
          "cannot add transfer functions with different input delays (", a.input_delay(), " s and ",
          b.input_delay(), " s)");
  return TransferFunction(a.numerator() * b.denominator() + b.numerator() * a.denominator(),
                          a.denominator() * b.denominator(), a.input_delay());
}

TransferFunction operator*(const TransferFunction& a, const TransferFunction& b) {
  return TransferFunction(a.numerator() * b.numerator(), a.denominator() * b.denominator(),
                          a.input_delay() + b.input_delay());
}

}  // namespace ctid
