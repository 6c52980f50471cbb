#include "ctid/core/controllable_form.h"

namespace ctid {

StateSpace controllable_form(const Eigen::VectorXd& numerator, const Eigen::VectorXd& denominator) {
  const Eigen::Index n = denominator.size() - 1;
  const double lead = denominator(n);
  const auto num = [&](Eigen::Index k) { return k < numerator.size() ? numerator(k) : 0.0; };
  StateSpace ss;
  ss.d = num(n) / lead;
  ss.a = Eigen::MatrixXd::Zero(n, n);
  ss.b = Eigen::VectorXd::Zero(n);
  ss.c = Eigen::RowVectorXd::Zero(n);
  if (n == 0) return ss;
  ss.a.diagonal(1).setOnes();
  for (Eigen::Index k = 0; k < n; ++k) ss.a(n - 1, k) = -denominator(k) / lead;
  ss.b(n - 1) = 1.0;
  for (Eigen::Index k = 0; k < n; ++k) ss.c(k) = (num(k) - ss.d * denominator(k)) / lead;
  return ss;
}

}  // namespace ctid
