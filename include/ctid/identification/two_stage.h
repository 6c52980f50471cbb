// Closed loop with an unknown controller: the two-stage method (decision 0043). Stage 1
// estimates the map from the external reference r to the plant input u (the input
// sensitivity: u = S r plus the noise fed back through the controller) as a finite impulse
// response or a discrete-time output-error model B(q^-1)/A(q^-1), whichever AIC prefers;
// stage 2 estimates the plant by
// the open-loop estimators from the simulated noise-free input u_hat = S_hat r, which the
// noise does not reach when r is external.
#pragma once

#include <array>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"

namespace ctid {

/// The largest order stage 1 may be given; the largest the automatic choice tries for each
/// kind of model.
inline constexpr int kMaxSensitivityOrder = 4096;
inline constexpr int kMaxAutomaticRationalOrder = 8;
inline constexpr int kMaxAutomaticFirTaps = 512;

/// The model of r -> u in stage 1.
enum class SensitivityModel {
  automatic,  ///< whichever of the two AIC prefers
  fir,        ///< u_k = sum_{i<L} g_i r_{k-i}: least squares, consistent, needs L >> ringing
  rational,   ///< u_k = B(q^-1)/A(q^-1) r_k, deg A = deg B = n: simplified refined IV
};

inline constexpr std::array<Enumerator<SensitivityModel>, 3> sensitivity_model_enumerators{{
    {SensitivityModel::automatic, "automatic", "The FIR or the rational model, by AIC."},
    {SensitivityModel::fir, "fir", "A finite impulse response by least squares."},
    {SensitivityModel::rational, "rational",
     "A discrete output-error model B/A by simplified refined IV."},
}};
constexpr std::span<const Enumerator<SensitivityModel>> enumerators(SensitivityModel) {
  return sensitivity_model_enumerators;
}

struct TwoStageOptions {
  /// The model of r -> u.
  SensitivityModel sensitivity_model = SensitivityModel::automatic;
  /// Its order: FIR taps L, or n = deg A = deg B; 0: chosen by AIC (taps 4, 8, ... up to 512
  /// and a tenth of the record; orders 1..8).
  int sensitivity_order = 0;

  static constexpr std::string_view type_name = "TwoStageOptions";
  static constexpr auto fields() {
    using O = TwoStageOptions;
    return std::tuple{
        field("sensitivity_model", &O::sensitivity_model,
              "Model of r -> u: automatic (by AIC), fir or rational."),
        field("sensitivity_order", &O::sensitivity_order,
              Between{0.0, kMaxSensitivityOrder, true, true},
              "FIR taps or rational order of the model of r -> u (0: chosen by AIC)."),
    };
  }
  void check_relations(const std::string& path) const;
  void validate() const { validate_fields(*this); }
};

/// Stage 1 on one record.
struct SensitivityFit {
  SensitivityModel model = SensitivityModel::fir;
  /// FIR taps, or the rational order n.
  int order = 0;
  /// [1, a_1 .. a_n] and [b_0 .. b_n] of A(q^-1) and B(q^-1) (an FIR: A = 1, B = g).
  Eigen::VectorXd denominator;
  Eigen::VectorXd numerator;
  /// u_hat = B/A r from rest (r = 0 and u = 0 before the record, as stage 2 assumes).
  Eigen::VectorXd simulated_input;
  /// How much of u the model explains [%] (the rest is the noise fed back).
  double fit_percent = 0.0;
  /// N ln(RSS/N) + 2k of the output error u - u_hat, k the parameters (AIC: stage 1 had
  /// better be too rich than too poor, since a missing part of r -> u biases stage 2).
  double aic = 0.0;
  /// Rational: the refined IV iteration settled within its 20 steps (an FIR: true).
  bool converged = true;
};

/// Stage 1: the model of record.reference() -> record.input() the options ask for (FIR taps
/// by least squares; a rational model by the discrete simplified refined IV from an ARX start,
/// an unstable A reflected for the prefilter, the stable iterate with the smallest output
/// error kept), its order by AIC where it is 0. Throws InvalidArgument when the record has no
/// reference, when the order is too large for the record, or when the reference does not
/// excite the model (singular equations, or no stable iterate).
SensitivityFit fit_sensitivity(const SampledData& record, const TwoStageOptions& options);

/// Stage 1's model driven by `reference` from rest, B/A r (r = 0 and u = 0 before it): the
/// simulated input for a reference other than the one it was fitted on, e.g. a whole record
/// of which stage 1 saw only the first part.
Eigen::VectorXd sensitivity_output(const SensitivityFit& fit, const Eigen::VectorXd& reference);

/// What stage 1 did, in IdentificationResult::two_stage.
struct TwoStageResult {
  /// The model of r -> u and its order (FIR taps, or n).
  SensitivityModel sensitivity_model = SensitivityModel::fir;
  int sensitivity_order = 0;
  /// Per record: how much of u the model of r -> u explains [%].
  std::vector<double> sensitivity_fit_percent;
  /// What the estimate needs to be consistent, in words.
  std::string assumptions;

  static constexpr std::string_view type_name = "TwoStageResult";
  static constexpr auto fields() {
    using R = TwoStageResult;
    return std::tuple{
        field("sensitivity_model", &R::sensitivity_model, "Model of r -> u: fir or rational."),
        field("sensitivity_order", &R::sensitivity_order,
              "FIR taps or rational order of the model of r -> u."),
        field("sensitivity_fit_percent", &R::sensitivity_fit_percent,
              "Per record: fit [%] of u by the model of r -> u."),
        field("assumptions", &R::assumptions, "What the estimate needs to be consistent."),
    };
  }
};

}  // namespace ctid
