// The per-sample kernel of every simulation: x_{k+1} = A x_k + B u_k, y_k = C x_k + D u_k
// for a SISO discrete realisation. Storage is allocated once; stepping never allocates, and
// A is kept row-major so that each new state entry is one contiguous dot product.
#pragma once

#include <Eigen/Core>

#include "ctid/core/state_space.h"

namespace ctid::internal {

class StateRecursion {
 public:
  explicit StateRecursion(const StateSpace& discrete)
      : a_(discrete.a),
        b_(discrete.b),
        c_(discrete.c),
        d_(discrete.d),
        x_(Eigen::VectorXd::Zero(discrete.order())),
        next_(Eigen::VectorXd::Zero(discrete.order())) {}

  int order() const { return static_cast<int>(x_.size()); }
  double feedthrough() const { return d_; }
  /// C x_k, the part of y_k that does not depend on u_k.
  double state_output() const {
    const double* c = c_.data();
    const double* x = x_.data();
    double sum = 0.0;
    for (Eigen::Index i = 0; i < x_.size(); ++i) sum += c[i] * x[i];
    return sum;
  }
  double output(double u) const { return state_output() + d_ * u; }
  /// x_{k+1} = A x_k + B u_k.
  void advance(double u) {
    const Eigen::Index n = x_.size();
    const double* a = a_.data();
    const double* b = b_.data();
    const double* x = x_.data();
    double* next = next_.data();
    for (Eigen::Index i = 0; i < n; ++i) {
      const double* row = a + i * n;
      double sum = b[i] * u;
      for (Eigen::Index j = 0; j < n; ++j) sum += row[j] * x[j];
      next[i] = sum;
    }
    x_.swap(next_);
  }
  void reset() { x_.setZero(); }

  /// y[k] (+)= response to u[0..count) from the current state.
  void run(const double* u, double* y, Eigen::Index count, bool accumulate) {
    for (Eigen::Index k = 0; k < count; ++k) {
      const double value = output(u[k]);
      y[k] = accumulate ? y[k] + value : value;
      advance(u[k]);
    }
  }

 private:
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> a_;
  Eigen::VectorXd b_;
  Eigen::RowVectorXd c_;
  double d_;
  Eigen::VectorXd x_;
  Eigen::VectorXd next_;
};

}  // namespace ctid::internal
