#include "ctid/core/additive_model.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numeric>
#include <optional>
#include <sstream>

#include "core/internal/finite_transfer_function.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"

namespace ctid {

namespace {

Polynomial integrator_factor(int l) { return Polynomial::monomial(l); }

void validate_submodels(const std::vector<Submodel>& submodels,
                        const std::vector<SubmodelOrder>& orders) {
  require(!submodels.empty(), "an additive model needs at least one submodel");
  int biproper = 0;
  int with_integrators = 0;
  for (size_t i = 0; i < submodels.size(); ++i) {
    const Submodel& s = submodels[i];
    const SubmodelOrder& o = orders[i];
    require(!s.a.is_zero() && s.a[0] == 1.0, "submodel ", i + 1,
            ": denominator A must be anti-monic (A(0) = 1); got A = ", s.a.to_string());
    require(s.integrators >= 0, "submodel ", i + 1, ": integrators is ", s.integrators,
            "; it must be >= 0");
    require(o.n >= 1 || s.integrators > 0, "submodel ", i + 1,
            ": denominator order n is 0 and there are no integrators; a submodel needs poles");
    require(o.m >= 0, "submodel ", i + 1, ": numerator order m is ", o.m, "; it must be >= 0");
    require(o.m <= o.n + s.integrators, "submodel ", i + 1, ": numerator order m = ", o.m,
            " exceeds the denominator order ", o.n + s.integrators, " (the model must be proper)");
    if (o.m == o.n + s.integrators) ++biproper;
    if (s.integrators > 0) ++with_integrators;
  }
  require(biproper <= 1, "an additive model may have at most one biproper submodel; got ",
          biproper);
  require(with_integrators <= 1,
          "an additive model may have poles at the origin in at most one submodel; got ",
          with_integrators);
}

std::vector<SubmodelOrder> orders_of(const std::vector<Submodel>& submodels) {
  std::vector<SubmodelOrder> orders;
  for (const Submodel& s : submodels) orders.push_back({s.n(), s.m(), s.integrators});
  return orders;
}

}  // namespace

TransferFunction Submodel::to_transfer_function() const {
  return TransferFunction(b, integrator_factor(integrators) * a);
}

AdditiveModel::AdditiveModel(std::vector<Submodel> submodels, double input_delay)
    : submodels_(std::move(submodels)), orders_(orders_of(submodels_)), input_delay_(input_delay) {
  for (size_t i = 0; i < submodels_.size(); ++i) {
    require(!submodels_[i].b.is_zero(), "submodel ", i + 1, ": numerator B is zero");
  }
  validate_submodels(submodels_, orders_);
  require(std::isfinite(input_delay_) && input_delay_ >= 0.0, "input delay is ", input_delay_,
          " s; it must be finite and >= 0");
}

AdditiveModel AdditiveModel::from_parameters(const std::vector<SubmodelOrder>& orders,
                                             const Eigen::VectorXd& theta, double input_delay) {
  int expected = 0;
  for (const SubmodelOrder& o : orders) {
    require(o.n >= 0 && o.m >= 0, "submodel orders must be >= 0; got n = ", o.n, ", m = ", o.m);
    expected += o.n + o.m + 1;
  }
  require(theta.size() == expected, "parameter vector has ", theta.size(),
          " entries; the orders need ", expected);
  require(theta.allFinite(), "parameter vector has a non-finite entry");
  std::vector<Submodel> submodels;
  Eigen::Index offset = 0;
  for (const SubmodelOrder& o : orders) {
    Eigen::VectorXd a(o.n + 1);
    a(0) = 1.0;
    a.tail(o.n) = theta.segment(offset, o.n);
    offset += o.n;
    Eigen::VectorXd b = theta.segment(offset, o.m + 1);
    offset += o.m + 1;
    submodels.push_back({Polynomial::trimmed(a), Polynomial::trimmed(b), o.integrators});
  }
  AdditiveModel model;
  model.submodels_ = std::move(submodels);
  model.orders_ = orders;
  model.input_delay_ = input_delay;
  require(std::isfinite(input_delay) && input_delay >= 0.0, "input delay is ", input_delay,
          " s; it must be finite and >= 0");
  validate_submodels(model.submodels_, model.orders_);
  return model;
}

namespace {

// The Polynomial operators' results, or none where their coefficients would not be finite (the
// operators throw there): from_transfer_function's arithmetic, without the exception.
std::optional<Polynomial> finite_scaled(double s, const Polynomial& p) {
  if (!std::isfinite(s)) return std::nullopt;
  if (s == 0.0) return Polynomial();
  const Eigen::VectorXd c = s * p.coefficients();
  if (!c.allFinite() || (c.size() > 1 && c(c.size() - 1) == 0.0)) return std::nullopt;
  return s * p;
}

std::optional<Polynomial> finite_sum(const Polynomial& a, const Polynomial& b) {
  const Eigen::Index n = std::max(a.coefficients().size(), b.coefficients().size());
  Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
  c.head(a.coefficients().size()) += a.coefficients();
  c.head(b.coefficients().size()) += b.coefficients();
  if (!c.allFinite()) return std::nullopt;
  return a + b;
}

std::optional<Polynomial> finite_product(const Polynomial& a, const Polynomial& b) {
  if (a.is_zero() || b.is_zero()) return Polynomial();
  Eigen::VectorXd c = Eigen::VectorXd::Zero(a.coefficients().size() + b.coefficients().size() - 1);
  for (Eigen::Index i = 0; i < a.coefficients().size(); ++i) {
    c.segment(i, b.coefficients().size()) += a.coefficients()(i) * b.coefficients();
  }
  if (!c.allFinite()) return std::nullopt;
  return a * b;
}

// Polynomial(c) when c is finite with a non-zero leading coefficient.
std::optional<Polynomial> exact_polynomial(const Eigen::VectorXd& c) {
  if (!c.allFinite() || c.size() == 0 || c(c.size() - 1) == 0.0) return std::nullopt;
  return Polynomial(c);
}

std::optional<Polynomial> trimmed_polynomial(const Eigen::VectorXd& c) {
  if (!c.allFinite()) return std::nullopt;
  return Polynomial::trimmed(c);
}

// The derivative of a polynomial, or none where k a_k is not finite.
std::optional<Polynomial> finite_derivative(const Polynomial& p) {
  for (int k = 1; k <= p.degree(); ++k) {
    if (!std::isfinite(k * p[k])) return std::nullopt;
  }
  return p.derivative();
}

// The first pole (in order) that another one repeats, if any.
std::optional<std::complex<double>> repeated_pole(const Eigen::VectorXcd& poles) {
  for (Eigen::Index i = 0; i < poles.size(); ++i) {
    for (Eigen::Index j = i + 1; j < poles.size(); ++j) {
      if (!(std::abs(poles(i) - poles(j)) > 1e-6 * std::max(std::abs(poles(i)), 1e-300))) {
        return poles(i);
      }
    }
  }
  return std::nullopt;
}

// B + d p^l A: the submodel's numerator with the direct term d joined to it (biproper), or
// none where that overflows.
std::optional<Polynomial> with_direct_term(const Submodel& s, double d) {
  const std::optional<Polynomial> scaled = finite_scaled(d, integrator_factor(s.integrators));
  const std::optional<Polynomial> product = scaled ? finite_product(*scaled, s.a) : std::nullopt;
  return product ? finite_sum(s.b, *product) : std::nullopt;
}

}  // namespace

AdditiveModel AdditiveModel::from_transfer_function(const TransferFunction& g,
                                                    double imag_tolerance) {
  std::string failure;
  std::optional<AdditiveModel> model = split_transfer_function(g, imag_tolerance, &failure);
  require(model.has_value(), failure);
  return std::move(*model);
}

std::optional<AdditiveModel> AdditiveModel::split_transfer_function(const TransferFunction& g,
                                                                    double imag_tolerance,
                                                                    std::string* failure) {
  const auto fail = [failure](auto&&... parts) -> std::optional<AdditiveModel> {
    if (failure != nullptr) *failure = internal::concat(parts...);
    return std::nullopt;
  };
  if (!g.is_proper()) return fail("cannot split an improper transfer function into submodels");
  if (g.denominator().degree() < 1) return fail("a constant transfer function has no submodels");
  const Polynomial& den = g.denominator();
  const double d = g.numerator().coefficient(den.degree()) / den.leading();
  const std::optional<Polynomial> direct_part = finite_scaled(d, den);
  const std::optional<Polynomial> remainder_or =
      direct_part ? finite_sum(g.numerator(), -*direct_part) : std::nullopt;
  const std::optional<Polynomial> den_derivative_or = finite_derivative(den);
  if (!remainder_or || !den_derivative_or) {
    return fail("the transfer function's coefficients overflow its partial-fraction split");
  }
  const Polynomial& remainder = *remainder_or;

  // Poles at the origin are the exact zero low-order coefficients of D.
  int l = 0;
  while (den[l] == 0.0) ++l;
  Eigen::VectorXd reduced_coeffs = den.coefficients().tail(den.degree() + 1 - l);
  const Polynomial reduced(reduced_coeffs);  // D = s^l D'
  const Eigen::VectorXcd poles = reduced.roots();
  const Polynomial& den_derivative = *den_derivative_or;

  if (const std::optional<std::complex<double>> repeated = repeated_pole(poles)) {
    return fail("the transfer function has a repeated pole near ", repeated->real(), " + ",
                repeated->imag(),
                "j; partial fractions into additive submodels need distinct poles");
  }
  const auto overflow = [&fail](const std::complex<double>& pole) {
    return fail("the partial fraction of pole ", pole.real(), " + ", pole.imag(),
                "j is not finite");
  };

  struct Piece {
    double magnitude;
    Submodel submodel;
  };
  std::vector<Piece> pieces;
  if (l > 0) {
    // Principal part at the origin P(s)/s^l: P = R / D' truncated to l terms of its series.
    Eigen::VectorXd p = Eigen::VectorXd::Zero(l);
    for (int k = 0; k < l; ++k) {
      double acc = remainder[k];
      for (int j = 1; j <= k; ++j) acc -= reduced[j] * p(k - j);
      p(k) = acc / reduced[0];
    }
    const std::optional<Polynomial> b = trimmed_polynomial(p);
    if (!b) return overflow(0.0);
    pieces.push_back({0.0, {Polynomial::constant(1.0), *b, l}});
  }
  std::vector<bool> used(static_cast<size_t>(poles.size()), false);
  for (Eigen::Index i = 0; i < poles.size(); ++i) {
    if (used[static_cast<size_t>(i)]) continue;
    used[static_cast<size_t>(i)] = true;
    const std::complex<double> pole = poles(i);
    const std::complex<double> residue = remainder(pole) / den_derivative(pole);
    const double magnitude = std::abs(pole);
    if (std::abs(pole.imag()) <= imag_tolerance * magnitude) {
      // r/(s - p) = (-r/p) / (1 - s/p).
      const double p = pole.real();
      const std::optional<Polynomial> a = exact_polynomial(Eigen::Vector2d(1.0, -1.0 / p));
      const std::optional<Polynomial> b =
          trimmed_polynomial(Eigen::VectorXd::Constant(1, -residue.real() / p));
      if (!a || !b) return overflow(pole);
      pieces.push_back({magnitude, {*a, *b, 0}});
      continue;
    }
    // Pair with the conjugate.
    Eigen::Index partner = -1;
    double best = INFINITY;
    for (Eigen::Index j = 0; j < poles.size(); ++j) {
      if (used[static_cast<size_t>(j)]) continue;
      const double distance = std::abs(poles(j) - std::conj(pole));
      if (distance < best) {
        best = distance;
        partner = j;
      }
    }
    if (!(partner >= 0 && best <= 1e-6 * magnitude)) {
      return fail("complex pole ", pole.real(), " + ", pole.imag(), "j has no conjugate partner");
    }
    used[static_cast<size_t>(partner)] = true;
    // r/(s-p) + conj(r)/(s-conj p) = (2Re(r) s - 2Re(r conj p)) / (s^2 - 2Re(p) s + |p|^2).
    const double m2 = std::norm(pole);
    Eigen::Vector2d b(-2.0 * (residue * std::conj(pole)).real() / m2, 2.0 * residue.real() / m2);
    const std::optional<Polynomial> a =
        exact_polynomial(Eigen::Vector3d(1.0, -2.0 * pole.real() / m2, 1.0 / m2));
    const std::optional<Polynomial> numerator = trimmed_polynomial(b);
    if (!a || !numerator) return overflow(pole);
    pieces.push_back({magnitude, {*a, *numerator, 0}});
  }
  std::stable_sort(pieces.begin(), pieces.end(),
                   [](const Piece& x, const Piece& y) { return x.magnitude < y.magnitude; });
  if (d != 0.0) {
    Submodel& first = pieces.front().submodel;
    std::optional<Polynomial> b = with_direct_term(first, d);
    if (!b) return fail("the direct term ", d, " overflows the first submodel's numerator");
    first.b = std::move(*b);
  }
  std::vector<Submodel> submodels;
  for (Piece& piece : pieces) {
    submodels.push_back(std::move(piece.submodel));
  }
  // A submodel whose residue vanished keeps a zero numerator, of order 0 in orders_.
  AdditiveModel model;
  model.submodels_ = std::move(submodels);
  model.orders_.clear();
  for (const Submodel& s : model.submodels_) {
    model.orders_.push_back({s.n(), std::max(s.m(), 0), s.integrators});
  }
  model.input_delay_ = g.input_delay();
  validate_submodels(model.submodels_, model.orders_);  // holds by construction
  return model;
}

AdditiveModel AdditiveModel::with_input_delay(double tau) const {
  require(std::isfinite(tau) && tau >= 0.0, "input delay is ", tau,
          " s; it must be finite and >= 0");
  AdditiveModel copy = *this;
  copy.input_delay_ = tau;
  return copy;
}

std::vector<SubmodelOrder> AdditiveModel::orders() const { return orders_; }

int AdditiveModel::parameter_count() const {
  return std::accumulate(orders_.begin(), orders_.end(), 0,
                         [](int acc, const SubmodelOrder& o) { return acc + o.n + o.m + 1; });
}

Eigen::VectorXd AdditiveModel::parameters() const {
  Eigen::VectorXd theta(parameter_count());
  Eigen::Index offset = 0;
  for (size_t i = 0; i < submodels_.size(); ++i) {
    const SubmodelOrder& o = orders_[i];
    for (int k = 1; k <= o.n; ++k) theta(offset++) = submodels_[i].a[k];
    for (int k = 0; k <= o.m; ++k) theta(offset++) = submodels_[i].b[k];
  }
  return theta;
}

std::vector<std::string> AdditiveModel::parameter_names() const {
  std::vector<std::string> names;
  for (size_t i = 0; i < orders_.size(); ++i) {
    const std::string prefix = "theta" + std::to_string(i + 1) + ".";
    for (int k = 1; k <= orders_[i].n; ++k) names.push_back(prefix + "a" + std::to_string(k));
    for (int k = 0; k <= orders_[i].m; ++k) names.push_back(prefix + "b" + std::to_string(k));
  }
  return names;
}

AdditiveModel AdditiveModel::with_parameters(const Eigen::VectorXd& theta) const {
  return from_parameters(orders_, theta, input_delay_);
}

TransferFunction AdditiveModel::to_transfer_function() const {
  std::optional<TransferFunction> g = internal::transfer_function_if_finite(*this);
  if (!g) {  // the message only when it is needed (require would format the model every time)
    throw InvalidArgument(internal::concat("the transfer function of ", to_string(),
                                           " overflows: its coefficients are not finite"));
  }
  return std::move(*g);
}

namespace internal {

std::optional<TransferFunction> transfer_function_if_finite(const AdditiveModel& model) {
  Polynomial num;
  Polynomial den = Polynomial::constant(1.0);
  for (const Submodel& s : model.submodels()) {
    const std::optional<Polynomial> a = finite_product(integrator_factor(s.integrators), s.a);
    if (!a) return std::nullopt;
    const std::optional<Polynomial> left = finite_product(num, *a);
    const std::optional<Polynomial> right = finite_product(s.b, den);
    const std::optional<Polynomial> sum = left && right ? finite_sum(*left, *right) : std::nullopt;
    const std::optional<Polynomial> next = finite_product(den, *a);
    if (!sum || !next) return std::nullopt;
    num = *sum;
    den = *next;
  }
  if (den.is_zero()) return std::nullopt;
  return TransferFunction(num, den, model.input_delay());
}

}  // namespace internal

std::complex<double> AdditiveModel::frequency_response(double omega) const {
  const std::complex<double> s(0.0, omega);
  std::complex<double> sum = 0.0;
  for (const Submodel& m : submodels_) {
    sum += m.b(s) / (std::pow(s, m.integrators) * m.a(s));
  }
  return sum * std::exp(-s * input_delay_);
}

std::optional<ModalParameters> AdditiveModel::modal_parameters(int i) const {
  require(i >= 0 && i < size(), "submodel index ", i, " is out of range [0, ", size(), ")");
  const Submodel& s = submodels_[static_cast<size_t>(i)];
  if (s.n() != 2 || s.integrators != 0 || !(s.a[2] > 0.0)) return std::nullopt;
  ModalParameters modal;
  modal.natural_frequency = 1.0 / std::sqrt(s.a[2]);
  modal.damping_ratio = s.a[1] / (2.0 * std::sqrt(s.a[2]));
  modal.gain = s.b[0];
  return modal;
}

std::string Submodel::to_string() const {
  std::string text = "(" + b.to_string() + ") / ";
  if (integrators == 0) return text + "(" + a.to_string() + ")";
  const std::string origin = integrators == 1 ? "s" : "s^" + std::to_string(integrators);
  if (a.degree() == 0 && a[0] == 1.0) return text + origin;
  return text + "(" + origin + " (" + a.to_string() + "))";
}

std::string AdditiveModel::to_string() const {
  std::string text;
  for (size_t i = 0; i < submodels_.size(); ++i) {
    if (i > 0) text += " + ";
    text += submodels_[i].to_string();
  }
  if (input_delay_ != 0.0) text += ", input delay " + format_brief(input_delay_) + " s";
  return text;
}

}  // namespace ctid
