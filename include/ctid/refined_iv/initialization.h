// Starting models for the refined IV iterations without knowing the true system. Candidates:
// a least-squares state-variable-filter (LSSVF, Young 1965) estimate of the unfactored model
// for a grid of filter bandwidths, and a model built from the resonance peaks of the record's
// FRF (lightly damped data, where LSSVF starts tend to miss modes); each is refined by a few
// SRIVC iterations (eq. 30) and the best output-error fit kept. Its poles are then grouped
// into the requested submodels (complex pairs stay together, origin poles go to the
// integrator submodel) with numerators by least squares. In closed loop (a known controller)
// only starts the controller stabilises are kept, each refined by CLSRIVC (decision 0011).
#pragma once

#include <optional>
#include <string_view>
#include <tuple>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/discrete_transfer_function.h"
#include "ctid/core/fields.h"
#include "ctid/core/sampled_data.h"
#include "ctid/core/transfer_function.h"
#include "ctid/frequency/frf.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid {

struct InitializationOptions {
  /// Bandwidths lambda [rad/s] of the SVF filter (1 + p/lambda)^n to try; empty: a factor-2
  /// grid from (pi/h)/128 to pi/h.
  std::vector<double> filter_bandwidths;
  /// SRIVC iterations refining each start, and CLSRIVC iterations in closed loop (0: the
  /// starts as they are).
  int refinement_iterations = 20;
  /// Records longer than this screen the candidates on a piece of themselves: their first
  /// max(screening_samples, N / kScreeningFraction) samples, so the start costs about what a
  /// fit costs however long the record (issue 14). The refined IV fit it starts then runs on
  /// the whole record. 0: always the whole record.
  int screening_samples = 10000;
  /// Input delay in samples.
  int input_delay_samples = 0;
  /// Which candidates are tried: auto (all), lssvf or frf.
  StartMethod method = StartMethod::automatic;
  /// The known controller u_k = C_d(q)(r_k - y_k) of closed-loop data (the data must hold the
  /// reference); none: open loop. With it every candidate, and its open-loop SRIVC
  /// refinement, is made one the controller stabilises (unstable poles reflected, then the
  /// gain halved up to kStartGainHalvings times) and refined by CLSRIVC; only starts the
  /// controller stabilises are kept, compared by the same output error y - G u.
  std::optional<DiscreteTransferFunction> controller;

  /// Most halvings of a candidate's gain while the controller does not stabilise it.
  static constexpr int kStartGainHalvings = 20;
  /// The screening piece is at least this fraction 1/kScreeningFraction of the record.
  static constexpr int kScreeningFraction = 32;

  /// The number of samples the candidates are screened on, for a record of `samples`.
  int screening_length(int samples) const;

  static constexpr std::string_view type_name = "InitializationOptions";
  static constexpr auto fields() {
    using O = InitializationOptions;
    return std::tuple{
        field("filter_bandwidths", &O::filter_bandwidths, Each{Finite{GreaterThan{0}}},
              "SVF bandwidths to try [rad/s]; empty: a factor-2 grid up to pi/h."),
        field("refinement_iterations", &O::refinement_iterations, AtLeast{0},
              "SRIVC iterations refining each LSSVF start (0: LSSVF only)."),
        field("screening_samples", &O::screening_samples, AtLeast{0},
              "Longer records screen the starts on their first max(this, N/32) samples; 0: "
              "the whole record."),
        field("input_delay_samples", &O::input_delay_samples, AtLeast{0}, "Input delay [samples]."),
        field("method", &O::method, "Candidates tried: auto (all), lssvf or frf."),
        field("controller", &O::controller,
              "Known discrete controller of closed-loop data (starts it stabilises, refined by "
              "CLSRIVC), or none (open loop)."),
    };
  }
  /// Throws InvalidArgument naming the first bad field, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// LSSVF estimate of B/(p^l A) (A anti-monic, deg A = order.n, deg B = order.m) with the
/// filter (1 + p/lambda)^(n + l). Open-loop least squares: biased under noise, a start only.
TransferFunction lssvf(const SampledData& data, const SubmodelOrder& order, double bandwidth,
                       int input_delay = 0);

/// The mode 1 + 2 zeta / w_n p + p^2 / w_n^2 of a resonance peak: its half-power damping
/// clamped to [1e-3, 0.5] (0.05 where it could not be measured), w_n from the resonance
/// frequency w_r = w_n sqrt(1 - 2 zeta^2).
Polynomial mode_from_peak(const ResonancePeak& peak);

/// A start from the resonance peaks of the record's Welch FRF (default_segment_length,
/// resonance_peaks on its excited, coherent lines): the n/2 most prominent peaks give pole
/// pairs -zeta w +- j w sqrt(1 - zeta^2) with their half-power damping (clamped to [1e-3,
/// 0.5]; 0.05 where it cannot be measured), an odd n adds a real pole at the FRF's lowest
/// line, integrators sit at the origin, and B is fitted by output-error least squares.
/// None when the FRF has fewer peaks than the pairs needed.
std::optional<TransferFunction> frf_peak_start(const SampledData& data, const SubmodelOrder& order,
                                               int input_delay = 0);

/// Orders of the unfactored model equivalent to an additive structure: n = sum n_i,
/// m = max_i (m_i + sum_{j != i} n_j + l - l_i), l = integrators.
SubmodelOrder unfactored_order(const std::vector<SubmodelOrder>& orders);

/// The best unfactored start for `order` among the candidates options.method names (see file
/// comment). Throws InvalidArgument when no candidate gives a finite model (with frf: when
/// the FRF has too few peaks for the order). With options.controller: the best start the
/// controller stabilises; if it stabilises none, the best candidate as found in open loop
/// (the caller's CLSRIVC then stops with Termination::closed_loop_unstable). Throws
/// InvalidArgument if the data has no reference or the controller's sample time differs.
TransferFunction initial_transfer_function(const SampledData& data, const SubmodelOrder& order,
                                           const InitializationOptions& options = {});

/// Groups the poles of g into submodels of the requested orders: from the slowest up, each
/// pole (or pair) goes to the first listed submodel with room for it whole, a real pole
/// preferring one with an odd number of poles left, so the listed order of the submodels
/// does not change the grouping (decision 0007); the numerators B_i are then fitted to the data by
/// linear least squares (output error with the denominators fixed). Unstable poles are
/// reflected. Throws InvalidArgument if the pole counts do not match.
AdditiveModel group_into_submodels(const TransferFunction& g,
                                   const std::vector<SubmodelOrder>& orders,
                                   const SampledData& data, int input_delay = 0);

/// initial_transfer_function + group_into_submodels. With options.controller the numerators
/// are fitted to the unfactored start's response to u instead of to y (so the grouped model
/// stays close to the stabilised start), and a grouped model the controller still does not
/// stabilise has its gain halved as above.
AdditiveModel initial_additive_model(const SampledData& data,
                                     const std::vector<SubmodelOrder>& orders,
                                     const InitializationOptions& options = {});

/// initial_additive_model from its unfactored start g, as initial_transfer_function(data,
/// unfactored_order(orders), options) returned it: for callers that fit from g in more than
/// one structure and screen it once.
AdditiveModel additive_model_from_start(const TransferFunction& g, const SampledData& data,
                                        const std::vector<SubmodelOrder>& orders,
                                        const InitializationOptions& options = {});

}  // namespace ctid
