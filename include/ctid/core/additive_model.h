// Additive continuous-time models G(p) = e^{-p tau} sum_i B_i(p) / (p^{l_i} A_i(p))
// (González et al., eqs. 1-3 and Remark 5). Each denominator is anti-monic,
// A_i(p) = 1 + a_i1 p + ... + a_in p^n, and a submodel's parameters are
// theta_i = [a_i1 ... a_in, b_i0 ... b_im] (coefficient of p first). At most one submodel is
// biproper and at most one carries poles at the origin (l_i > 0).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/core/polynomial.h"
#include "ctid/core/transfer_function.h"

namespace ctid {

struct Submodel {
  Polynomial a;  ///< anti-monic denominator A_i, a[0] == 1, degree n_i >= 1 (or 0 if l_i > 0)
  Polynomial b;  ///< numerator B_i, degree m_i
  int integrators = 0;  ///< l_i, poles at the origin, the factor 1/p^{l_i}

  int n() const { return a.degree(); }
  int m() const { return b.degree(); }
  /// n_i + m_i + 1 parameters (the 1 of A_i is fixed).
  int parameter_count() const { return n() + m() + 1; }
  bool is_biproper() const { return m() == n() + integrators; }
  TransferFunction to_transfer_function() const;
  /// B_i over p^l_i A_i in the printed form of docs/conventions.md: "(3.03) / (0.5 s^2 + 0.25 s +
  /// 1)", with integrators "(2) / (s (0.1 s + 1))" or "(2) / s^2" (no poles besides the origin).
  std::string to_string() const;
};

/// Modal parameters of a second-order submodel B(p)/(1 + a1 p + a2 p^2):
/// natural frequency w_n = 1/sqrt(a2) [rad/s], damping ratio zeta = a1/(2 sqrt(a2)),
/// and static (modal) gain B(0).
struct ModalParameters {
  double natural_frequency = 0.0;
  double damping_ratio = 0.0;
  double gain = 0.0;

  static constexpr std::string_view type_name = "ModalParameters";
  static constexpr auto fields() {
    using S = ModalParameters;
    return std::tuple{
        field("natural_frequency", &S::natural_frequency, "Natural frequency w_n [rad/s]."),
        field("damping_ratio", &S::damping_ratio, "Damping ratio zeta."),
        field("gain", &S::gain, "Static (modal) gain B(0)."),
    };
  }
};

/// How a submodel structure is asked for: orders (n_i, m_i) and poles at the origin.
struct SubmodelOrder {
  int n = 2;
  int m = 0;
  int integrators = 0;

  static constexpr std::string_view type_name = "SubmodelOrder";
  static constexpr auto fields() {
    return std::tuple{
        field("n", &SubmodelOrder::n, AtLeast{0}, "Degree of A_i (poles besides the origin)."),
        field("m", &SubmodelOrder::m, AtLeast{0}, "Degree of B_i (zeros)."),
        field("integrators", &SubmodelOrder::integrators, AtLeast{0},
              "l_i, poles at the origin (the factor 1/p^l_i)."),
    };
  }
  void validate() const { validate_fields(*this); }
};

class AdditiveModel {
 public:
  /// Validates every rule of the parameterisation; throws InvalidArgument naming the
  /// submodel and the rule.
  explicit AdditiveModel(std::vector<Submodel> submodels, double input_delay = 0.0);

  /// Builds a model from the stacked parameter vector theta = [theta_1; ...; theta_K].
  /// The orders are kept even where a leading coefficient of theta is exactly zero, so
  /// parameters() gives back a vector of the same layout.
  static AdditiveModel from_parameters(const std::vector<SubmodelOrder>& orders,
                                       const Eigen::VectorXd& theta, double input_delay = 0.0);

  /// Partial-fraction split of an unfactored model: real poles give first-order
  /// submodels, complex pairs second-order modes, poles at the origin one integrator
  /// submodel (B/p^l); a direct feedthrough is added to the numerator of the
  /// lowest-frequency submodel, making it biproper. Submodels are sorted by pole
  /// magnitude. Poles with |Im| <= imag_tolerance * |pole| count as real. Requires
  /// distinct non-zero poles (repeated poles throw InvalidArgument).
  static AdditiveModel from_transfer_function(const TransferFunction& g,
                                              double imag_tolerance = 1e-8);
  /// from_transfer_function's split as a value: none when the poles cannot be split (a repeated
  /// pole, a complex pole without its conjugate, coefficients that overflow) or `g` is improper
  /// or constant, with the reason in `failure` if given. Callers that steer on whether a model
  /// splits use this; from_transfer_function throws the same reason (decision 0045).
  static std::optional<AdditiveModel> split_transfer_function(const TransferFunction& g,
                                                              double imag_tolerance = 1e-8,
                                                              std::string* failure = nullptr);

  const std::vector<Submodel>& submodels() const { return submodels_; }
  int size() const { return static_cast<int>(submodels_.size()); }
  const Submodel& operator[](int i) const { return submodels_.at(static_cast<size_t>(i)); }
  double input_delay() const { return input_delay_; }
  AdditiveModel with_input_delay(double tau) const;
  std::vector<SubmodelOrder> orders() const;

  int parameter_count() const;
  Eigen::VectorXd parameters() const;
  /// The name of each parameter, in parameters() order: "theta<i>.a<k>" and "theta<i>.b<k>",
  /// submodels counted from 1 (theta1.a1, theta1.a2, theta1.b0, theta2.a1, ...).
  std::vector<std::string> parameter_names() const;
  AdditiveModel with_parameters(const Eigen::VectorXd& theta) const;

  /// The sum as one transfer function (common denominator, input delay kept).
  TransferFunction to_transfer_function() const;
  /// sum_i G_i(j omega) e^{-j omega tau}.
  std::complex<double> frequency_response(double omega) const;

  /// Modal parameters of submodel i if it is second order with complex poles and no
  /// integrators; std::nullopt otherwise.
  std::optional<ModalParameters> modal_parameters(int i) const;

  /// The submodels' to_string() joined by " + ", then ", input delay 0.1 s" if there is one.
  std::string to_string() const;

 private:
  AdditiveModel() = default;

  std::vector<Submodel> submodels_;
  std::vector<SubmodelOrder> orders_;  // may exceed the degrees if leading coefficients are 0
  double input_delay_ = 0.0;
};

}  // namespace ctid
