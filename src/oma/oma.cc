// oma(): checks, the stabilisation diagram over every order, automatic picking and the
// standard errors: first-order perturbation (ssi_uncertainty.h) or segment-based (Reynders,
// Pintelon and De Roeck, MSSP 2008, section 3); decision 0036. pLSCF shares the diagram,
// picking and segment errors (decision 0066).
#include "ctid/oma/oma.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "core/internal/signal_range.h"
#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/core/parallel.h"
#include "ctid/oma/fdd.h"
#include "ctid/oma/plscf.h"
#include "ctid/oma/ssi_cov.h"
#include "ctid/oma/ssi_data.h"
#include "ctid/oma/ssi_uncertainty.h"
#include "ctid/oma/stabilisation.h"
#include "oma/internal/ssi_pipeline.h"

namespace ctid {
namespace {

using oma_detail::ModalPole;
using oma_detail::OrderPoles;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Correlations reach lag 2p - 1; a record of fewer than this many times p samples gives
// correlations too noisy to be worth a Hankel matrix.
constexpr int kSamplesPerBlockRow = 20;
// Automatic block rows: lags spanning this many periods of the lowest spectral peak, within
// this many rows (and columns) of the Hankel matrix (decision 0035).
constexpr double kLagPeriods = 4.0;
// pLSCF's least lags (decision 0066): 129 lines from 0 to Nyquist.
constexpr int kPlscfMinLags = 256;
constexpr double kMaxHankelRows = 1000.0;
// A user frequency takes the nearest cluster within this relative distance.
constexpr double kNearTolerance = 0.1;

void check_record(const Eigen::MatrixXd& y, double h, const std::vector<std::string>& names) {
  require(std::isfinite(h) && h > 0.0, "sample_time is ", h, "; it must be finite and > 0");
  require(y.cols() >= 2, "outputs has ", y.cols(),
          " channel(s); output-only modal analysis needs at least 2 (--output-columns)");
  for (Eigen::Index j = 0; j < y.cols(); ++j) {
    for (Eigen::Index k = 0; k < y.rows(); ++k) {
      require(std::isfinite(y(k, j)), "outputs channel '", names[static_cast<std::size_t>(j)],
              "' is ", y(k, j), " at sample ", k, "; every value must be finite");
    }
    internal::require_magnitude_in_range(
        y.col(j), "outputs channel '" + names[static_cast<std::size_t>(j)] + "'");
    require(y.rows() == 0 || (y.col(j).array() != y(0, j)).any(), "outputs channel '",
            names[static_cast<std::size_t>(j)], "' is ", y.rows() > 0 ? y(0, j) : 0.0,
            " at every sample; a constant channel carries no response");
  }
}

using oma_detail::ssi_samples_needed;

int pick_block_rows(const OmaOptions& o, Eigen::Index l, Eigen::Index r, Eigen::Index n) {
  const int p = o.block_rows > 0 ? o.block_rows
                                 : std::max(10, static_cast<int>((o.max_order + r - 1) / r) + 1);
  // pLSCF has no Hankel matrix: its p only sets the lags (plscf_lags).
  require(o.method == OmaMethod::plscf || ((p - 1) * l >= o.max_order && p * r >= o.max_order),
          "OmaOptions.max_order is ", o.max_order, "; the Hankel matrix of ", p,
          " block rows (block_rows) over ", l, " channels and ", r,
          " references holds at most order ", std::min<Eigen::Index>((p - 1) * l, p * r),
          " (--max-order / --block-rows)");
  require(n >= static_cast<Eigen::Index>(kSamplesPerBlockRow) * p, "the record has ", n,
          " samples; ", p, " block rows (max_order ", o.max_order, ") need at least ",
          kSamplesPerBlockRow * p, " (a lower --max-order or --block-rows, or a longer record)");
  const Eigen::Index needed = ssi_samples_needed(o, p, l, r);
  require(n >= needed, "the record has ", n, " samples; ssi-data with ", p, " block rows over ", r,
          " references and ", l, " channels needs at least ", needed,
          " (N - 2p + 1 Hankel columns for its p(r + l) = ", p * (r + l),
          " rows; a lower --block-rows or --max-order, fewer --reference-columns, or a longer "
          "record)");
  return p;
}

// The observability factor of the SSI method: SSI-cov from the Hankel matrix of the
// correlations, SSI-data from the LQ factor of the data Hankel matrix. Orders, poles, shapes,
// stabilisation, picking and standard errors are shared from here on. When the whole
// record's SSI-cov estimate gets standard errors (`with_errors`: either kind, so that both give
// the same modes), its Hankel matrix has one SVD with U and V, from which come both the factor
// of every order and the perturbation standard errors (decision 0041); otherwise U alone.
struct RecordSsi {
  oma_detail::HankelSvd svd;  // empty unless with_errors
  oma_detail::SsiFactor factor;
};

RecordSsi record_ssi(const Eigen::MatrixXd& y, const std::vector<int>& refs, int p,
                     const OmaOptions& o, bool with_errors, int threads = 0) {
  RecordSsi out;
  if (o.method == OmaMethod::ssi_data) {
    out.factor = oma_detail::ssi_data_factor(y, refs, p, o.max_order, threads);
    return out;
  }
  const Eigen::MatrixXd hankel =
      oma_detail::correlation_hankel(oma_detail::output_correlations(y, refs, 2 * p - 1), p);
  const int l = static_cast<int>(y.cols());
  if (!with_errors) {
    out.factor = oma_detail::hankel_factor(hankel, l, o.max_order);
    return out;
  }
  out.svd = oma_detail::hankel_svd(hankel);
  out.factor = oma_detail::observability_factor(out.svd.u, out.svd.singular_values, l, o.max_order);
  return out;
}

// SSI's orders 2, 4, ..., max_order (states); pLSCF's polynomial orders 1, 2, ..., max_order.
std::vector<OrderPoles> all_orders(const oma_detail::PolesOfOrder& poles, const OmaOptions& o) {
  const int step = o.method == OmaMethod::plscf ? 1 : 2;
  std::vector<OrderPoles> orders;
  for (int n = step; n <= o.max_order; n += step) orders.push_back({n, poles(n)});
  return orders;
}

// The poles of every order of one factor.
oma_detail::PolesOfOrder poles_of(oma_detail::SsiFactor factor, double h, const OmaOptions& o) {
  return [factor = std::move(factor), h, max_damping = o.max_damping](int n) {
    return oma_detail::ssi_poles(factor, n, h, max_damping);
  };
}

OmaMode make_mode(const oma_detail::PoleCluster& cluster, const std::vector<OrderPoles>& orders) {
  const ModalPole& p = orders[static_cast<std::size_t>(cluster.representative.first)]
                           .poles[static_cast<std::size_t>(cluster.representative.second)];
  OmaMode m;
  m.frequency_hz = p.frequency_hz;
  m.damping_ratio = p.damping_ratio;
  for (Eigen::Index j = 0; j < p.shape.size(); ++j) {
    m.shape_real.push_back(p.shape(j).real());
    m.shape_imag.push_back(p.shape(j).imag());
  }
  m.mpc = p.mpc;
  m.mpd = p.mpd;
  m.supporting_orders = cluster.supporting_orders;
  m.order = orders[static_cast<std::size_t>(cluster.representative.first)].order;
  m.frequency_hz_std = m.damping_ratio_std = kNaN;
  m.shape_real_std.assign(m.shape_real.size(), kNaN);
  m.shape_imag_std.assign(m.shape_real.size(), kNaN);
  return m;
}

// The modes: clusters with enough supporting orders, and for each user frequency the nearest
// cluster (any size) within kNearTolerance; reasons for the verdict when one is missing.
std::vector<OmaMode> pick_modes(const std::vector<oma_detail::PoleCluster>& clusters,
                                const std::vector<OrderPoles>& orders, const OmaOptions& o,
                                Verdict& verdict) {
  std::vector<char> chosen(clusters.size(), 0);
  const int needed = std::max(
      2, static_cast<int>(std::ceil(o.min_support_fraction * static_cast<double>(orders.size()))));
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    if (o.modes_near_hz.empty() && clusters[c].supporting_orders >= needed) chosen[c] = 1;
  }
  for (double f : o.modes_near_hz) {
    std::size_t best = clusters.size();
    for (std::size_t c = 0; c < clusters.size(); ++c) {
      const double d = std::abs(clusters[c].frequency_hz - f) / f;
      if (d < kNearTolerance &&
          (best == clusters.size() || d < std::abs(clusters[best].frequency_hz - f) / f)) {
        best = c;
      }
    }
    if (best == clusters.size()) {
      verdict.fail(internal::concat("no stable pole within 10 % of ", f, " Hz"),
                   {"a higher --max-order", verdict_advice::more_data});
    } else {
      chosen[best] = 1;
    }
  }
  std::vector<OmaMode> modes;
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    if (chosen[c]) modes.push_back(make_mode(clusters[c], orders));
  }
  if (modes.empty() && o.modes_near_hz.empty()) {
    verdict.fail(internal::concat("no mode found: no cluster of stable poles is supported by ",
                                  needed, " of the ", orders.size(), " orders"),
                 {"a higher --max-order", verdict_advice::more_data});
  }
  return modes;
}

double spread(const std::vector<double>& v, double blocks) {
  if (v.size() < 2) return kNaN;
  double mean = 0.0;
  for (double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  double ss = 0.0;
  for (double x : v) ss += (x - mean) * (x - mean);
  return std::sqrt(ss / static_cast<double>(v.size() - 1) / blocks);
}

// Segment-based standard errors of one record (Reynders, Pintelon and De Roeck, MSSP 2008,
// section 3): the record in n_b blocks of equal length.
void segment_uncertainty(const Eigen::MatrixXd& y, const std::vector<int>& refs, int p, double h,
                         const OmaOptions& o, std::vector<OmaMode>& modes) {
  const int nb = o.uncertainty_blocks;
  const Eigen::Index length = y.rows() / std::max(nb, 1);
  const auto r = static_cast<Eigen::Index>(refs.size());
  if (nb < 2 || modes.empty() || length < ssi_samples_needed(o, p, y.cols(), r)) {
    return;
  }
  oma_detail::segment_standard_errors(
      nb,
      [&](int b) {
        return poles_of(record_ssi(y.middleRows(b * length, length), refs, p, o, false, 1).factor,
                        h, o);
      },
      o, modes);
}

// First-order perturbation standard errors of the SSI-cov modes (decision 0036): the Hankel
// matrix of the record, the square-root factor of its covariance from n_b blocks, and each
// mode's sensitivities at its own order. Returns how many modes' standard errors came out
// non-finite (left NaN), or -1 when the blocks are too short for any.
int perturbation_uncertainty(const Eigen::MatrixXd& y, const oma_detail::HankelSvd& hankel,
                             const std::vector<int>& refs, int p, double h, const OmaOptions& o,
                             std::vector<OmaMode>& modes) {
  const int nb = o.uncertainty_blocks;
  const Eigen::Index length = y.rows() / std::max(nb, 1);
  const auto r = static_cast<Eigen::Index>(refs.size());
  if (nb < 2 || modes.empty()) return 0;
  if (length < ssi_samples_needed(o, p, y.cols(), r)) return -1;
  const Eigen::MatrixXd factor = oma_detail::hankel_covariance_factor(y, refs, p, nb);
  int highest = 0;
  for (const OmaMode& m : modes) highest = std::max(highest, m.order);
  const auto changes = oma_detail::observability_changes(hankel, highest, factor);
  int failed = 0;
  for (OmaMode& m : modes) {
    const double wn = 2.0 * std::numbers::pi * m.frequency_hz;
    const std::complex<double> s(-m.damping_ratio * wn,
                                 wn * std::sqrt(1.0 - m.damping_ratio * m.damping_ratio));
    const auto sensitivity = oma_detail::pole_sensitivity(hankel, static_cast<int>(y.cols()),
                                                          m.order, h, std::exp(s * h), changes);
    const bool same = sensitivity.has_value() &&
                      std::abs(sensitivity->frequency_hz / m.frequency_hz - 1.0) < 1e-6;
    const auto root_sum = [](const auto& row) {
      const double v = std::sqrt(row.squaredNorm());
      return std::isfinite(v) ? v : kNaN;
    };
    if (!same) {
      ++failed;
      continue;
    }
    m.frequency_hz_std = root_sum(sensitivity->frequency);
    m.damping_ratio_std = root_sum(sensitivity->damping);
    bool finite = std::isfinite(m.frequency_hz_std) && std::isfinite(m.damping_ratio_std);
    for (std::size_t j = 0; j < m.shape_real.size(); ++j) {
      const auto row = sensitivity->shape_change.row(static_cast<Eigen::Index>(j));
      m.shape_real_std[j] = root_sum(row.real().eval());
      m.shape_imag_std[j] = root_sum(row.imag().eval());
      finite = finite && std::isfinite(m.shape_real_std[j]) && std::isfinite(m.shape_imag_std[j]);
    }
    if (!finite) ++failed;
  }
  return failed;
}

// The standard errors the options ask for, and what the message says about them.
std::string standard_errors(const Eigen::MatrixXd& y, const RecordSsi& record,
                            const std::vector<int>& refs, int p, double h, const OmaOptions& o,
                            std::vector<OmaMode>& modes) {
  if (o.uncertainty_blocks < 2 || modes.empty()) return "";
  if (o.method == OmaMethod::ssi_data || o.uncertainty == OmaUncertainty::segments) {
    segment_uncertainty(y, refs, p, h, o, modes);
    return "";
  }
  const int failed = perturbation_uncertainty(y, record.svd, refs, p, h, o, modes);
  if (failed < 0) {
    return internal::concat("; no standard errors: ", o.uncertainty_blocks,
                            " blocks are too short for ", p, " block rows");
  }
  std::string note = internal::concat("; first-order perturbation standard errors from ",
                                      o.uncertainty_blocks, " blocks");
  if (failed > 0) {
    note += internal::concat(" (NaN for ", failed,
                             " mode(s): the perturbation is singular there, e.g. two equal "
                             "singular values)");
  }
  return note;
}

int automatic_segment_length(Eigen::Index samples) {
  int length = 256;
  while (2 * length <= samples / 8 && 2 * length <= 16384) length *= 2;
  return static_cast<int>(std::min<Eigen::Index>(length, samples));
}

// One mode of fdd or efdd at a peak line: the first singular vector there is its shape.
OmaMode spectral_mode(const oma_detail::SingularSpectrum& spectrum,
                      const oma_detail::SpectralMatrix& spectral, int line,
                      const OmaOptions& options, double sample_time) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  OmaMode mode;
  mode.frequency_hz = oma_detail::interpolated_peak_hz(spectrum, spectral.frequency_hz, line);
  mode.frequency_hz_std = mode.damping_ratio = mode.damping_ratio_std = nan;
  if (options.method == OmaMethod::efdd) {
    const oma_detail::BellEstimate bell =
        oma_detail::efdd_bell(spectrum, spectral, line, options.efdd_mac, sample_time);
    if (std::isfinite(bell.frequency_hz)) mode.frequency_hz = bell.frequency_hz;
    mode.damping_ratio = bell.damping_ratio;
  }
  const Eigen::VectorXcd shape =
      oma_detail::normalise_shape(spectrum.first_vector[static_cast<std::size_t>(line)]);
  for (Eigen::Index j = 0; j < shape.size(); ++j) {
    mode.shape_real.push_back(shape(j).real());
    mode.shape_imag.push_back(shape(j).imag());
  }
  mode.shape_real_std.assign(mode.shape_real.size(), nan);
  mode.shape_imag_std.assign(mode.shape_real.size(), nan);
  mode.mpc = oma_detail::modal_phase_collinearity(shape);
  mode.mpd = oma_detail::mean_phase_deviation(shape);
  return mode;
}

// fdd and efdd: the peaks of the first singular value (or the ones nearest modes_near_hz).
struct OutputSpectrum {
  oma_detail::SpectralMatrix spectral;
  oma_detail::SingularSpectrum singular;
};

// The spectral matrix and its singular values, the first of which every method's result
// carries (the curve behind the stabilisation diagram).
OutputSpectrum output_spectrum(const Eigen::MatrixXd& outputs, double sample_time,
                               const OmaOptions& options, OmaResult& result) {
  const int length = options.segment_length > 0 ? options.segment_length
                                                : automatic_segment_length(outputs.rows());
  OutputSpectrum s;
  s.spectral = oma_detail::output_spectral_matrix(outputs, sample_time, length);
  s.singular = oma_detail::singular_spectrum(s.spectral);
  const Eigen::VectorXd& f = s.spectral.frequency_hz;
  const Eigen::VectorXd s1 = s.singular.values.col(0);
  result.spectrum_hz.assign(f.data(), f.data() + f.size());
  result.first_singular_value.assign(s1.data(), s1.data() + s1.size());
  return s;
}

// Automatic block rows (decision 0035): the order rule's p, raised so that the lags, 2p - 1
// samples, span kLagPeriods periods of the lowest peak of the first singular value, within
// kMaxHankelRows rows or columns of the Hankel matrix, kSamplesPerBlockRow samples per
// block row and the samples ssi-data needs. When the budget stops short, `note` says how many
// periods the lags span.
int block_rows_for_lowest_peak(const OutputSpectrum& spectrum, int p, Eigen::Index l,
                               Eigen::Index r, Eigen::Index n, double sample_time,
                               const OmaOptions& options, std::string& note) {
  const std::vector<int> peaks =
      oma_detail::singular_value_peaks(spectrum.singular, options.peak_prominence_db);
  if (peaks.empty()) return p;
  const double lowest_hz = spectrum.spectral.frequency_hz(peaks.front());
  const double wanted = std::ceil(0.5 * (kLagPeriods / (lowest_hz * sample_time) + 1.0));
  // SSI-data's Hankel matrix has p (l + r) rows, SSI-cov's p l rows and p r columns.
  const bool data = options.method == OmaMethod::ssi_data;
  const auto width = static_cast<double>(data ? l + r : std::max(l, r));
  double budget = std::min(std::floor(kMaxHankelRows / width),
                           std::floor(static_cast<double>(n) / kSamplesPerBlockRow));
  while (budget > p && ssi_samples_needed(options, static_cast<int>(budget), l, r) > n) --budget;
  const int raised = static_cast<int>(std::max<double>(p, std::min(wanted, budget)));
  if (wanted > budget) {
    note = internal::concat(
        "; lags span ", format_significant((2.0 * raised - 1.0) * sample_time * lowest_hz, 2),
        " periods of the lowest spectral peak at ", format_significant(lowest_hz, 4), " Hz; ",
        static_cast<int>(wanted), " block rows would span ", kLagPeriods);
  }
  return raised;
}

void spectral_oma(const Eigen::MatrixXd& outputs, double sample_time, const OmaOptions& options,
                  OmaResult& result) {
  const OutputSpectrum both = output_spectrum(outputs, sample_time, options, result);
  const oma_detail::SpectralMatrix& spectral = both.spectral;
  const oma_detail::SingularSpectrum& spectrum = both.singular;
  const int length = spectral.segment_length;
  std::vector<int> lines;
  if (options.modes_near_hz.empty()) {
    lines = oma_detail::singular_value_peaks(spectrum, options.peak_prominence_db);
    if (lines.empty()) {
      result.verdict.fail(
          internal::concat("no mode found: no peak of the first singular value stands ",
                           options.peak_prominence_db, " dB above its valleys"),
          {"a lower --peak-prominence-db", verdict_advice::more_data});
    }
  }
  for (const double f : options.modes_near_hz) {
    const int line = oma_detail::peak_near(spectrum, spectral.frequency_hz, f);
    const double nyquist_hz = 0.5 / sample_time;
    if (f >= nyquist_hz) {
      result.verdict.fail(internal::concat("no mode near ", f,
                                           " Hz: it is not below the Nyquist "
                                           "frequency ",
                                           nyquist_hz, " Hz"),
                          {"a record sampled faster"});
    } else if (line < 1) {
      result.verdict.fail(internal::concat("no spectral line within 10 % of ", f, " Hz"),
                          {"a longer --segment-length", verdict_advice::more_data});
    } else if (std::find(lines.begin(), lines.end(), line) == lines.end()) {
      lines.push_back(line);
    }
  }
  std::sort(lines.begin(), lines.end());
  for (const int line : lines) {
    result.modes.push_back(spectral_mode(spectrum, spectral, line, options, sample_time));
  }
  result.termination = Termination::converged;
  result.message = internal::concat(result.modes.size(),
                                    " mode(s) from the first singular value of the spectral "
                                    "matrix (",
                                    length, "-sample segments, ", spectral.segments, " averaged)");
}

}  // namespace

// pLSCF (decision 0066): the diagram's order is the polynomial order q (r q poles each, as
// pyOMA2 counts its orders). Lags: the SSI choice 2p - 1 (spanning periods of
// the lowest peak), 4 per polynomial coefficient (the M/2 + 1 lines then two per coefficient)
// or kPlscfMinLags (lines close enough to resolve neighbouring modes), at most a tenth of the
// samples and at least 2 per coefficient. The segments of the standard errors use as many lags
// as they hold at 5 samples each, at least 2 per coefficient.
int plscf_lags(int p, Eigen::Index samples, int largest) {
  const int wanted = std::max({2 * p - 1, 4 * (largest + 1), kPlscfMinLags});
  const int lags = static_cast<int>(std::min<Eigen::Index>(wanted, samples / 10));
  require(lags >= 2 * (largest + 1), "the record has ", samples, " samples; plscf to ",
          "polynomial order ", largest, " (--max-order) needs at least ", 20 * (largest + 1),
          " (10 per lag over 2 (order + 1) lags; a lower --max-order or a longer record)");
  return lags;
}

oma_detail::PolesOfOrder plscf_poles_of(const Eigen::MatrixXd& y, const std::vector<int>& refs,
                                        int lags, double h, int largest, const OmaOptions& o) {
  auto spectra = std::make_shared<const oma_detail::HalfSpectra>(
      oma_detail::half_spectra(y, refs, lags, h, largest));
  return [spectra, max_damping = o.max_damping](int q) {
    return oma_detail::plscf_poles(*spectra, q, max_damping);
  };
}

void plscf_oma(const Eigen::MatrixXd& y, const std::vector<int>& refs, int p, double h,
               const OmaOptions& o, const std::string& lag_note, OmaResult& result) {
  const int r = static_cast<int>(refs.size());
  // Polynomial orders 1..Q, Q = max_order, or ceil(4 max_order / r) with more than 4 references:
  // at most 4 max_order + r poles at the largest order.
  const int largest = std::min(o.max_order, (4 * o.max_order + r - 1) / r);
  const int lags = plscf_lags(p, y.rows(), largest);
  OmaOptions orders = o;  // the diagram's orders are 1..largest
  orders.max_order = largest;
  oma_detail::ssi_modes(plscf_poles_of(y, refs, lags, h, largest, o), orders, result);
  // Standard errors from segments (no first-order perturbation of pLSCF here).
  const int nb = o.uncertainty_blocks;
  const Eigen::Index length = y.rows() / std::max(nb, 1);
  std::string error_note;
  if (nb >= 2 && !result.modes.empty()) {
    const int block_lags = static_cast<int>(std::min<Eigen::Index>(lags, length / 5));
    if (block_lags >= 2 * (largest + 1)) {
      oma_detail::segment_standard_errors(
          nb,
          [&](int b) {
            return plscf_poles_of(y.middleRows(b * length, length), refs, block_lags, h, largest,
                                  o);
          },
          o, result.modes);
      error_note =
          internal::concat("; standard errors from ", nb, " segments of ", block_lags, " lags");
    } else {
      error_note = internal::concat("; no standard errors: ", nb, " blocks of ", length,
                                    " samples are too short for polynomial order ", largest);
    }
  }
  result.termination = Termination::converged;
  result.message =
      internal::concat(result.modes.size(), " mode(s) from polynomial orders 1..", largest, " (", r,
                       " poles per order; ", lags, " lags", lag_note, ")", error_note);
}

OmaResult oma(const Eigen::MatrixXd& outputs, double sample_time, const OmaOptions& options,
              std::vector<std::string> channel_names) {
  options.validate();
  const Eigen::Index l = outputs.cols();
  if (channel_names.empty()) {
    for (Eigen::Index j = 0; j < l; ++j) channel_names.push_back("y" + std::to_string(j + 1));
  }
  require(static_cast<Eigen::Index>(channel_names.size()) == l, "channel_names has ",
          channel_names.size(), " names for ", l, " channels");
  check_record(outputs, sample_time, channel_names);
  std::vector<int> refs = options.reference_channels;
  if (refs.empty()) {
    for (int j = 0; j < static_cast<int>(l); ++j) refs.push_back(j);
  }
  for (std::size_t i = 0; i < refs.size(); ++i) {
    require(refs[i] < l, "OmaOptions.reference_channels[", i, "] is ", refs[i], "; it must be < ",
            l, " (the number of channels)");
  }
  OmaResult result;
  result.method = options.method;
  result.sample_time = sample_time;
  result.samples = static_cast<int>(outputs.rows());
  result.channels = channel_names;
  result.reference_channels = refs;
  if (options.method == OmaMethod::fdd || options.method == OmaMethod::efdd) {
    spectral_oma(outputs, sample_time, options, result);
    return result;
  }
  int p = pick_block_rows(options, l, static_cast<Eigen::Index>(refs.size()), outputs.rows());
  const OutputSpectrum spectrum = output_spectrum(outputs, sample_time, options, result);
  std::string lag_note;
  if (options.block_rows == 0) {
    p = block_rows_for_lowest_peak(spectrum, p, l, static_cast<Eigen::Index>(refs.size()),
                                   outputs.rows(), sample_time, options, lag_note);
  }
  result.block_rows = p;
  const auto r = static_cast<Eigen::Index>(refs.size());
  if (options.method == OmaMethod::plscf) {
    plscf_oma(outputs, refs, p, sample_time, options, lag_note, result);
    return result;
  }
  const bool with_errors =
      options.uncertainty_blocks >= 2 &&
      outputs.rows() / options.uncertainty_blocks >= ssi_samples_needed(options, p, l, r);
  const RecordSsi record = record_ssi(outputs, refs, p, options, with_errors);
  oma_detail::ssi_modes(poles_of(record.factor, sample_time, options), options, result);
  const std::string error_note =
      standard_errors(outputs, record, refs, p, sample_time, options, result.modes);
  result.termination = Termination::converged;
  result.message =
      internal::concat(result.modes.size(), " mode(s) from orders 2..", options.max_order, " (", p,
                       " block rows", lag_note, ")", error_note);
  return result;
}

namespace oma_detail {

SsiFactor record_factor(const Eigen::MatrixXd& y, const std::vector<int>& refs, int p,
                        const OmaOptions& options, int threads) {
  return record_ssi(y, refs, p, options, false, threads).factor;
}

// SSI-cov kSamplesPerBlockRow per block row; SSI-data that too, and at least as many Hankel
// columns as rows.
Eigen::Index ssi_samples_needed(const OmaOptions& o, int p, Eigen::Index l, Eigen::Index r) {
  const Eigen::Index needed = static_cast<Eigen::Index>(kSamplesPerBlockRow) * p;
  if (o.method != OmaMethod::ssi_data) return needed;
  return std::max(needed, ssi_data_samples_needed(p, l, r));
}

void ssi_modes(const PolesOfOrder& poles, const OmaOptions& options, OmaResult& result) {
  const auto orders = all_orders(poles, options);
  const auto stability = classify_poles(orders, options);
  for (std::size_t o = 0; o < orders.size(); ++o) {
    for (std::size_t k = 0; k < orders[o].poles.size(); ++k) {
      const ModalPole& q = orders[o].poles[k];
      result.stabilisation.push_back(
          {orders[o].order, q.frequency_hz, q.damping_ratio, stability[o][k], q.mpc});
    }
  }
  const auto clusters = cluster_stable_poles(orders, stability, options.cluster_distance);
  result.modes = pick_modes(clusters, orders, options, result.verdict);
  result.iterations = static_cast<int>(orders.size());
}

void segment_standard_errors(int nb, const std::function<PolesOfOrder(int)>& block_poles,
                             const OmaOptions& o, std::vector<OmaMode>& modes) {
  const std::size_t m = modes.size();
  std::vector<std::vector<double>> f(m), z(m);
  std::vector<std::vector<Eigen::VectorXcd>> shapes(m);
  // The blocks' poles on threads (each block on one), the matching in block order.
  std::vector<PolesOfOrder> blocks(static_cast<std::size_t>(nb));
  parallel_for(nb, 0, [&](int b) { blocks[static_cast<std::size_t>(b)] = block_poles(b); });
  for (const PolesOfOrder& poles_of_order : blocks) {
    for (std::size_t i = 0; i < m; ++i) {
      const auto poles = poles_of_order(modes[i].order);
      const Eigen::VectorXcd ref = shape_of(modes[i]);
      const ModalPole* best = nullptr;
      double best_d = 0.0;
      for (const ModalPole& q : poles) {
        const double df = std::abs(q.frequency_hz - modes[i].frequency_hz) / modes[i].frequency_hz;
        const double d = df + 1.0 - modal_assurance(ref, q.shape);
        if (df < o.cluster_distance * 5.0 && (best == nullptr || d < best_d)) {
          best = &q;
          best_d = d;
        }
      }
      if (best == nullptr) continue;
      f[i].push_back(best->frequency_hz);
      z[i].push_back(best->damping_ratio);
      const std::complex<double> alpha = best->shape.dot(ref) / best->shape.squaredNorm();
      shapes[i].push_back(alpha * best->shape);
    }
  }
  for (std::size_t i = 0; i < m; ++i) {
    modes[i].frequency_hz_std = spread(f[i], nb);
    modes[i].damping_ratio_std = spread(z[i], nb);
    for (std::size_t j = 0; j < modes[i].shape_real.size(); ++j) {
      std::vector<double> re, im;
      for (const auto& s : shapes[i]) {
        re.push_back(s(static_cast<Eigen::Index>(j)).real());
        im.push_back(s(static_cast<Eigen::Index>(j)).imag());
      }
      modes[i].shape_real_std[j] = spread(re, nb);
      modes[i].shape_imag_std[j] = spread(im, nb);
    }
  }
}

Eigen::VectorXcd shape_of(const OmaMode& m) {
  Eigen::VectorXcd s(static_cast<Eigen::Index>(m.shape_real.size()));
  for (Eigen::Index j = 0; j < s.size(); ++j) {
    s(j) = {m.shape_real[static_cast<std::size_t>(j)], m.shape_imag[static_cast<std::size_t>(j)]};
  }
  return s;
}

}  // namespace oma_detail

}  // namespace ctid
