// Exact ZOH and FOH discretisation through one matrix exponential of an augmented matrix
// (Van Loan's construction): the blocks of exp(M h) are exactly the integrals needed, with no
// inverse of A, so integrators (singular A) need no special case.
#include "ctid/simulation/discretization.h"

#include <cmath>
#include <utility>

#include <unsupported/Eigen/MatrixFunctions>

#include "ctid/core/error.h"

namespace ctid {
namespace {

void check_arguments(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double h,
                     const char* function) {
  require(a.rows() == a.cols(), function, ": A must be square, got ", a.rows(), " x ", a.cols());
  require(b.rows() == a.rows(), function, ": B must have as many rows as A (", a.rows(), "), got ",
          b.rows());
  require(b.cols() >= 1, function, ": B must have at least one column, got 0");
  require(std::isfinite(h) && h > 0.0, function,
          ": sample time h must be positive and finite, got ", h);
  require(a.allFinite(), function, ": A has a non-finite entry");
  require(b.allFinite(), function, ": B has a non-finite entry");
}

}  // namespace

ZohDiscretization discretize_zoh(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double h) {
  check_arguments(a, b, h, "discretize_zoh");
  const Eigen::Index n = a.rows();
  const Eigen::Index m = b.cols();
  // exp([[A, B], [0, 0]] h) = [[e^{Ah}, int_0^h e^{As} ds B], [0, I]].
  Eigen::MatrixXd augmented = Eigen::MatrixXd::Zero(n + m, n + m);
  augmented.topLeftCorner(n, n) = a * h;
  augmented.topRightCorner(n, m) = b * h;
  const Eigen::MatrixXd e = augmented.exp();
  ZohDiscretization result;
  result.phi = e.topLeftCorner(n, n);
  result.gamma = e.topRightCorner(n, m);
  return result;
}

FohDiscretization discretize_foh(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, double h) {
  check_arguments(a, b, h, "discretize_foh");
  const Eigen::Index n = a.rows();
  const Eigen::Index m = b.cols();
  // With u(t_k + s) = u_k + (u_{k+1} - u_k) s / h, x_{k+1} = Phi x_k + G0 u_k + G1 (u_{k+1} - u_k),
  // G0 = int_0^h e^{A(h-s)} ds B and G1 = (1/h) int_0^h e^{A(h-s)} s ds B. Both are blocks of
  // exp(M h), M = [[A, B, 0], [0, 0, I/h], [0, 0, 0]].
  Eigen::MatrixXd augmented = Eigen::MatrixXd::Zero(n + 2 * m, n + 2 * m);
  augmented.topLeftCorner(n, n) = a * h;
  augmented.block(0, n, n, m) = b * h;
  augmented.block(n, n + m, m, m).setIdentity();
  const Eigen::MatrixXd e = augmented.exp();
  const Eigen::MatrixXd g0 = e.block(0, n, n, m);
  const Eigen::MatrixXd g1 = e.block(0, n + m, n, m);
  FohDiscretization result;
  result.phi = e.topLeftCorner(n, n);
  result.gamma0 = g0 - g1;
  result.gamma1 = g1;
  return result;
}

DelayedHoldDiscretization discretize_delayed(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                             double h, double fraction, Hold hold) {
  check_arguments(a, b, h, "discretize_delayed");
  require(std::isfinite(fraction) && fraction >= 0.0 && fraction < 1.0,
          "discretize_delayed: the delay fraction is ", fraction, "; it must be in [0, 1)");
  const Eigen::Index n = a.rows();
  const Eigen::Index m = b.cols();
  const double f = fraction;
  DelayedHoldDiscretization r;
  r.next = Eigen::MatrixXd::Zero(n, m);
  r.previous = Eigen::MatrixXd::Zero(n, m);
  if (hold == Hold::zero_order_hold) {
    if (f == 0.0) {
      ZohDiscretization whole = discretize_zoh(a, b, h);
      r.phi = std::move(whole.phi);
      r.current = std::move(whole.gamma);
      return r;
    }
    // u_{k-1} on [t_k, t_k + f h), u_k on the rest.
    const ZohDiscretization first = discretize_zoh(a, b, f * h);
    const ZohDiscretization second = discretize_zoh(a, b, (1.0 - f) * h);
    r.phi = second.phi * first.phi;
    r.previous = second.phi * first.gamma;
    r.current = second.gamma;
    return r;
  }
  if (f == 0.0) {
    FohDiscretization whole = discretize_foh(a, b, h);
    r.phi = std::move(whole.phi);
    r.current = std::move(whole.gamma0);
    r.next = std::move(whole.gamma1);
    return r;
  }
  // On [t_k, t_k + f h) the line from f u_{k-1} + (1 - f) u_k to u_k; on the rest the line
  // from u_k to f u_k + (1 - f) u_{k+1}.
  const FohDiscretization first = discretize_foh(a, b, f * h);
  const FohDiscretization second = discretize_foh(a, b, (1.0 - f) * h);
  r.phi = second.phi * first.phi;
  r.previous = f * second.phi * first.gamma0;
  r.current =
      second.phi * ((1.0 - f) * first.gamma0 + first.gamma1) + second.gamma0 + f * second.gamma1;
  r.next = (1.0 - f) * second.gamma1;
  return r;
}

DelayedSample delayed_sample(double fraction, Hold hold) {
  if (fraction == 0.0) return {0.0, 1.0};
  if (hold == Hold::zero_order_hold) return {1.0, 0.0};
  return {fraction, 1.0 - fraction};
}

StateSpace discretize_zoh(const StateSpace& model, double h, double fraction) {
  model.validate();
  if (fraction == 0.0) return discretize_zoh(model, h);
  const DelayedHoldDiscretization w =
      discretize_delayed(model.a, model.b, h, fraction, Hold::zero_order_hold);
  const int n = model.order();
  // States [x; u_{k-1}].
  StateSpace result;
  result.a = Eigen::MatrixXd::Zero(n + 1, n + 1);
  result.a.topLeftCorner(n, n) = w.phi;
  result.a.block(0, n, n, 1) = w.previous;
  result.b = Eigen::VectorXd::Zero(n + 1);
  result.b.head(n) = w.current.col(0);
  result.b(n) = 1.0;
  result.c = Eigen::RowVectorXd::Zero(n + 1);
  result.c.head(n) = model.c;
  result.c(n) = model.d;
  result.d = 0.0;
  return result;
}

StateSpace discretize_zoh(const StateSpace& model, double h) {
  model.validate();
  ZohDiscretization zoh = discretize_zoh(model.a, model.b, h);
  StateSpace result;
  result.a = std::move(zoh.phi);
  result.b = zoh.gamma.col(0);
  result.c = model.c;
  result.d = model.d;
  return result;
}

}  // namespace ctid
