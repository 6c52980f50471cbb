// Output-only (operational) modal analysis: continuous-time modes of a structure from its
// ambient response, no input measured. Covariance-driven stochastic subspace identification
// with reference channels (Peeters and De Roeck, MSSP 1999), every order 2..max_order from one
// SVD (Döhler and Mevel, CEP 2012), a stabilisation diagram, automatic picking by clustering
// the stable poles (Magalhães, Cunha and Caetano, MSSP 2009) and standard errors by first-order
// perturbation or from segments (Reynders, Pintelon and De Roeck, MSSP 2008; decision 0036); or the
// data-driven variant (the LQ factor of the data Hankel matrix, ssi_data.h) feeding the same path
// from the observability matrix on; or FDD/EFDD. Poles s = ln(λ)/h; shapes normalised as
// docs/decisions/0030-oma-conventions.md says. Method and options: docs/oma.md.
#pragma once

#include <array>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/estimation/termination.h"
#include "ctid/estimation/verdict.h"

namespace ctid {

enum class OmaMethod { ssi_cov, fdd, efdd, ssi_data, plscf };
inline constexpr std::array<Enumerator<OmaMethod>, 5> oma_method_enumerators{{
    {OmaMethod::ssi_cov, "ssi-cov", "Covariance-driven stochastic subspace identification."},
    {OmaMethod::ssi_data, "ssi-data",
     "Data-driven stochastic subspace identification: the projection of the future outputs on "
     "the past references by an LQ factorisation of the data Hankel matrix."},
    {OmaMethod::fdd, "fdd",
     "Frequency-domain decomposition: peaks of the first singular value of the output "
     "spectral matrix (frequency and shape, no damping)."},
    {OmaMethod::efdd, "efdd",
     "Enhanced FDD: frequency and damping from the correlation function of each peak's "
     "single-degree-of-freedom bell."},
    {OmaMethod::plscf, "plscf",
     "Poly-reference least-squares complex frequency domain (PolyMAX) on the half-spectra of "
     "the positive-lag correlations; the diagram's orders are polynomial orders 1..max_order "
     "(r q poles at order q; with more than 4 references up to ceil(4 max_order / r))."},
}};
constexpr std::span<const Enumerator<OmaMethod>> enumerators(OmaMethod) {
  return oma_method_enumerators;
}

/// How the standard errors of the SSI modes are computed (decision 0036).
enum class OmaUncertainty { perturbation, segments };
inline constexpr std::array<Enumerator<OmaUncertainty>, 2> oma_uncertainty_enumerators{{
    {OmaUncertainty::perturbation, "perturbation",
     "First-order perturbation of the SSI-cov estimate: the covariance of the Hankel matrix from "
     "uncertainty_blocks blocks, carried through the SVD, A and the eigenvalue problem "
     "(Reynders, Pintelon and De Roeck 2008; Doehler and Mevel 2013). ssi-data: as segments."},
    {OmaUncertainty::segments, "segments",
     "The modes re-identified on each of uncertainty_blocks segments: their spread over "
     "sqrt(uncertainty_blocks)."},
}};
constexpr std::span<const Enumerator<OmaUncertainty>> enumerators(OmaUncertainty) {
  return oma_uncertainty_enumerators;
}

/// Stability of a pole against the poles of the previous order in the diagram.
enum class PoleStability { new_pole, frequency, frequency_damping, frequency_shape, stable };
inline constexpr std::array<Enumerator<PoleStability>, 5> pole_stability_enumerators{{
    {PoleStability::new_pole, "new", "No pole of the previous order within the frequency bound."},
    {PoleStability::frequency, "frequency", "Stable in frequency only."},
    {PoleStability::frequency_damping, "frequency_damping", "Stable in frequency and damping."},
    {PoleStability::frequency_shape, "frequency_shape", "Stable in frequency and shape (MAC)."},
    {PoleStability::stable, "stable", "Stable in frequency, damping and shape."},
}};
constexpr std::span<const Enumerator<PoleStability>> enumerators(PoleStability) {
  return pole_stability_enumerators;
}

struct OmaOptions {
  OmaMethod method = OmaMethod::ssi_cov;
  /// Largest model order (states); orders 2, 4, ..., max_order are identified. plscf: the
  /// largest polynomial order Q, orders 1, 2, ..., Q (r q poles at order q, r references),
  /// with more than 4 references Q = ceil(4 max_order / r).
  int max_order = 40;
  /// Block rows p (= block columns q) of the Hankel matrix of correlations R_1..R_{2p-1};
  /// ssi-data: p block rows of past references over p of future outputs.
  /// 0 picks max(10, ceil(max_order / references) + 1), raised so that the lags span 4
  /// periods of the lowest peak of the first singular value, within p * max(channels,
  /// references) <= 1000 (ssi-data: p * (channels + references) <= 1000; decision 0035).
  int block_rows = 0;
  /// Reference channels (0-based output indices); empty: every channel.
  std::vector<int> reference_channels;
  /// Poles with a damping ratio outside (0, max_damping) are not structural modes.
  double max_damping = 0.2;
  /// Stability bounds against the previous order: |Δf|/f, |Δζ|/ζ and 1 - MAC.
  double frequency_tolerance = 0.01;
  double damping_tolerance = 0.05;
  double mac_tolerance = 0.02;
  /// Two stable poles join a cluster when |Δf|/max f + (1 - MAC) is below this.
  double cluster_distance = 0.02;
  /// A cluster is a mode when it holds poles of at least this share of the orders tried.
  double min_support_fraction = 0.4;
  /// Frequencies [Hz] to pick near: each takes the nearest cluster of stable poles (any
  /// size) within 10 % in frequency; empty: automatic picking only.
  std::vector<double> modes_near_hz;
  /// Blocks n_b for the standard errors (either kind); 0: none (standard errors NaN).
  int uncertainty_blocks = 10;
  /// perturbation (SSI-cov's first-order perturbation; ssi-data falls back to segments) or
  /// segments (the spread of the modes of n_b segments); decision 0036.
  OmaUncertainty uncertainty = OmaUncertainty::perturbation;
  /// Samples per Welch segment of the spectral matrix (fdd, efdd, and every result's first
  /// singular value); 0: the largest power of two up to N / 8, within 256..16384 (at most N).
  int segment_length = 0;
  /// A peak of the first singular value stands this far [dB] above the higher of its valleys
  /// (fdd and efdd's modes; the lowest peak sets ssi-cov's automatic block rows).
  double peak_prominence_db = 6.0;
  /// efdd: lines whose first singular vector has at least this MAC with the peak's form the
  /// single-degree-of-freedom bell.
  double efdd_mac = 0.8;

  static constexpr std::string_view type_name = "OmaOptions";
  static constexpr auto fields() {
    using S = OmaOptions;
    return std::tuple{
        field("method", &S::method, "Identification method."),
        field("max_order", &S::max_order, AtLeast{2}, "Largest model order (states)."),
        field("block_rows", &S::block_rows, AtLeast{0}, "Hankel block rows p; 0: automatic."),
        field("reference_channels", &S::reference_channels, Each{AtLeast{0}},
              "Reference channels (0-based); empty: all.")
            .with_flag("reference-columns"),
        field("max_damping", &S::max_damping, Between{0, 1, false, true},
              "Largest damping ratio of a structural mode."),
        field("frequency_tolerance", &S::frequency_tolerance, GreaterThan{0},
              "Stability bound on |df|/f."),
        field("damping_tolerance", &S::damping_tolerance, GreaterThan{0},
              "Stability bound on |dzeta|/zeta."),
        field("mac_tolerance", &S::mac_tolerance, Between{0, 1, false, true},
              "Stability bound on 1 - MAC."),
        field("cluster_distance", &S::cluster_distance, GreaterThan{0},
              "Clustering threshold on |df|/f + 1 - MAC."),
        field("min_support_fraction", &S::min_support_fraction, Between{0, 1, false, true},
              "Share of orders a cluster needs to be a mode."),
        field("modes_near_hz", &S::modes_near_hz, Each{Finite{GreaterThan{0}}},
              "Frequencies [Hz] to pick near.")
            .with_flag("modes-near"),
        field("uncertainty_blocks", &S::uncertainty_blocks, AtLeast{0},
              "Blocks for the standard errors; 0: none."),
        field("uncertainty", &S::uncertainty,
              "Standard errors by first-order perturbation (ssi-cov) or from segments."),
        field("segment_length", &S::segment_length, AtLeast{0},
              "Samples per Welch segment of the spectral matrix; 0: automatic."),
        field("peak_prominence_db", &S::peak_prominence_db, GreaterThan{0},
              "How far [dB] a spectral peak stands above its valleys (fdd, efdd; ssi-cov's "
              "automatic block rows)."),
        field("efdd_mac", &S::efdd_mac, Between{0, 1, false, true},
              "efdd: MAC with the peak's shape that bounds the bell."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// One pole of the stabilisation diagram.
struct OmaPole {
  int order = 0;
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  PoleStability stability = PoleStability::new_pole;
  double mpc = 0.0;

  static constexpr std::string_view type_name = "OmaPole";
  static constexpr auto fields() {
    using S = OmaPole;
    return std::tuple{
        field("order", &S::order, "Model order."),
        field("frequency_hz", &S::frequency_hz, "Natural frequency [Hz]."),
        field("damping_ratio", &S::damping_ratio, "Damping ratio."),
        field("stability", &S::stability, "Stability against the previous order."),
        field("mpc", &S::mpc, "Modal phase collinearity of its shape."),
    };
  }
};

/// One identified mode: its cluster's representative, with standard errors (decision 0036).
struct OmaMode {
  double frequency_hz = 0.0;
  double frequency_hz_std = 0.0;
  double damping_ratio = 0.0;
  double damping_ratio_std = 0.0;
  /// Complex mode shape, one entry per channel (decision 0030: the largest entry is 1).
  std::vector<double> shape_real;
  std::vector<double> shape_imag;
  std::vector<double> shape_real_std;
  std::vector<double> shape_imag_std;
  double mpc = 0.0;
  double mpd = 0.0;
  int supporting_orders = 0;
  int order = 0;  ///< the order of the representative pole

  static constexpr std::string_view type_name = "OmaMode";
  static constexpr auto fields() {
    using S = OmaMode;
    return std::tuple{
        field("frequency_hz", &S::frequency_hz, "Natural frequency [Hz]."),
        field("frequency_hz_std", &S::frequency_hz_std, "Its standard error [Hz]."),
        field("damping_ratio", &S::damping_ratio, "Damping ratio."),
        field("damping_ratio_std", &S::damping_ratio_std, "Its standard error."),
        field("shape_real", &S::shape_real, "Real part of the mode shape."),
        field("shape_imag", &S::shape_imag, "Imaginary part of the mode shape."),
        field("shape_real_std", &S::shape_real_std, "Standard errors of shape_real."),
        field("shape_imag_std", &S::shape_imag_std, "Standard errors of shape_imag."),
        field("mpc", &S::mpc, "Modal phase collinearity (1: real shape)."),
        field("mpd", &S::mpd, "Mean phase deviation [deg] (0: real shape)."),
        field("supporting_orders", &S::supporting_orders, "Orders with a pole in its cluster."),
        field("order", &S::order, "Order of the representative pole."),
    };
  }
};

/// The result of oma(): why it ended (Outcome), the modes, the diagram (SSI only) and the verdict
/// ("no mode found" is an unusable verdict, not an exception).
struct OmaResult : Outcome {
  OmaMethod method = OmaMethod::ssi_cov;
  double sample_time = 0.0;
  int samples = 0;
  std::vector<std::string> channels;
  std::vector<int> reference_channels;
  int block_rows = 0;
  std::vector<OmaMode> modes;
  std::vector<OmaPole> stabilisation;
  std::vector<double> spectrum_hz;
  std::vector<double> first_singular_value;
  Verdict verdict;

  static constexpr std::string_view type_name = "OmaResult";
  static constexpr auto fields() {
    using S = OmaResult;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("method", &S::method, "Identification method."),
            field("sample_time", &S::sample_time, "Sample time h [s]."),
            field("samples", &S::samples, "Samples N of the record."),
            field("channels", &S::channels, "Output channel names."),
            field("reference_channels", &S::reference_channels, "Reference channels (0-based)."),
            field("block_rows", &S::block_rows, "Hankel block rows p used."),
            field("modes", &S::modes, "Identified modes, by frequency."),
            field("stabilisation", &S::stabilisation, "Every pole kept, every order."),
            field("spectrum_hz", &S::spectrum_hz, "Lines [Hz] of the output spectral matrix."),
            field("first_singular_value", &S::first_singular_value,
                  "Its first singular value at each line [unit^2/Hz]."),
            field("verdict", &S::verdict, "Whether any mode was found."),
        });
  }
};

/// Modes of the N x l record `outputs` sampled every `sample_time` seconds. Channels are
/// named by `channel_names` (empty: y1..yl). Throws InvalidArgument for fewer than two
/// channels, a constant or non-finite channel, a bad option, a max_order the Hankel matrix
/// cannot hold, or too few samples for its lags.
OmaResult oma(const Eigen::MatrixXd& outputs, double sample_time, const OmaOptions& options = {},
              std::vector<std::string> channel_names = {});

}  // namespace ctid
