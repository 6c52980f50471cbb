// The front door of the FRF-matrix fit: frf_matrix_fit.
#include "ctid/identification/frf_matrix.h"

namespace ctid {

FrfMatrixFitResult identify(const MimoFrf& frf, const std::vector<SubmodelOrder>& orders,
                            const FrfIdentificationOptions& options,
                            const std::function<void(int, int)>& progress) {
  return frf_matrix_fit(frf, orders, options.frf_fit, options.initial_model, progress);
}

}  // namespace ctid
