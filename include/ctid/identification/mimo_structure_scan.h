// How many modes a record of several inputs and outputs holds (decision 0064): the shared-pole
// fit (identify(MimoData), decision 0018) for each mode count, scored on the estimation part
// and on a held-out end of the record, a recommendation by the rule scan_structures states for
// one channel, and the stabilisation diagram of the modes over the counts, each mode marked
// stable in frequency and damping when the count before has a mode close to it.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/core/mimo_data.h"
#include "ctid/estimation/termination.h"
#include "ctid/identification/mimo.h"
#include "ctid/identification/structure_scan.h"

namespace ctid {

struct MimoStructureScanOptions {
  /// Share of the record, at its end, held out: each fit is simulated from rest over the whole
  /// record and scored on that part only. 0: score on the estimation data. In [0, 0.9].
  double validation_fraction = 0.3;
  /// Parsimony: the fewest modes whose held-out error is at most (1 + error_tolerance) times
  /// the best usable one's. None: 2 sqrt(2 / N_v), as scan_structures (decision 0015).
  std::optional<double> error_tolerance;
  /// Stabilisation diagram: a mode is stable in frequency (damping) when the count before has a
  /// mode within this relative distance of its natural frequency (damping ratio).
  double frequency_tolerance = 0.01;
  double damping_tolerance = 0.05;
  /// Options of every fit (direct term, delays, iterations, covariance).
  MimoIdentificationOptions identification;

  static constexpr std::string_view type_name = "MimoStructureScanOptions";
  static constexpr auto fields() {
    using O = MimoStructureScanOptions;
    return std::tuple{
        field("validation_fraction", &O::validation_fraction, Between{0.0, 0.9, true, true},
              "Share of the record, at its end, used to score the validation fit (0: none)."),
        field("error_tolerance", &O::error_tolerance, Finite{AtLeast{0.0}},
              "Relative held-out error increase accepted for fewer modes; none: 2 sqrt(2 / N_v)."),
        field("frequency_tolerance", &O::frequency_tolerance, Finite{GreaterThan{0.0}},
              "Relative frequency change of a mode stable in frequency."),
        field("damping_tolerance", &O::damping_tolerance, Finite{GreaterThan{0.0}},
              "Relative damping change of a mode stable in damping."),
        field("identification", &O::identification, "MimoIdentificationOptions of every fit."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// One mode count: how its fit ended (the Outcome; `message` is the fit's one-line report, or
/// the error that stopped it) and how it scores.
struct MimoStructureFit : Outcome {
  int modes = 0;  ///< second-order submodels (2 poles, 1 zero each)
  /// False when the fit failed or its verdict says so, or when it fits the estimation data
  /// worse (by more than 2 sqrt(2 / N_v), relative) than a usable fit with fewer modes.
  bool usable = false;
  std::vector<std::string> reasons;  ///< why not usable (empty when usable)
  Eigen::VectorXd estimation_fit;    ///< per output: fit_percent on the estimation part
  Eigen::VectorXd validation_fit;    ///< per output: fit_percent on the held-out part
  /// Mean over the outputs of (1 - fit/100)^2 on the held-out part: each output's squared
  /// error relative to its own variation, so no channel's unit dominates.
  double validation_error = 0.0;

  static constexpr std::string_view type_name = "MimoStructureFit";
  static constexpr auto fields() {
    using S = MimoStructureFit;
    return std::tuple_cat(
        std::tuple{field("modes", &S::modes, "Second-order submodels of the fit.")},
        Outcome::fields(),
        std::tuple{
            field("usable", &S::usable,
                  "The fit's verdict says usable and it reached its optimum."),
            field("reasons", &S::reasons, "Why not usable (empty when usable)."),
            field("estimation_fit", &S::estimation_fit,
                  "Per output: fit % on the estimation part."),
            field("validation_fit", &S::validation_fit, "Per output: fit % on the held-out part."),
            field("validation_error", &S::validation_error,
                  "Mean over the outputs of (1 - fit/100)^2 on the held-out part."),
        });
  }
};

struct MimoStructureScanResult {
  std::vector<MimoStructureFit> fits;  ///< in the order of the mode counts
  int recommended = -1;                ///< index into fits; -1 when no fit is usable
  std::string rule;                    ///< one sentence: why that one
  int estimation_samples = 0;
  int validation_samples = 0;
  /// Every mode of every fit; `order` is twice the fit's mode count.
  std::vector<StabilisationPoint> stabilisation;

  static constexpr std::string_view type_name = "MimoStructureScanResult";
  static constexpr auto fields() {
    using S = MimoStructureScanResult;
    return std::tuple{
        field("fits", &S::fits, "MimoStructureFit of every mode count, in order."),
        field("recommended", &S::recommended, "Index of the recommended fit (-1: none usable)."),
        field("rule", &S::rule, "Why that one."),
        field("estimation_samples", &S::estimation_samples, "Samples fitted."),
        field("validation_samples", &S::validation_samples, "Samples held out (0: none)."),
        field("stabilisation", &S::stabilisation, "StabilisationPoint of every mode of every fit."),
    };
  }
};

/// Fits `mode_counts` modes (each count k: k submodels of 2 poles and 1 zero, shared by every
/// channel) on the first (1 - validation_fraction) of the open-loop record and scores each
/// (see MimoStructureScanOptions). A count whose fit throws is reported with its message and
/// usable = false; the scan throws InvalidArgument only for bad options, no or a non-positive
/// or repeated count, or too short a record. The counts are fitted in parallel, each into its
/// own slot, so the result is the serial one; `progress`, if given, is called after each fit.
MimoStructureScanResult scan_mimo_modes(const MimoData& data, const std::vector<int>& mode_counts,
                                        const MimoStructureScanOptions& options = {},
                                        const std::function<void(int, int)>& progress = {});

}  // namespace ctid
