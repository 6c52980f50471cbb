// Continuous-time filters applied to sampled signals, the kernel of the refined IV estimators
// (González et al., eqs. 10, 20, 22, 24, 31-32). One realisation of 1/D(p) yields every
// p^k/D(p) x, k = 0..deg D, in one pass; p^k B/A^2 is two cascaded banks. Signals are
// interpolated between samples by a zero-order hold (inputs) or linear interpolation
// (outputs), discretised exactly, and every filter starts at rest at the first sample.
#pragma once

#include <optional>

#include <Eigen/Core>

#include "ctid/core/hold.h"
#include "ctid/core/polynomial.h"

namespace ctid {

/// A single-input, multi-output continuous-time filter dz/dt = A z + b x, y = C z + d x
/// (r outputs). Built by the functions below; any realisation with consistent sizes works.
struct FilterRealization {
  Eigen::MatrixXd a;  ///< s x s
  Eigen::VectorXd b;  ///< s
  Eigen::MatrixXd c;  ///< r x s
  Eigen::VectorXd d;  ///< r

  int order() const { return static_cast<int>(a.rows()); }
  int outputs() const { return static_cast<int>(c.rows()); }
  /// Whether every entry of A, b, C and d is finite.
  bool finite() const;
  /// Throws InvalidArgument if the sizes disagree or an entry is not finite.
  void validate() const;
};

/// Outputs p^k / D(p) for k = 0..deg D (row k), from one controllable-form realisation of
/// 1/D in the time scale of the non-zero roots of D, then diagonally balanced. D may have
/// roots at the origin (D = p^l A for integrator submodels, Remark 5). Requires deg D >= 1.
FilterRealization derivative_filters(const Polynomial& denominator);

/// derivative_filters as a value (decision 0045): none when deg D < 1 or an entry of the
/// realisation is not finite (D's leading coefficient so small against the others that the
/// realisation overflows). For callers that steer on whether a model's filters exist, e.g. an
/// iterate whose A lost its leading coefficient; the same realisation when there is one.
std::optional<FilterRealization> finite_derivative_filters(const Polynomial& denominator);

/// Series connection: the first filter's outputs combined with `weights` (one per output of
/// `first`) drive `second`; the result has the outputs of `second`. E.g.
/// cascade(derivative_filters(A), b, derivative_filters(A)) gives p^k B / A^2.
FilterRealization cascade(const FilterRealization& first, const Eigen::VectorXd& weights,
                          const FilterRealization& second);

/// Reduces a realisation to one output: weights' * y.
FilterRealization combine_outputs(const FilterRealization& filter, const Eigen::VectorXd& weights);

/// A filter discretised exactly for one sample time and one interpolation; apply() runs the
/// per-sample state recursion from rest (no allocation per sample). Exact zeros of the
/// discretised state matrix and of C (block-triangular cascades, the diagonal outputs of a
/// derivative bank) are skipped, so a realisation with extra outputs costs little more.
class SampledFilter {
 public:
  /// Recursion state for feeding a record in consecutive pieces (run()): the filter state
  /// and the last sample seen (the first-order hold needs it to finish the next step).
  struct Stream {
    Eigen::VectorXd state;
    Eigen::VectorXd scratch;
    double previous = 0.0;
    double before_previous = 0.0;  // the sample before it (fractional delays)
    bool started = false;
  };

  /// `delay_fraction` f in [0, 1): the filter sees the interpolated signal delayed by f
  /// sample times, x(t - f h), zero before the first sample (discretize_delayed).
  SampledFilter(const FilterRealization& filter, double sample_time, Hold interpolation,
                double delay_fraction = 0.0);

  int order() const { return static_cast<int>(phi_.rows()); }
  int outputs() const { return static_cast<int>(c_.rows()); }

  /// out(k, j) = output j at t_k for the interpolated signal x; out must be N x outputs().
  void apply(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::MatrixXd> out) const;
  Eigen::MatrixXd apply(const Eigen::Ref<const Eigen::VectorXd>& x) const;

  /// A stream at rest before the first sample.
  Stream start() const;
  /// Feeds the next x.size() samples of the record: out(k, j) = output first_output + j at
  /// the k-th of them, for j < out.cols(). Pieces fed in order give exactly apply() of the
  /// whole record; memory stays O(order) whatever the record length.
  void run(const Eigen::Ref<const Eigen::VectorXd>& x, Stream& stream,
           Eigen::Ref<Eigen::MatrixXd> out, int first_output = 0) const;

 private:
  // S: the state dimension fixed at compile time (0: any). H > 0: rows [0, H) of phi have
  // their non-zeros in columns [0, H) (a cascade's zero upper right block).
  template <int S, int H>
  void run_fixed(const Eigen::Ref<const Eigen::VectorXd>& x, Stream& stream,
                 Eigen::Ref<Eigen::MatrixXd> out, int first_output) const;

  Eigen::MatrixXd phi_;     // column-major: the recursion adds phi(:, j) z_j
  Eigen::VectorXi phi_lo_;  // rows [lo, hi) of column j hold its non-zeros
  Eigen::VectorXi phi_hi_;
  bool split_ = false;              // phi's upper right order/2 x order/2 block is exactly zero
  Eigen::VectorXd gamma_previous_;  // weight of x_{k-1} (non-zero only for a delay fraction)
  Eigen::VectorXd gamma0_;          // weight of x_k
  Eigen::VectorXd gamma1_;          // weight of x_{k+1} (zero for the zero-order hold)
  bool fractional_ = false;         // gamma_previous_ is used
  double output_previous_ = 0.0;    // the delayed signal at t_k: these weights of x_{k-1}, x_k
  double output_current_ = 1.0;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> c_;
  Eigen::VectorXi c_lo_;  // columns [lo, hi) of row j hold its non-zeros
  Eigen::VectorXi c_hi_;
  Eigen::VectorXd d_;
};

/// Convenience: the N x (deg D + 1) matrix whose column k is p^k / D(p) x at the samples.
Eigen::MatrixXd filter_derivatives(const Polynomial& denominator,
                                   const Eigen::Ref<const Eigen::VectorXd>& x, double sample_time,
                                   Hold interpolation);

/// Shifts a sampled signal by `delay` samples: out_k = x_{k - delay}, zero before the start.
Eigen::VectorXd delay_samples(const Eigen::Ref<const Eigen::VectorXd>& x, int delay);

}  // namespace ctid
