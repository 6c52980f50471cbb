// Validation of separated forward/feedback models as in De Iuliis, Germani, Manes 2017,
// Section 4: the responses of the true and estimated transfer functions to the same
// unit-variance white noise held by a ZOH at t_c (0.005 s) over T (5 s), compared by
// MSE = (1/N) sum_{k=1}^{N} (ŷ(k t_c) - y(k t_c))², plus the exact expectation of that MSE
// over noise realisations, from the impulse response of the ZOH-discretised error system.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <tuple>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/core/transfer_function.h"

namespace ctid {

struct WhiteNoiseValidationOptions {
  double sample_time = 0.005;  ///< t_c [s]
  double duration = 5.0;       ///< T [s]; N = round(T / t_c)
  std::uint64_t seed = 1;

  static constexpr std::string_view type_name = "WhiteNoiseValidationOptions";
  static constexpr auto fields() {
    using O = WhiteNoiseValidationOptions;
    constexpr double inf = std::numeric_limits<double>::infinity();
    return std::tuple{
        field("sample_time", &O::sample_time, Between{0.0, inf},
              "t_c [s]: the white noise is held by a ZOH for this long."),
        field("duration", &O::duration, Between{0.0, inf}, "T [s] (>= sample_time)."),
        field("seed", &O::seed, "Seed of the white noise."),
    };
  }
  void validate() const { validate_fields(*this); }
  /// duration >= sample_time.
  void check_relations(const std::string& path) const;
};

struct ResponseComparison {
  double mse = 0.0;           ///< this realisation; +inf if a response overflowed
  double expected_mse = 0.0;  ///< E[MSE] over white-noise realisations; +inf on overflow
  bool estimate_stable = true;
  Eigen::VectorXd truth;     ///< y(k t_c), k = 1..N
  Eigen::VectorXd estimate;  ///< ŷ(k t_c)

  static constexpr std::string_view type_name = "ResponseComparison";
  static constexpr auto fields() {
    using R = ResponseComparison;
    return std::tuple{
        field("mse", &R::mse, "MSE of this realisation (inf: overflow)."),
        field("expected_mse", &R::expected_mse, "Expected MSE over realisations."),
        field("estimate_stable", &R::estimate_stable, "The estimate is stable."),
        field("truth", &R::truth, "True response y(k t_c), k = 1..N."),
        field("estimate", &R::estimate, "Estimated response."),
    };
  }
};

/// Both models must be strictly proper or proper, without delay.
ResponseComparison compare_white_noise_response(const TransferFunction& truth,
                                                const TransferFunction& estimate,
                                                const WhiteNoiseValidationOptions& options = {});

/// (1/N) sum_{k=1}^{N} sum_{j=0}^{k} g_j², g the impulse response of the ZOH-discretised
/// estimate - truth at t_c (g_0 its direct term).
double expected_white_noise_mse(const TransferFunction& truth, const TransferFunction& estimate,
                                double sample_time, int samples);

}  // namespace ctid
