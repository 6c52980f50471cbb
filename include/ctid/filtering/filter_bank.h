// Continuous-time filters applied to sampled signals, the kernel of the refined IV estimators
// (González et al., eqs. 10, 20, 22, 24, 31-32). One realisation of 1/D(p) yields every
// p^k/D(p) x, k = 0..deg D, in one pass; p^k B/A^2 is two cascaded banks. Signals are
// interpolated between samples by a zero-order hold (inputs) or linear interpolation
// (outputs), discretised exactly, and every filter starts at rest at the first sample.
#pragma once

#include <Eigen/Core>

#include "ctid/core/polynomial.h"

namespace ctid {

/// How a sampled signal is continued between the samples before it enters a
/// continuous-time filter.
enum class Interpolation {
  zero_order_hold,   ///< x(t) = x_k on [t_k, t_k+1): exact for ZOH inputs
  first_order_hold,  ///< x(t) linear between x_k and x_k+1 (the last sample is held)
};

/// A single-input, multi-output continuous-time filter dz/dt = A z + b x, y = C z + d x
/// (r outputs). Built by the functions below; any realisation with consistent sizes works.
struct FilterRealization {
  Eigen::MatrixXd a;  ///< s x s
  Eigen::VectorXd b;  ///< s
  Eigen::MatrixXd c;  ///< r x s
  Eigen::VectorXd d;  ///< r

  int order() const { return static_cast<int>(a.rows()); }
  int outputs() const { return static_cast<int>(c.rows()); }
  /// Throws InvalidArgument if the sizes disagree or an entry is not finite.
  void validate() const;
};

/// Outputs p^k / D(p) for k = 0..deg D (row k), from one controllable-form realisation of
/// 1/D in the time scale of the non-zero roots of D, then diagonally balanced. D may have
/// roots at the origin (D = p^l A for integrator submodels, Remark 5). Requires deg D >= 1.
FilterRealization derivative_filters(const Polynomial& denominator);

/// Series connection: the first filter's outputs combined with `weights` (one per output of
/// `first`) drive `second`; the result has the outputs of `second`. E.g.
/// cascade(derivative_filters(A), b, derivative_filters(A)) gives p^k B / A^2.
FilterRealization cascade(const FilterRealization& first, const Eigen::VectorXd& weights,
                          const FilterRealization& second);

/// Reduces a realisation to one output: weights' * y.
FilterRealization combine_outputs(const FilterRealization& filter, const Eigen::VectorXd& weights);

/// A filter discretised exactly for one sample time and one interpolation; apply() runs the
/// per-sample state recursion from rest (no allocation per sample).
class SampledFilter {
 public:
  SampledFilter(const FilterRealization& filter, double sample_time, Interpolation interpolation);

  int order() const { return static_cast<int>(phi_.rows()); }
  int outputs() const { return static_cast<int>(c_.rows()); }

  /// out(k, j) = output j at t_k for the interpolated signal x; out must be N x outputs().
  void apply(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::MatrixXd> out) const;
  Eigen::MatrixXd apply(const Eigen::Ref<const Eigen::VectorXd>& x) const;

 private:
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> phi_;
  Eigen::VectorXd gamma0_;  // weight of x_k
  Eigen::VectorXd gamma1_;  // weight of x_{k+1} (zero for the zero-order hold)
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> c_;
  Eigen::VectorXd d_;
};

/// Convenience: the N x (deg D + 1) matrix whose column k is p^k / D(p) x at the samples.
Eigen::MatrixXd filter_derivatives(const Polynomial& denominator,
                                   const Eigen::Ref<const Eigen::VectorXd>& x, double sample_time,
                                   Interpolation interpolation);

/// Shifts a sampled signal by `delay` samples: out_k = x_{k - delay}, zero before the start.
Eigen::VectorXd delay_samples(const Eigen::Ref<const Eigen::VectorXd>& x, int delay);

}  // namespace ctid
