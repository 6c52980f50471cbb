// ARMA models of a sampled noise sequence: the discrete-time noise part of the hybrid
// Box-Jenkins model behind RIVC (Young, Recursive Estimation and Time-Series Analysis, 2nd ed.,
// Chapter 8; Garnier and Young, 2014),
//   D(q^-1) v_t = C(q^-1) e_t,  D = 1 + d_1 q^-1 + ... + d_p q^-p,  C = 1 + c_1 q^-1 + ... + c_q
//   q^-q,
// e white. fit_arma minimises sum e_t^2 with e = (D/C) v run from rest at the first sample of
// each record (the conditional prediction error), by Gauss-Newton from the Hannan-Rissanen
// estimate (a long AR model, then least squares on its residuals), C kept invertible.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"

namespace ctid {

/// The largest AR or MA order fit_arma takes.
inline constexpr int kMaxArmaOrder = 20;

/// An ARMA(p, q) model of a noise sequence with its standard errors and spectrum.
struct ArmaModel {
  Eigen::VectorXd ar;  ///< D: [1, d_1, ..., d_p]
  Eigen::VectorXd ma;  ///< C: [1, c_1, ..., c_q]
  /// sum e^2 / (N - p - q) of the innovations e = (D/C) v.
  double innovation_variance = 0.0;
  /// Of [d_1..d_p, c_1..c_q]: innovation_variance (J'J)^-1, J the gradient of e; NaN where
  /// it cannot be formed (a sequence without noise).
  Eigen::MatrixXd covariance;
  Eigen::VectorXd standard_errors;  ///< sqrt of its diagonal
  /// Bayesian information criterion N ln(sum e^2 / N) + (p + q) ln N (orders chosen by it).
  double criterion = std::numeric_limits<double>::quiet_NaN();
  int iterations = 0;      ///< Gauss-Newton steps taken
  bool converged = false;  ///< the step fell below the tolerance within the iteration limit
  /// One-sided power spectral density of v, h sigma_e^2 |C/D|^2 (e^{-i 2 pi f h}) * 2, at
  /// `spectrum_frequencies` [Hz] from 0 to the Nyquist frequency (set by arma_spectrum).
  Eigen::VectorXd spectrum_frequencies;
  Eigen::VectorXd spectrum;

  int ar_order() const { return static_cast<int>(ar.size()) - 1; }
  int ma_order() const { return static_cast<int>(ma.size()) - 1; }

  static constexpr std::string_view type_name = "ArmaModel";
  static constexpr auto fields() {
    using S = ArmaModel;
    return std::tuple{
        field("ar", &S::ar, "D(q^-1): [1, d_1, ..., d_p]."),
        field("ma", &S::ma, "C(q^-1): [1, c_1, ..., c_q]."),
        field("innovation_variance", &S::innovation_variance,
              "sum e^2 / (N - p - q) of the innovations e = (D/C) v."),
        field("covariance", &S::covariance, "Of [d_1..d_p, c_1..c_q]."),
        field("standard_errors", &S::standard_errors, "sqrt of its diagonal."),
        field("criterion", &S::criterion, "BIC: N ln(sum e^2 / N) + (p + q) ln N."),
        field("iterations", &S::iterations, "Gauss-Newton steps taken."),
        field("converged", &S::converged, "The step fell below the tolerance."),
        field("spectrum_frequencies", &S::spectrum_frequencies,
              "Frequencies of `spectrum` [Hz], 0 to Nyquist."),
        field("spectrum", &S::spectrum,
              "One-sided power spectral density of v, 2 h sigma_e^2 |C/D|^2 [unit^2/Hz]."),
    };
  }
};

/// ARMA(ar_order, ma_order) of v. `record_starts` lists the first sample of each record after
/// the first (records are concatenated in v; the filters restart at each). Throws
/// InvalidArgument for orders outside [0, kMaxArmaOrder], a v that is not finite, or a record
/// too short for the orders (fewer than 10 (p + q) + 20 samples in all). A v of zeros gives
/// D = C = 1 with zero variance and NaN standard errors.
ArmaModel fit_arma(const Eigen::VectorXd& v, int ar_order, int ma_order,
                   const std::vector<Eigen::Index>& record_starts = {});

/// The orders in 0..max_order (each) with the smallest criterion, fitted; the same arguments
/// and checks as fit_arma.
ArmaModel fit_arma_by_criterion(const Eigen::VectorXd& v, int max_order,
                                const std::vector<Eigen::Index>& record_starts = {});

/// e = (D/C) v from rest at the start of v and of each record.
Eigen::VectorXd arma_innovations(const ArmaModel& model, const Eigen::VectorXd& v,
                                 const std::vector<Eigen::Index>& record_starts = {});

/// Sets model.spectrum_frequencies (`points` from 0 to 1 / (2 h)) and model.spectrum.
void arma_spectrum(ArmaModel& model, double sample_time, int points = 256);

/// (D/C) x column by column, continued from one block of rows to the next (one state per
/// column, direct form II transposed): the discrete prefilter of RIVC on streamed blocks.
class InverseNoiseFilter {
 public:
  InverseNoiseFilter(const ArmaModel& model, Eigen::Index columns);
  /// Back to rest (a new record).
  void reset() { state_.setZero(); }
  /// Filters the rows of `block` in place, in time order.
  void apply(Eigen::Ref<Eigen::MatrixXd> block);

 private:
  Eigen::VectorXd numerator_;    // D, padded to the filter's order + 1
  Eigen::VectorXd denominator_;  // C, likewise
  Eigen::MatrixXd state_;        // order x columns
};

}  // namespace ctid
