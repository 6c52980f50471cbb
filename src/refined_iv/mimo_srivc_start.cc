// The start of mimo_srivc (the shared-pole refined IV estimator): candidates from the
// common-denominator least squares over a grid of bandwidths and from the FRF peaks, each
// refined by a few iterations.
#include "ctid/refined_iv/mimo_srivc.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <optional>
#include <utility>

#include <Eigen/Dense>
#include <Eigen/SVD>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/estimation/validation.h"
#include "ctid/estimation/verdict.h"
#include "ctid/filtering/filter_bank.h"
#include "ctid/frequency/frf.h"
#include "ctid/frequency/mimo_frf.h"
#include "ctid/refined_iv/additive_srivc.h"
#include "ctid/refined_iv/covariance.h"
#include "ctid/refined_iv/initialization.h"
#include "ctid/simulation/discretization.h"
#include "ctid/simulation/simulate.h"
#include "estimation/internal/mimo_layout.h"
#include "estimation/internal/scaled_least_squares.h"
#include "internal/mimo_srivc_parts.h"
#include "internal/refined_iv_engine.h"

namespace ctid::mimo_srivc_parts {

namespace {

// The common-denominator state-variable-filter least squares over every channel, the MIMO form
// of the SISO start's LSSVF: A(p) y_j = sum_k B_jk(p) u_k with one A of degree n = sum n_i,
// every signal through 1 / (1 + p / lambda)^n. The numerator columns are the same for every
// output, so they are projected out once and A comes from a system of n unknowns. Its poles
// are grouped into the structure's submodels (group_into_submodels); none if they do not fit.
// Whether (1 + p / lambda)^order and its companion realisation (coefficients divided by the
// leading one) have every coefficient well inside double precision: a structure of a hundred
// modes would overflow them at most bandwidths.
bool binomial_filter_is_representable(int order, double lambda) {
  const double log_lambda = std::log10(lambda);
  for (int k = 0; k <= order; ++k) {
    const double log_binomial =
        (std::lgamma(order + 1.0) - std::lgamma(k + 1.0) - std::lgamma(order - k + 1.0)) /
        std::log(10.0);
    const double coefficient = log_binomial - k * log_lambda;         // of p^k in f
    const double realised = log_binomial + (order - k) * log_lambda;  // divided by the lead
    if (std::abs(coefficient) > 250.0 || std::abs(realised) > 250.0) return false;
  }
  return true;
}

std::optional<std::vector<Polynomial>> common_denominator_start(const Layout& layout,
                                                                const MimoData& data, double lambda,
                                                                Hold interpolation) {
  // With l integrators (in at most one submodel) the common form is A(p) p^l y_j = B_j(p) u:
  // the output's derivatives start at p^l, and A holds the other poles only.
  int n = 0;
  int l = 0;
  for (const SubmodelOrder& o : layout.orders) {
    n += o.n;
    l += o.integrators;
  }
  if (n == 0) return std::vector<Polynomial>(layout.orders.size(), Polynomial{1.0});
  int m = layout.direct ? n + l : 0;  // a direct term makes every channel biproper
  for (const SubmodelOrder& o : layout.orders) m = std::max(m, o.m + n - o.n + l - o.integrators);
  if (!binomial_filter_is_representable(n + l, lambda)) return std::nullopt;
  Polynomial f{1.0};
  for (int q = 0; q < n + l; ++q) f = f * Polynomial{1.0, 1.0 / lambda};
  const FilterRealization bank = derivative_filters(f);
  const SampledFilter on_outputs(bank, data.sample_time(), interpolation);
  Eigen::MatrixXd u(data.size(), layout.inputs * (m + 1));
  for (int k = 0; k < layout.inputs; ++k) {
    u.middleCols(k * (m + 1), m + 1) = filtered_input(layout, bank, data, k).leftCols(m + 1);
  }
  const Eigen::MatrixXd q = scaled_thin_qr(u).q;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  for (int j = 0; j < layout.outputs; ++j) {
    const Eigen::MatrixXd fy = on_outputs.apply(data.outputs().col(j));
    Eigen::MatrixXd phi = -fy.middleCols(l + 1, n);
    phi -= q * (q.transpose() * phi);
    const Eigen::VectorXd y0 = fy.col(l) - q * (q.transpose() * fy.col(l));
    // Each output weighted by its own size, so that every channel counts alike.
    const double w = 1.0 / std::max(fy.col(l).squaredNorm(), 1e-300);
    normal += w * phi.transpose() * phi;
    rhs += w * phi.transpose() * y0;
  }
  const Eigen::VectorXd s = internal::column_scales(normal);
  const Eigen::VectorXd a_tail =
      s.cwiseInverse().asDiagonal() *
      (s.cwiseInverse().asDiagonal() * normal * s.cwiseInverse().asDiagonal())
          .colPivHouseholderQr()
          .solve(s.cwiseInverse().asDiagonal() * rhs);
  if (!a_tail.allFinite()) return std::nullopt;
  Eigen::VectorXd a(n + 1);
  a(0) = 1.0;
  a.tail(n) = a_tail;
  if (a(n) == 0.0) return std::nullopt;  // A lost its leading coefficient: not a candidate
  // A's poles grouped into the submodels that have poles besides integrators; none when they
  // do not fit the structure: not a candidate.
  std::vector<SubmodelOrder> with_poles;
  int biproper = 0;
  for (SubmodelOrder o : layout.orders) {
    if (o.n == 0) continue;
    o.m = std::min(o.m, o.n);
    o.integrators = 0;
    if (o.m == o.n) ++biproper;
    with_poles.push_back(o);
  }
  // An additive model has at most one biproper submodel, so group_into_submodels has no
  // grouping for a structure with more.
  if (biproper > 1) return std::nullopt;
  const std::optional<AdditiveModel> grouped = internal::grouped_submodels(
      TransferFunction(Polynomial{1.0}, Polynomial(a)), with_poles, data.channel(0, 0), 0);
  if (!grouped) return std::nullopt;
  std::vector<Polynomial> denominators;
  int next = 0;
  for (const SubmodelOrder& o : layout.orders) {
    denominators.push_back(o.n == 0 ? Polynomial{1.0}
                                    : grouped->submodels()[static_cast<size_t>(next++)].a);
  }
  return denominators;
}

// Denominators from the most prominent peaks of the summed-power FRF over every channel
// (summed_power_frf of the Welch FRF matrix, segments of `segment_length` samples), one mode
// per peak (mode_from_peak); none unless every submodel is a mode (n = 2) and the FRF has as
// many peaks as there are modes.
std::optional<std::vector<Polynomial>> frf_peak_denominators(const Layout& layout,
                                                             const MimoData& data,
                                                             int segment_length) {
  // Integrators alone (a rigid-body submodel) have A = 1; every other submodel must be a mode.
  int modes = 0;
  for (const SubmodelOrder& o : layout.orders) {
    if (o.n == 2 && o.integrators == 0) {
      ++modes;
    } else if (o.n != 0) {
      return std::nullopt;
    }
  }
  // A Welch segment needs at least 8 samples (WelchOptions), the record at least one segment.
  if (modes == 0 || segment_length < 8 || data.size() < segment_length) return std::nullopt;
  WelchOptions welch;
  welch.segment_length = segment_length;
  PeakOptions options;
  options.max_peaks = modes;
  std::vector<ResonancePeak> peaks =
      resonance_peaks(summed_power_frf(welch_frf(data, welch)), options);
  if (static_cast<int>(peaks.size()) < modes) return std::nullopt;
  std::sort(peaks.begin(), peaks.end(), [](const ResonancePeak& x, const ResonancePeak& y) {
    return x.frequency < y.frequency;
  });
  std::vector<Polynomial> a;
  auto peak = peaks.begin();
  for (const SubmodelOrder& o : layout.orders) {
    if (o.n == 0) {
      a.push_back(Polynomial{1.0});
      continue;
    }
    std::optional<Polynomial> mode = internal::mode_from_peak_if_finite(*peak++);
    if (!mode) return std::nullopt;  // a peak that gives no finite mode (at frequency 0)
    a.push_back(std::move(*mode));
  }
  return a;
}

// The start. Candidates: the common-denominator fit at each bandwidth of the SISO start's grid
// (Nyquist / 128 up to Nyquist by octaves), numerators by least squares; the
// kRefinedCandidates of them with the smallest relative output error and the FRF-peak
// candidates (default and fine Welch segments) are each given kRefinementIterations of the
// iteration, and the best refined one is the start (a candidate that fits well as it is can
// still lead the iteration astray).
constexpr int kRefinedCandidates = 3;

// The finer of the FRF-peak candidates' Welch segments: the largest power of two of at most a
// quarter of the record (seven half-overlapping averages), so that close modes separate.
int fine_segment_length(int samples) {
  int length = default_segment_length(samples);
  while (length * 2 <= samples / 4) length *= 2;
  return length;
}

constexpr int kRefinementIterations = 5;

}  // namespace

Iterate automatic_start(const Layout& layout, const MimoData& data, Hold interpolation) {
  std::vector<std::pair<double, Iterate>> candidates;
  const double nyquist = M_PI / data.sample_time();
  for (double lambda = nyquist / 128.0; lambda <= nyquist * 1.0001; lambda *= 2.0) {
    const std::optional<std::vector<Polynomial>> a =
        common_denominator_start(layout, data, lambda, interpolation);
    if (!a) continue;
    Iterate candidate = fit_numerators(layout, data, *a);
    const double cost = relative_output_error(layout, data, candidate);
    if (std::isfinite(cost)) candidates.emplace_back(cost, std::move(candidate));
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  if (candidates.size() > static_cast<size_t>(kRefinedCandidates)) {
    candidates.erase(candidates.begin() + kRefinedCandidates, candidates.end());
  }
  // The FRF-peak candidates are refined whatever their first fit: lightly damped modes put at
  // the right frequencies with a rough damping fit badly before the iteration corrects them.
  std::vector<int> lengths{default_segment_length(data.size())};
  if (fine_segment_length(data.size()) > lengths[0]) {
    lengths.push_back(fine_segment_length(data.size()));
  }
  for (int length : lengths) {
    // An FRF that gives no start is not a candidate.
    const std::optional<std::vector<Polynomial>> a = frf_peak_denominators(layout, data, length);
    if (!a) continue;
    Iterate candidate = fit_numerators(layout, data, *a);
    const double cost = relative_output_error(layout, data, candidate);
    if (std::isfinite(cost)) candidates.emplace_back(cost, std::move(candidate));
  }
  require(!candidates.empty(), "mimo_srivc: no start found from the data (neither the ",
          "common-denominator least squares at any filter bandwidth nor the FRF peaks gave a ",
          "model of this structure); give an initial model");
  std::optional<Iterations> best;
  for (auto& [cost, candidate] : candidates) {
    Iterations refined = run_iterations(layout, data, std::move(candidate), kRefinementIterations,
                                        0.0, interpolation);
    if (!best || refined.cost < best->cost) best = std::move(refined);
  }
  return std::move(best->model);
}

}  // namespace ctid::mimo_srivc_parts
