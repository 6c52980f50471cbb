// A continuous-time model with several inputs and outputs whose submodels share their poles
// across channels: G(p) = sum_i R_i(p) / A_i(p), R_i an n_y x n_u matrix of numerator
// polynomials over one anti-monic denominator A_i (a mode, a real pole, ...), plus an optional
// direct term D (n_y x n_u; accelerometers driven by forces need one) and optional per-input
// delays tau_k: G[j, k](p) = e^{-p tau_k} (sum_i R_i[j, k] / A_i + D[j, k]). Channel (output j,
// input k) is that SISO additive model with input delay tau_k, so everything SISO (simulate,
// frequency responses, modal parameters) applies per channel.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/polynomial.h"

namespace ctid {

struct MimoSubmodel {
  Polynomial a;               ///< anti-monic A_i, a[0] == 1 (degree 0 only with integrators)
  std::vector<Polynomial> b;  ///< R_i[j, k] at b[j * inputs + k]
  int integrators = 0;        ///< l_i poles at the origin: R_i / (p^{l_i} A_i) (rigid body: 2)
};

class MimoAdditiveModel {
 public:
  /// `direct`: D, outputs x inputs, or empty for none. Throws InvalidArgument for no
  /// submodel, a denominator that is not anti-monic or of degree 0, a numerator count other
  /// than inputs * outputs, a D of another size, or non-finite coefficients. `input_delays`:
  /// tau_k [s] per input (finite, >= 0), or empty for none.
  MimoAdditiveModel(int inputs, int outputs, std::vector<MimoSubmodel> submodels,
                    Eigen::MatrixXd direct = {}, Eigen::VectorXd input_delays = {});

  int inputs() const { return inputs_; }
  int outputs() const { return outputs_; }
  int size() const { return static_cast<int>(submodels_.size()); }
  const std::vector<MimoSubmodel>& submodels() const { return submodels_; }
  const MimoSubmodel& operator[](int i) const { return submodels_.at(static_cast<size_t>(i)); }
  /// R_i[output, input].
  const Polynomial& numerator(int i, int output, int input) const;
  /// D (outputs x inputs; zero when the model has none).
  const Eigen::MatrixXd& direct() const { return direct_; }
  bool has_direct_term() const { return has_direct_; }
  /// tau_k [s] of every input (zero when the model has none).
  const Eigen::VectorXd& input_delays() const { return input_delays_; }
  bool has_input_delays() const { return (input_delays_.array() != 0.0).any(); }
  /// The same model with these per-input delays [s] (one per input, or empty for none).
  MimoAdditiveModel with_input_delays(Eigen::VectorXd input_delays) const;
  /// The SISO additive model of one channel: sum_i R_i[output, input] / (p^{l_i} A_i), with
  /// D[output, input] added to the first submodel's numerator as D p^{l_1} A_1 (which makes it
  /// biproper), and the input's delay.
  AdditiveModel channel(int output, int input) const;

 private:
  int inputs_;
  int outputs_;
  std::vector<MimoSubmodel> submodels_;
  Eigen::MatrixXd direct_;
  bool has_direct_ = false;
  Eigen::VectorXd input_delays_;
};

}  // namespace ctid
