#include "ctid/core/mimo_model.h"

#include <cmath>
#include <utility>

#include "ctid/core/error.h"

namespace ctid {

MimoAdditiveModel::MimoAdditiveModel(int inputs, int outputs, std::vector<MimoSubmodel> submodels,
                                     Eigen::MatrixXd direct, Eigen::VectorXd input_delays)
    : inputs_(inputs),
      outputs_(outputs),
      submodels_(std::move(submodels)),
      direct_(std::move(direct)),
      has_direct_(direct_.size() > 0),
      input_delays_(std::move(input_delays)) {
  require(inputs_ >= 1 && outputs_ >= 1, "a MIMO model needs at least one input and one output; ",
          "got ", inputs_, " inputs and ", outputs_, " outputs");
  require(!submodels_.empty(), "a MIMO model needs at least one submodel");
  for (size_t i = 0; i < submodels_.size(); ++i) {
    const MimoSubmodel& s = submodels_[i];
    require(s.integrators >= 0, "submodel ", i + 1, " has ", s.integrators,
            " integrators; the count must be >= 0");
    require(s.a.degree() >= 0 && s.a[0] == 1.0 && s.a.degree() + s.integrators >= 1, "submodel ",
            i + 1,
            ": the denominator must be anti-monic (a[0] = 1) with at least one pole (degree >= 1 "
            "or integrators)");
    require(s.a.coefficients().allFinite(), "submodel ", i + 1, ": non-finite denominator");
    require(static_cast<int>(s.b.size()) == inputs_ * outputs_, "submodel ", i + 1, " has ",
            s.b.size(), " numerators; ", outputs_, " outputs x ", inputs_, " inputs need ",
            inputs_ * outputs_);
    for (const Polynomial& b : s.b) {
      require(b.coefficients().allFinite(), "submodel ", i + 1, ": non-finite numerator");
    }
  }
  if (has_direct_) {
    require(direct_.rows() == outputs_ && direct_.cols() == inputs_, "the direct term is ",
            direct_.rows(), " x ", direct_.cols(), "; a model with ", outputs_, " outputs and ",
            inputs_, " inputs needs ", outputs_, " x ", inputs_);
    require(direct_.allFinite(), "the direct term has non-finite entries");
  } else {
    direct_ = Eigen::MatrixXd::Zero(outputs_, inputs_);
  }
  if (input_delays_.size() == 0) {
    input_delays_ = Eigen::VectorXd::Zero(inputs_);
  } else {
    require(input_delays_.size() == inputs_, "the model has ", input_delays_.size(),
            " input delays; a model with ", inputs_, " inputs needs one per input");
    for (Eigen::Index k = 0; k < input_delays_.size(); ++k) {
      require(std::isfinite(input_delays_(k)) && input_delays_(k) >= 0.0, "input ", k + 1,
              ": the delay is ", input_delays_(k), " s; it must be finite and >= 0");
    }
  }
}

MimoAdditiveModel MimoAdditiveModel::with_input_delays(Eigen::VectorXd input_delays) const {
  return MimoAdditiveModel(inputs_, outputs_, submodels_, has_direct_ ? direct_ : Eigen::MatrixXd(),
                           std::move(input_delays));
}

const Polynomial& MimoAdditiveModel::numerator(int i, int output, int input) const {
  require(output >= 0 && output < outputs_ && input >= 0 && input < inputs_, "channel (output ",
          output, ", input ", input, ") is outside a ", outputs_, " x ", inputs_, " model");
  return (*this)[i].b[static_cast<size_t>(output * inputs_ + input)];
}

AdditiveModel MimoAdditiveModel::channel(int output, int input) const {
  std::vector<Submodel> siso;
  for (int i = 0; i < size(); ++i) {
    const MimoSubmodel& s = submodels_[static_cast<size_t>(i)];
    siso.push_back(Submodel{s.a, numerator(i, output, input), s.integrators});
  }
  const double d = direct_(output, input);
  if (d != 0.0) siso[0].b = siso[0].b + d * (Polynomial::monomial(siso[0].integrators) * siso[0].a);
  return AdditiveModel(std::move(siso), input_delays_(input));
}

}  // namespace ctid
