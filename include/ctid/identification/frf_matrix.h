// The front door of the modal fit of a measured FRF matrix (decision 0019): identify(MimoFrf,
// orders, ...) runs what `ctid fit-frf` and Python's ctid.frf_matrix_fit run, the
// frequency-domain estimator of frf_fit/frf_matrix_fit.h (vector-fitting start, numerators by
// least squares, Levenberg-Marquardt). The result type stays the estimator's.
#pragma once

#include <functional>
#include <optional>
#include <string_view>
#include <tuple>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/mimo_model.h"
#include "ctid/frequency/mimo_frf.h"
#include "ctid/frf_fit/frf_matrix_fit.h"

namespace ctid {

struct FrfIdentificationOptions {
  /// Options of the FRF-matrix fit (band, weighting, direct term, iterations).
  FrfMatrixFitOptions frf_fit;
  /// Start of the Levenberg-Marquardt iteration (same orders and size); none: vector fitting.
  std::optional<MimoAdditiveModel> initial_model;

  static constexpr std::string_view type_name = "FrfIdentificationOptions";
  static constexpr auto fields() {
    using O = FrfIdentificationOptions;
    return std::tuple{
        field("frf_fit", &O::frf_fit, "FrfMatrixFitOptions of the FRF-matrix fit."),
        field("initial_model", &O::initial_model,
              "Start of the iteration (orders and size as the fit's); none: vector fitting."),
    };
  }
  /// Throws InvalidArgument naming the first bad field by its full path, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// Fits the submodels `orders` (n_i in {1, 2}, m_i <= n_i, no integrators), poles shared by
/// every channel, to the FRF matrix `frf`: frf_matrix_fit(frf, orders, options.frf_fit,
/// options.initial_model, progress), with its input checks (options, orders, start, the FRF's
/// sizes, values and frequencies); throws InvalidArgument as it does, and how the iteration
/// ended is in the result. `progress` as frf_matrix_fit's.
FrfMatrixFitResult identify(const MimoFrf& frf, const std::vector<SubmodelOrder>& orders,
                            const FrfIdentificationOptions& options = {},
                            const std::function<void(int, int)>& progress = {});

}  // namespace ctid
