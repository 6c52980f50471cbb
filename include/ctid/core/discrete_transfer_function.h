// Discrete-time SISO transfer functions in the shift operator q (q x_k = x_{k+1}),
// G(q) = N(q)/D(q) with ascending coefficients in q (polynomial.h). Used for controllers
// C_d(q), such as the PID of González et al. Section 6.2, and noise filters such as
// (q + 0.5)/(q - 0.85).
#pragma once

#include <complex>
#include <string>

#include <Eigen/Core>

#include "ctid/core/polynomial.h"
#include "ctid/core/state_space.h"

namespace ctid {

class DiscreteTransferFunction {
 public:
  /// Requires a proper model (deg N <= deg D), a positive finite sample time and finite
  /// coefficients.
  DiscreteTransferFunction(Polynomial numerator, Polynomial denominator, double sample_time);

  const Polynomial& numerator() const { return numerator_; }
  const Polynomial& denominator() const { return denominator_; }
  double sample_time() const { return sample_time_; }

  Eigen::VectorXcd poles() const { return denominator_.roots(); }
  Eigen::VectorXcd zeros() const { return numerator_.roots(); }
  /// N(1)/D(1).
  double dc_gain() const;
  std::complex<double> operator()(std::complex<double> z) const;
  /// G(e^{j omega h}), omega in rad/s.
  std::complex<double> frequency_response(double omega) const;
  bool is_biproper() const { return numerator_.degree() == denominator_.degree(); }
  /// All poles strictly inside the unit circle.
  bool is_stable() const;

  /// Controllable-form realisation x_{k+1} = A x_k + B u_k, y_k = C x_k + D u_k.
  StateSpace to_state_space() const;
  /// y = G(q) x from rest (zero initial state).
  Eigen::VectorXd filter(const Eigen::VectorXd& x) const;

  std::string to_string() const;

 private:
  Polynomial numerator_;
  Polynomial denominator_;
  double sample_time_;
};

}  // namespace ctid
