// Shared systems of the MIMO tests (mimo_srivc, frf_matrix_fit, the CLI): the four modes of
// González et al. Section 6.1 seen by several inputs and outputs through seeded rank-one
// residues, eight modes at the flexible structure's size, and a small two-mode system.
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

/// Eight lightly damped modes (1-14 rad/s, damping 0.01-0.05) over two inputs and `outputs`
/// sensors, the size of the flexible structure: rank-one residues from a seeded normal
/// distribution, with general numerators b_0 + b_1 p (complex residues) when `general`.
inline MimoAdditiveModel eight_mode_structure(int outputs, unsigned seed, bool general = false) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const double frequencies[] = {1.0, 1.9, 3.1, 4.4, 6.0, 8.1, 10.6, 13.9};
  const double damping[] = {0.02, 0.01, 0.03, 0.015, 0.05, 0.02, 0.04, 0.03};
  std::vector<MimoSubmodel> submodels;
  for (int i = 0; i < 8; ++i) {
    const double w = frequencies[i];
    MimoSubmodel s{Polynomial{1.0, 2.0 * damping[i] / w, 1.0 / (w * w)}, {}};
    const double l[] = {normal(rng), normal(rng)};
    for (int j = 0; j < outputs; ++j) {
      const double psi = normal(rng);
      for (double lk : l) {
        if (general) {
          s.b.push_back(Polynomial{psi * lk, 0.3 * normal(rng) / w});
        } else {
          s.b.push_back(Polynomial{psi * lk});
        }
      }
    }
    submodels.push_back(std::move(s));
  }
  return MimoAdditiveModel(2, outputs, std::move(submodels));
}

/// Two modes (1.4 and 4 rad/s) with rank-one real residues over three outputs and two inputs:
/// a small record for the command-line tests.
inline MimoAdditiveModel two_mode_structure() {
  const double shapes[2][3] = {{1.0, 0.5, -0.3}, {-0.4, 1.0, 0.6}};
  const double participation[2][2] = {{1.0, 0.6}, {-0.5, 0.8}};
  std::vector<MimoSubmodel> submodels;
  const double w[2] = {1.4, 4.0};
  for (int i = 0; i < 2; ++i) {
    MimoSubmodel s{Polynomial{1.0, 0.1 / w[i], 1.0 / (w[i] * w[i])}, {}};
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 2; ++k) s.b.push_back(Polynomial{shapes[i][j] * participation[i][k]});
    }
    submodels.push_back(std::move(s));
  }
  return MimoAdditiveModel(2, 3, std::move(submodels));
}

}  // namespace ctid::testing
