// Continuous-time SISO transfer functions G(s) = e^{-s tau} N(s)/D(s), written in s or in
// the differential operator p = d/dt (the same object). Coefficients follow the ascending
// convention of polynomial.h.
#pragma once

#include <complex>
#include <string>

#include <Eigen/Core>

#include "ctid/core/polynomial.h"
#include "ctid/core/state_space.h"

namespace ctid {

class TransferFunction {
 public:
  /// Throws InvalidArgument for a zero denominator, non-finite coefficients or a negative
  /// or non-finite delay. Improper models are allowed as values but cannot be simulated.
  TransferFunction(Polynomial numerator, Polynomial denominator, double input_delay = 0.0);

  const Polynomial& numerator() const { return numerator_; }
  const Polynomial& denominator() const { return denominator_; }
  /// Input delay tau in seconds (>= 0).
  double input_delay() const { return input_delay_; }
  TransferFunction with_input_delay(double tau) const;

  Eigen::VectorXcd poles() const { return denominator_.roots(); }
  Eigen::VectorXcd zeros() const { return numerator_.roots(); }
  /// N(0)/D(0); +-infinity for a pole at the origin (NaN if N(0) = 0 too).
  double dc_gain() const;
  /// G(s) including the delay factor.
  std::complex<double> operator()(std::complex<double> s) const;
  /// G(j omega), omega in rad/s.
  std::complex<double> frequency_response(double omega) const;

  int relative_degree() const { return denominator_.degree() - numerator_.degree(); }
  bool is_proper() const { return relative_degree() >= 0; }
  bool is_strictly_proper() const { return relative_degree() > 0; }
  bool is_biproper() const { return relative_degree() == 0; }
  /// True when every pole has a negative real part.
  bool is_stable() const;

  /// Same transfer function with a monic denominator.
  TransferFunction normalized() const;

  /// A minimal, well-conditioned realisation (the delay is not part of it): a companion
  /// form in the scaled time t' = w0 t, w0 = |D(0)/D_n|^(1/n), mapped back by a diagonal
  /// similarity, then balanced, so entries stay of the size of the pole magnitudes.
  /// Requires a proper model.
  StateSpace to_state_space() const;
  /// The transfer function of a realisation (delay 0).
  static TransferFunction from_state_space(const StateSpace& model);

  std::string to_string() const;

 private:
  Polynomial numerator_;
  Polynomial denominator_;
  double input_delay_ = 0.0;
};

TransferFunction operator+(const TransferFunction& a, const TransferFunction& b);
TransferFunction operator*(const TransferFunction& a, const TransferFunction& b);

}  // namespace ctid
