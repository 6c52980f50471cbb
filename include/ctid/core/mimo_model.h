// A continuous-time model with several inputs and outputs whose submodels share their poles
// across channels: G(p) = sum_i R_i(p) / A_i(p), R_i an n_y x n_u matrix of numerator
// polynomials over one anti-monic denominator A_i (a mode, a real pole, ...), plus an optional
// direct term D (n_y x n_u; accelerometers driven by forces need one). Channel (output j,
// input k) is the SISO additive model sum_i R_i[j, k] / A_i + D[j, k], so everything SISO
// (simulate, frequency responses, modal parameters) applies per channel.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/polynomial.h"

namespace ctid {

struct MimoSubmodel {
  Polynomial a;               ///< anti-monic A_i, a[0] == 1, degree >= 1
  std::vector<Polynomial> b;  ///< R_i[j, k] at b[j * inputs + k]
};

class MimoAdditiveModel {
 public:
  /// `direct`: D, outputs x inputs, or empty for none. Throws InvalidArgument for no
  /// submodel, a denominator that is not anti-monic or of degree 0, a numerator count other
  /// than inputs * outputs, a D of another size, or non-finite coefficients.
  MimoAdditiveModel(int inputs, int outputs, std::vector<MimoSubmodel> submodels,
                    Eigen::MatrixXd direct = {});

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
  /// The SISO additive model of one channel: sum_i R_i[output, input] / A_i, with D[output,
  /// input] added to the first submodel's numerator as D A_1 (which makes it biproper).
  AdditiveModel channel(int output, int input) const;

 private:
  int inputs_;
  int outputs_;
  std::vector<MimoSubmodel> submodels_;
  Eigen::MatrixXd direct_;
  bool has_direct_ = false;
};

}  // namespace ctid
