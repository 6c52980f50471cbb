// Shared systems of the MIMO tests (mimo_srivc, frf_matrix_fit): the four modes of González
// et al. Section 6.1 seen by several inputs and outputs through seeded rank-one residues.
#pragma once

#include <random>
#include <vector>

#include "ctid/core/mimo_model.h"
#include "support/paper_systems.h"

namespace ctid::testing {

/// R_i[j, k] = g_i psi_ij l_ik: the Section 6.1 mode i's gain g_i times a shape psi_i and a
/// participation l_i drawn from a seeded normal distribution.
inline MimoAdditiveModel four_mode_beam(int inputs, int outputs, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<MimoSubmodel> submodels;
  const AdditiveModel modes = open_loop_four_modes();
  for (const Submodel& mode : modes.submodels()) {
    MimoSubmodel s{mode.a, {}};
    Eigen::VectorXd shape(outputs);
    Eigen::VectorXd participation(inputs);
    for (int j = 0; j < outputs; ++j) shape(j) = normal(rng);
    for (int k = 0; k < inputs; ++k) participation(k) = normal(rng);
    for (int j = 0; j < outputs; ++j) {
      for (int k = 0; k < inputs; ++k) {
        s.b.push_back(Polynomial{mode.b[0] * shape(j) * participation(k)});
      }
    }
    submodels.push_back(std::move(s));
  }
  return MimoAdditiveModel(inputs, outputs, std::move(submodels));
}

}  // namespace ctid::testing
