// AdditiveModel::to_transfer_function as a value (decision 0045): the sum of the submodels over
// a common denominator, or none where its coefficients would overflow (to_transfer_function
// throws there), for callers that steer on whether a model has a representable transfer
// function. Private to ctid's layers.
#pragma once

#include <optional>

#include "ctid/core/additive_model.h"
#include "ctid/core/transfer_function.h"

namespace ctid::internal {

std::optional<TransferFunction> transfer_function_if_finite(const AdditiveModel& model);

}  // namespace ctid::internal
