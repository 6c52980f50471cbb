// The modes of a shared-pole MIMO model G = sum_i R_i / A_i + D (every A_i shared by all
// channels), however it was estimated: the time-domain mimo_srivc (refined_iv) and the
// FRF-matrix fit (frf_fit) both describe their estimate by these modes, with standard errors
// from the covariance in the one parameter layout both use (decisions 0018, 0019, 0045).
#pragma once

#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/mimo_model.h"

namespace ctid {

/// One second-order submodel as a mode shared by every channel. The residue matrix at the
/// pole s = -zeta w_n + j w_n sqrt(1 - zeta^2) is Res = R_i(s) / A_i'(s) (outputs x inputs);
/// the mode shape is its principal left singular vector, scaled to unit length with its
/// largest entry real and positive (docs/decisions/0018), and the participation factors are
/// L = Res^T conj(shape), so that Res = shape L^T when Res has rank one.
struct MimoMode {
  int submodel = 0;
  double natural_frequency = 0.0;  ///< w_n [rad/s]
  double damping_ratio = 0.0;
  double natural_frequency_se = 0.0;  ///< NaN without a covariance
  double damping_ratio_se = 0.0;
  Eigen::VectorXcd shape;          ///< outputs
  Eigen::VectorXd shape_se_real;   ///< standard errors of Re(shape), NaN without covariance
  Eigen::VectorXd shape_se_imag;   ///< ... of Im(shape)
  Eigen::VectorXcd participation;  ///< inputs
  /// sigma_1^2 / sum sigma_k^2 of Res: 1 for a rank-one residue (one shape explains it).
  double rank_one_share = 1.0;

  static constexpr std::string_view type_name = "MimoMode";
  static constexpr auto fields() {
    using S = MimoMode;
    return std::tuple{
        field("submodel", &S::submodel, "Index of the submodel."),
        field("natural_frequency", &S::natural_frequency, "w_n [rad/s]."),
        field("damping_ratio", &S::damping_ratio, "zeta."),
        field("natural_frequency_se", &S::natural_frequency_se, "Standard error of w_n."),
        field("damping_ratio_se", &S::damping_ratio_se, "Standard error of zeta."),
        field("shape", &S::shape, "Mode shape over the outputs (unit length)."),
        field("shape_se_real", &S::shape_se_real, "Standard errors of Re(shape)."),
        field("shape_se_imag", &S::shape_se_imag, "Standard errors of Im(shape)."),
        field("participation", &S::participation, "Participation factors over the inputs."),
        field("rank_one_share", &S::rank_one_share,
              "Share of the residue explained by the shape (1: rank one)."),
    };
  }
};

/// MAC(a, b) = |a^H b|^2 / ((a^H a)(b^H b)): 1 for proportional shapes, 0 for orthogonal ones.
double modal_assurance(const Eigen::VectorXcd& a, const Eigen::VectorXcd& b);
/// MAC of every pair (rows: `a`, columns: `b`).
Eigen::MatrixXd modal_assurance(const std::vector<MimoMode>& a, const std::vector<MimoMode>& b);

/// Every second-order submodel of `model` (structure `orders`) as a MimoMode. `covariance`,
/// if not empty, is that of the parameters in MimoEstimationResult::covariance's layout (every
/// submodel's a_1..a_n; then per output, per submodel, per input the numerator coefficients
/// b_0..b_m, and D[j, .] last when the model has a direct term) and gives the standard errors.
std::vector<MimoMode> mimo_modes(const MimoAdditiveModel& model,
                                 const std::vector<SubmodelOrder>& orders,
                                 const Eigen::MatrixXd& covariance = {});

}  // namespace ctid
