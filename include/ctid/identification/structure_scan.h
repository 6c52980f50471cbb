// Choosing the structure without knowing it: fit a list of candidate structures with
// identify(), score each on the estimation data and on a held-out end of the record, with the
// order-selection statistics of CONTSID's srivcstruc (YIC, RT2; Young 2011, Recursive
// Estimation and Time-Series Analysis, Ch. 8) and the classical AIC and BIC, and recommend one
// by a stated rule. For modal scans the poles of every fit form a stabilisation diagram
// (natural frequency against order, each pole marked stable in frequency and damping when the
// previous order has a pole close to it), as modal-analysis tools draw it.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"
#include "ctid/estimation/termination.h"
#include "ctid/identification/identification.h"

namespace ctid {

struct StructureScanOptions {
  /// Share of the record, at its end, held out to score the validation fit: each estimate is
  /// simulated over the whole record from rest (or, when identification estimates initial
  /// conditions, from the state fitted on the estimation part) and scored on that part only.
  /// 0: score on the estimation data. In [0, 0.9].
  double validation_fraction = 0.3;
  /// Parsimony: the recommended structure is the one with the fewest parameters whose
  /// held-out mean squared error is at most (1 + error_tolerance) times the best usable one's.
  /// None: 2 sqrt(2 / N_v), twice the relative standard deviation of the mean square of N_v
  /// white-noise samples (N_v held out, or fitted when nothing is held out), so a smaller
  /// model is kept only when its extra error is within what the noise alone would make
  /// (decision 0015). >= 0.
  std::optional<double> error_tolerance;
  /// Stabilisation diagram: a pole is stable in frequency (damping) when the previous order
  /// has a pole within this relative distance of its natural frequency (damping ratio). > 0.
  double frequency_tolerance = 0.01;
  double damping_tolerance = 0.05;
  /// Options of every fit (controller, delay, estimator options).
  IdentificationOptions identification;

  static constexpr std::string_view type_name = "StructureScanOptions";
  static constexpr auto fields() {
    using O = StructureScanOptions;
    return std::tuple{
        field("validation_fraction", &O::validation_fraction, Between{0.0, 0.9, true, true},
              "Share of the record, at its end, used to score the validation fit (0: none)."),
        field("error_tolerance", &O::error_tolerance, Finite{AtLeast{0.0}},
              "Relative held-out error increase accepted for fewer parameters; none: "
              "2 sqrt(2 / N_v)."),
        field("frequency_tolerance", &O::frequency_tolerance, Finite{GreaterThan{0.0}},
              "Relative frequency change of a pole stable in frequency."),
        field("damping_tolerance", &O::damping_tolerance, Finite{GreaterThan{0.0}},
              "Relative damping change of a pole stable in damping."),
        field("identification", &O::identification, "IdentificationOptions of every fit."),
    };
  }
  /// Throws InvalidArgument naming the first bad field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// One candidate structure: how its fit ended (the Outcome; `message` is the fit's one-line
/// report, or the error that stopped it) and how it scores.
struct StructureFit : Outcome {
  ModelStructure structure;
  int parameters = 0;  ///< entries of beta
  /// False when the fit failed, did not give a finite, stable model, or its verdict says so,
  /// or when it fits the estimation data worse, by more than 2 sqrt(2 / N_v) (relative; N_v
  /// as for error_tolerance, whatever error_tolerance says), than a usable fit
  /// of a structure it contains (same kind, each submodel within one of its own with as many
  /// poles and zeros and the same integrators): it stopped short of its optimum.
  bool usable = false;
  /// Why not usable: the estimate's verdict reasons and the scan's (empty when usable).
  std::vector<std::string> reasons;

  double estimation_fit = 0.0;    ///< fit_percent on the estimation part
  double validation_fit = 0.0;    ///< fit_percent on the held-out part (see validation_fraction)
  double validation_error = 0.0;  ///< mean squared output error on the held-out part
  /// Young's information criterion: ln(s_e^2 / s_y^2) + ln((1/p) sum_i P_ii / beta_i^2), with
  /// P the parameter covariance (NaN without one). More negative is better.
  double yic = 0.0;
  double rt2 = 0.0;  ///< 1 - s_e^2 / s_y^2 on the estimation part (output error)
  double aic = 0.0;  ///< N ln(s_e^2) + 2 p
  double bic = 0.0;  ///< N ln(s_e^2) + p ln N
  TransferFunction transfer_function{Polynomial{1.0}, Polynomial{1.0}};  ///< the estimate

  static constexpr std::string_view type_name = "StructureFit";
  static constexpr auto fields() {
    using S = StructureFit;
    return std::tuple_cat(
        std::tuple{
            field("structure", &S::structure, "The candidate ModelStructure."),
            field("parameters", &S::parameters, "Entries of beta."),
        },
        Outcome::fields(),
        std::tuple{
            field("usable", &S::usable, "Finite, stable, and the fit's verdict says usable."),
            field("reasons", &S::reasons,
                  "Why not usable: the verdict's reasons and the scan's (empty when usable)."),
            field("estimation_fit", &S::estimation_fit, "fit_percent on the estimation part."),
            field("validation_fit", &S::validation_fit, "fit_percent on the held-out part."),
            field("validation_error", &S::validation_error,
                  "Mean squared output error on the held-out part."),
            field("yic", &S::yic, "Young's information criterion (more negative is better)."),
            field("rt2", &S::rt2, "1 - s_e^2 / s_y^2 on the estimation part."),
            field("aic", &S::aic, "N ln(s_e^2) + 2 p."),
            field("bic", &S::bic, "N ln(s_e^2) + p ln N."),
            field("transfer_function", &S::transfer_function, "The estimate, unfactored."),
        });
  }
};

/// One pole pair of the stabilisation diagram.
struct StabilisationPoint {
  int fit = 0;                 ///< index into StructureScanResult::fits
  int order = 0;               ///< number of poles of that fit (besides integrators)
  double frequency = 0.0;      ///< natural frequency |s| [rad/s]
  double damping_ratio = 0.0;  ///< -Re(s) / |s|
  bool stable_pole = false;    ///< Re(s) < 0
  bool stable_frequency = false;
  bool stable_damping = false;

  static constexpr std::string_view type_name = "StabilisationPoint";
  static constexpr auto fields() {
    using S = StabilisationPoint;
    return std::tuple{
        field("fit", &S::fit, "Index of the fit."),
        field("order", &S::order, "Poles of the fit besides integrators."),
        field("frequency", &S::frequency, "Natural frequency [rad/s]."),
        field("damping_ratio", &S::damping_ratio, "Damping ratio."),
        field("stable_pole", &S::stable_pole, "Re(s) < 0."),
        field("stable_frequency", &S::stable_frequency,
              "The previous order has a pole within frequency_tolerance."),
        field("stable_damping", &S::stable_damping, "... and within damping_tolerance in damping."),
    };
  }
};

struct StructureScanResult {
  std::vector<StructureFit> fits;  ///< in the order of the candidates
  int recommended = -1;            ///< index into fits; -1 when no fit is usable
  std::string rule;                ///< one sentence: why that one
  int estimation_samples = 0;
  int validation_samples = 0;
  std::vector<StabilisationPoint> stabilisation;  ///< pole pairs of every usable-or-not fit

  static constexpr std::string_view type_name = "StructureScanResult";
  static constexpr auto fields() {
    using S = StructureScanResult;
    return std::tuple{
        field("fits", &S::fits, "StructureFit of every candidate, in order."),
        field("recommended", &S::recommended, "Index of the recommended fit (-1: none usable)."),
        field("rule", &S::rule, "Why that one."),
        field("estimation_samples", &S::estimation_samples, "Samples fitted."),
        field("validation_samples", &S::validation_samples, "Samples held out (0: none)."),
        field("stabilisation", &S::stabilisation, "StabilisationPoint of every pole pair."),
    };
  }
};

/// Fits every candidate on the first (1 - validation_fraction) of the record and scores it
/// (see StructureScanOptions). A candidate whose fit throws (e.g. too many parameters for the
/// data) is reported with its message and usable = false; the scan itself throws
/// InvalidArgument only for bad options, an empty candidate list or too short a record.
/// Recommendation: among usable fits, the fewest parameters whose held-out mean squared error
/// is within error_tolerance (relative) of the best usable one's (ties: lower YIC).
/// `progress`, if given, is called after each candidate with the number fitted and the number
/// of candidates (under a lock, from the worker threads: the candidates are fitted in parallel
/// on all cores, core/parallel.h, and the result is the serial one whatever their number).
StructureScanResult scan_structures(const SampledData& data,
                                    const std::vector<ModelStructure>& candidates,
                                    const StructureScanOptions& options = {},
                                    const std::function<void(int, int)>& progress = {});

}  // namespace ctid
