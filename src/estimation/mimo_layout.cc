// The MIMO parameter layout's model (mimo_layout.h).
#include "estimation/internal/mimo_layout.h"

#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/mimo_model.h"
#include "ctid/core/polynomial.h"

namespace ctid::internal {

MimoAdditiveModel model_from_columns(const MimoLayout& layout, const std::vector<Polynomial>& a,
                                     const Eigen::MatrixXd& b) {
  std::vector<MimoSubmodel> submodels;
  for (int i = 0; i < layout.size(); ++i) {
    MimoSubmodel sub{
        a[static_cast<size_t>(i)], {}, layout.orders[static_cast<size_t>(i)].integrators};
    const int m = layout.orders[static_cast<size_t>(i)].m;
    for (int j = 0; j < layout.outputs; ++j) {
      for (int k = 0; k < layout.inputs; ++k) {
        // An estimate may be exactly zero (a numerator the data do not need).
        sub.b.push_back(
            Polynomial::trimmed(Eigen::VectorXd(b.block(layout.u_column(i, k, 0), j, m + 1, 1))));
      }
    }
    submodels.push_back(std::move(sub));
  }
  Eigen::MatrixXd direct;
  if (layout.direct) direct = b.middleRows(layout.d_at, layout.inputs).transpose();
  return MimoAdditiveModel(layout.inputs, layout.outputs, std::move(submodels), direct);
}

}  // namespace ctid::internal
