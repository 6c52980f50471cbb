#include "ctid/core/discrete_transfer_function.h"

#include <cmath>

#include "ctid/core/controllable_form.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"

namespace ctid {

DiscreteTransferFunction::DiscreteTransferFunction(Polynomial numerator, Polynomial denominator,
                                                   double sample_time)
    : numerator_(std::move(numerator)),
      denominator_(std::move(denominator)),
      sample_time_(sample_time) {
  require(!denominator_.is_zero(), "discrete transfer function denominator is the zero polynomial");
  require(numerator_.degree() <= denominator_.degree(),
          "discrete transfer function must be proper (causal): numerator degree ",
          numerator_.degree(), " exceeds denominator degree ", denominator_.degree());
  require(std::isfinite(sample_time_) && sample_time_ > 0.0, "sample time is ", sample_time_,
          " s; it must be finite and > 0");
}

double DiscreteTransferFunction::dc_gain() const { return numerator_(1.0) / denominator_(1.0); }

std::complex<double> DiscreteTransferFunction::operator()(std::complex<double> z) const {
  return numerator_(z) / denominator_(z);
}

std::complex<double> DiscreteTransferFunction::frequency_response(double omega) const {
  return (*this)(std::polar(1.0, omega * sample_time_));
}

bool DiscreteTransferFunction::is_stable() const {
  const Eigen::VectorXcd p = poles();
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    if (!(std::abs(p(i)) < 1.0)) return false;
  }
  return true;
}

StateSpace DiscreteTransferFunction::to_state_space() const {
  return controllable_form(numerator_.coefficients(), denominator_.coefficients());
}

Eigen::VectorXd DiscreteTransferFunction::filter(const Eigen::VectorXd& x) const {
  // Difference equation D(q) y = N(q) x from rest, written with the delays of
  // q^{-n} D(q): y_k = (sum_j N_j x_{k-n+j} - sum_{j<n} D_j y_{k-n+j}) / D_n.
  const int n = denominator_.degree();
  const double lead = denominator_.leading();
  const Eigen::Index size = x.size();
  Eigen::VectorXd y(size);
  for (Eigen::Index k = 0; k < size; ++k) {
    double acc = 0.0;
    for (int j = 0; j <= numerator_.degree(); ++j) {
      const Eigen::Index i = k - n + j;
      if (i >= 0) acc += numerator_[j] * x(i);
    }
    for (int j = 0; j < n; ++j) {
      const Eigen::Index i = k - n + j;
      if (i >= 0) acc -= denominator_[j] * y(i);
    }
    y(k) = acc / lead;
  }
  return y;
}

std::string DiscreteTransferFunction::to_string() const {
  return "(" + numerator_.to_string("q") + ") / (" + denominator_.to_string("q") +
         "), h = " + format_number(sample_time_) + " s";
}

}  // namespace ctid
