// A modal MIMO model fitted to a measured FRF matrix (issue 13: "estimation from measured
// FRFs", for users with an analyser's FRF matrix and no time records). The model is
// mimo_srivc's, G(s) = sum_i R_i(s) / A_i(s) + D, with every A_i shared by all channels; it is
// found by weighted least squares on the complex FRF: common poles by vector fitting (the
// Sanathanan-Koerner iteration in a partial-fraction basis with relocated poles, Gustavsen &
// Semlyen 1999, relaxed form Gustavsen 2006), grouped into the submodels, numerators by linear
// least squares given the poles (LSFD), then Levenberg-Marquardt on all parameters at once.
// The covariance is in MimoEstimationResult's layout, so mimo_modes gives the same mode table
// with standard errors. Method and choices: docs/decisions/0019-frf-matrix-fit.md.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/mimo_model.h"
#include "ctid/estimation/mimo_modes.h"
#include "ctid/estimation/termination.h"
#include "ctid/estimation/verdict.h"
#include "ctid/frequency/mimo_frf.h"

namespace ctid {

/// How the entries of the FRF matrix are weighted in the least squares.
enum class FrfWeighting {
  uniform,   ///< every entry alike (each output's noise level estimated from its residual)
  variance,  ///< each entry by 1 / its variance (MimoFrf::variance, finite and positive)
};

inline constexpr std::array<Enumerator<FrfWeighting>, 2> frf_weighting_enumerators{{
    {FrfWeighting::uniform, "uniform", "Every entry alike."},
    {FrfWeighting::variance, "variance", "Each entry by 1 / its variance from the FRF."},
}};
constexpr std::span<const Enumerator<FrfWeighting>> enumerators(FrfWeighting) {
  return frf_weighting_enumerators;
}

struct FrfMatrixFitOptions {
  /// Upper bound on the Levenberg-Marquardt iterations after the start. >= 1.
  int max_iterations = 100;
  /// Stop when the relative parameter change and the relative decrease of the cost are both
  /// below this. In (0, 1).
  double tolerance = 1e-10;
  /// Pole-relocation iterations of the vector-fitting start. >= 1.
  int start_iterations = 50;
  /// Estimate a direct term D (outputs x inputs), e.g. the mass line of accelerances.
  bool direct_term = false;
  /// Weighting of the entries (uniform, or by the FRF's variance).
  FrfWeighting weighting = FrfWeighting::uniform;
  /// Fit only the lines in [min_frequency, max_frequency] (rad/s; max_frequency 0: no upper
  /// limit).
  double min_frequency = 0.0;
  double max_frequency = 0.0;
  /// Compute the covariance and the modes' standard errors.
  bool compute_covariance = true;

  static constexpr std::string_view type_name = "FrfMatrixFitOptions";
  static constexpr auto fields() {
    using O = FrfMatrixFitOptions;
    return std::tuple{
        field("max_iterations", &O::max_iterations, AtLeast{1},
              "Upper bound on the Levenberg-Marquardt iterations."),
        field("tolerance", &O::tolerance, Between{0.0, 1.0},
              "Relative parameter change and cost decrease that stop the iteration."),
        field("start_iterations", &O::start_iterations, AtLeast{1},
              "Pole-relocation iterations of the vector-fitting start."),
        field("direct_term", &O::direct_term, "Estimate a direct term D as well.")
            .with_flag("direct"),
        field("weighting", &O::weighting, "Weighting of the FRF entries: uniform or variance."),
        // Both from one flag, --band LO:HI in Hz.
        field("min_frequency", &O::min_frequency, AtLeast{0}, "Lowest line fitted [rad/s].")
            .with_flag("band"),
        field("max_frequency", &O::max_frequency, AtLeast{0},
              "Highest line fitted [rad/s] (0: no upper limit).")
            .with_flag("band"),
        field("compute_covariance", &O::compute_covariance,
              "Compute the covariance and the modes' standard errors."),
    };
  }
  /// Throws InvalidArgument naming the first bad field, its value and the rule (and for
  /// min_frequency >= max_frequency).
  void validate() const;
};

/// Derives termination, message and iterations (Levenberg-Marquardt's) from Outcome.
struct FrfMatrixFitResult : Outcome {
  /// The estimate: the last accepted iterate (none if nothing was computed).
  std::optional<MimoAdditiveModel> model;
  int start_iterations = 0;  ///< pole relocations of the vector-fitting start
  int lines = 0;             ///< lines fitted (inside the band)
  /// outputs x inputs: 100 (1 - ||H_jk - G_jk|| / ||H_jk||) over the lines fitted.
  Eigen::MatrixXd fit_percent;
  /// Per output: mean |H_jk - G_jk|^2 / weight over its inputs and lines (with variance
  /// weighting about 1 when the FRF's variances are right).
  Eigen::VectorXd noise_variance;
  /// Finite, stable, no channel fitted below 0 %, well-conditioned normal equations, and no
  /// mode whose natural frequency or damping ratio has a standard error above its value.
  Verdict verdict;
  /// Covariance of the parameters in MimoEstimationResult::covariance's layout; empty unless
  /// computed.
  Eigen::MatrixXd covariance;
  /// Every second-order submodel with complex poles as a mode (mimo_modes), in submodel order.
  std::vector<MimoMode> modes;

  static constexpr std::string_view type_name = "FrfMatrixFitResult";
  static constexpr auto fields() {
    using S = FrfMatrixFitResult;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("model", &S::model, "The estimate: the last accepted iterate."),
            field("start_iterations", &S::start_iterations,
                  "Pole relocations of the vector-fitting start."),
            field("lines", &S::lines, "Lines fitted."),
            field("fit_percent", &S::fit_percent,
                  "outputs x inputs: 100 (1 - ||H - G|| / ||H||) per channel."),
            field("noise_variance", &S::noise_variance,
                  "Per output: mean weighted squared residual."),
            field("verdict", &S::verdict, "Whether the model is usable, and why not."),
            field("covariance", &S::covariance,
                  "Covariance of [a of every submodel; per output its numerators and D]."),
            field("modes", &S::modes, "MimoMode of every second-order submodel."),
        });
  }
};

/// Fits `orders` (n_i in {1, 2}, m_i <= n_i, no integrators; with options.direct_term no
/// biproper submodel) to the FRF matrix `frf` (frequencies in rad/s, increasing, not negative;
/// response n_y x n_u at each line; variance used with FrfWeighting::variance), starting from
/// `initial_model` (same orders and size) or, without one, from vector fitting. Throws
/// InvalidArgument for bad options, orders, start or FRF (sizes that do not match, values that
/// are not finite, frequencies not increasing, too few lines for the parameters); the outcome
/// of the iteration is in the result. `progress`, if given, is called with (k, total) as step k
/// starts, counting the vector-fitting relocations (without a start) and then the
/// Levenberg-Marquardt iterations against the most both may run.
FrfMatrixFitResult frf_matrix_fit(const MimoFrf& frf, const std::vector<SubmodelOrder>& orders,
                                  const FrfMatrixFitOptions& options = {},
                                  const std::optional<MimoAdditiveModel>& initial_model = {},
                                  const std::function<void(int, int)>& progress = {});

/// The response of `model` at the frequencies w (rad/s), one n_y x n_u matrix per frequency.
std::vector<Eigen::MatrixXcd> mimo_frequency_response(const MimoAdditiveModel& model,
                                                      const Eigen::VectorXd& frequencies);

}  // namespace ctid
