// Multi-setup output-only modal analysis: PoSER (decision 0059) and PreGER (decision 0062),
// multi_setup.h.
#include "ctid/oma/multi_setup.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/oma/ssi_cov.h"
#include "oma/internal/ssi_pipeline.h"

namespace ctid {
namespace oma_detail {

Eigen::VectorXcd poser_shape(const std::vector<Eigen::VectorXcd>& shapes,
                             const SetupLayout& layout) {
  const std::size_t r = layout.references.front().size();
  const Eigen::VectorXcd first = shapes[0](layout.references[0]);
  Eigen::VectorXcd global = Eigen::VectorXcd::Zero(layout.global_channels);
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const Eigen::VectorXcd own = shapes[s](layout.references[s]);
    const std::complex<double> alpha = own.dot(first) / own.squaredNorm();  // dot conjugates own
    global.head(static_cast<Eigen::Index>(r)) += alpha * own / static_cast<double>(shapes.size());
    for (std::size_t j = 0; j < layout.roving[s].size(); ++j) {
      const int g = layout.roving[s][j];
      if (g >= 0) global(g) = alpha * shapes[s](static_cast<Eigen::Index>(j));
    }
  }
  return global;
}

Eigen::MatrixXd preger_observability(const std::vector<Eigen::MatrixXd>& observabilities,
                                     const SetupLayout& layout) {
  const auto r = static_cast<Eigen::Index>(layout.references.front().size());
  const Eigen::Index g = layout.global_channels;
  const Eigen::Index l1 = static_cast<Eigen::Index>(layout.roving.front().size());
  const Eigen::Index p = observabilities.front().rows() / l1;
  Eigen::MatrixXd global(p * g, observabilities.front().cols());
  Eigen::MatrixXd first_references;
  for (std::size_t s = 0; s < observabilities.size(); ++s) {
    const Eigen::MatrixXd& own = observabilities[s];
    const auto l = static_cast<Eigen::Index>(layout.roving[s].size());
    Eigen::MatrixXd references(p * r, own.cols());
    for (Eigen::Index i = 0; i < p; ++i) {
      for (Eigen::Index k = 0; k < r; ++k) {
        references.row(i * r + k) =
            own.row(i * l + layout.references[s][static_cast<std::size_t>(k)]);
      }
    }
    if (s == 0) first_references = references;
    const Eigen::MatrixXd moved =
        s == 0 ? own
               : Eigen::MatrixXd(
                     own * references.completeOrthogonalDecomposition().solve(first_references));
    for (Eigen::Index i = 0; i < p; ++i) {
      if (s == 0) global.middleRows(i * g, r) = references.middleRows(i * r, r);
      for (Eigen::Index j = 0; j < l; ++j) {
        const int at = layout.roving[s][static_cast<std::size_t>(j)];
        if (at >= 0) global.row(i * g + at) = moved.row(i * l + j);
      }
    }
  }
  return global;
}

}  // namespace oma_detail

namespace multi_setup_detail {  // named: the module builds as one unit

using oma_detail::SetupLayout;

std::string listed(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

// The global channels (the references, then each setup's others) and where each setup's
// entries go; refuses what cannot be merged.
SetupLayout setup_layout(const std::vector<OmaSetup>& setups, const MultiSetupOptions& options,
                         std::vector<std::string>& channels) {
  require(setups.size() >= 2, "oma_multi_setup: ", setups.size(),
          " setup given; merging needs two or more (one record: oma)");
  const std::vector<std::string>& refs = options.reference_names;
  require(!refs.empty(),
          "oma_multi_setup: no reference channel; name the channels every setup measures");
  SetupLayout layout;
  channels = refs;
  std::vector<std::size_t> owner;  // the setup of each non-reference global channel
  for (std::size_t s = 0; s < setups.size(); ++s) {
    const OmaSetup& setup = setups[s];
    const std::vector<std::string>& names = setup.channel_names;
    require(static_cast<Eigen::Index>(names.size()) == setup.outputs.cols(), "setup ", s + 1, ": ",
            names.size(), " channel names for ", setup.outputs.cols(), " channels");
    require(std::abs(setup.sample_time - setups[0].sample_time) <=
                1e-6 * std::abs(setups[0].sample_time),
            "setup ", s + 1, "'s sample time ", setup.sample_time, " s differs from setup 1's ",
            setups[0].sample_time, " s; give setups of one sample time");
    std::vector<int> own_refs;
    for (const std::string& ref : refs) {
      const auto at = std::find(names.begin(), names.end(), ref);
      require(at != names.end(), "reference channel '", ref, "' is missing from setup ", s + 1,
              " (its channels: ", listed(names), ")");
      own_refs.push_back(static_cast<int>(at - names.begin()));
    }
    std::vector<int> roving;
    for (std::size_t j = 0; j < names.size(); ++j) {
      require(std::count(names.begin(), names.end(), names[j]) == 1, "setup ", s + 1,
              " names channel '", names[j], "' twice");
      if (std::find(refs.begin(), refs.end(), names[j]) != refs.end()) {
        roving.push_back(-1);
        continue;
      }
      const auto seen = std::find(channels.begin() + static_cast<std::ptrdiff_t>(refs.size()),
                                  channels.end(), names[j]);
      if (seen != channels.end()) {
        const std::size_t other =
            owner[static_cast<std::size_t>(seen - channels.begin()) - refs.size()];
        throw InvalidArgument(internal::concat(
            "channel '", names[j], "' is in setups ", other + 1, " and ", s + 1,
            " but is not a reference; name roving channels uniquely or list it as a reference"));
      }
      roving.push_back(static_cast<int>(channels.size()));
      channels.push_back(names[j]);
      owner.push_back(s);
    }
    layout.references.push_back(std::move(own_refs));
    layout.roving.push_back(std::move(roving));
  }
  layout.global_channels = static_cast<int>(channels.size());
  return layout;
}

// The index of the mode of `r` that is `anchor`'s (frequency within the tolerance, reference
// entries' MAC at least reference_mac, the best MAC among them), or -1. A mode whose reference
// entries are below 1e-3 of its largest entry (1) is one the references do not see: its scale
// onto setup 1 is undetermined, so it matches nothing.
int matching_mode(const OmaMode& anchor, const std::vector<int>& anchor_refs, const OmaResult& r,
                  const std::vector<int>& refs, const MultiSetupOptions& options) {
  constexpr double kSeen = 1e-3;
  const Eigen::VectorXcd a = oma_detail::shape_of(anchor)(anchor_refs);
  if (!(a.norm() > kSeen)) return -1;
  int best = -1;
  double best_mac = options.reference_mac;
  for (std::size_t i = 0; i < r.modes.size(); ++i) {
    const OmaMode& m = r.modes[i];
    if (std::abs(m.frequency_hz / anchor.frequency_hz - 1.0) > options.frequency_tolerance) {
      continue;
    }
    const Eigen::VectorXcd b = oma_detail::shape_of(m)(refs);
    if (!(b.norm() > kSeen)) continue;
    const double mac = oma_detail::modal_assurance(a, b);
    if (mac >= best_mac) {
      best_mac = mac;
      best = static_cast<int>(i);
    }
  }
  return best;
}

// The inverse-variance weighted mean of the setups' values and its standard error. Each
// setup's variance comes from `blocks` blocks (n_b - 1 = nu degrees of freedom), so 1 / se^2
// overstates 1 / sigma^2 by nu / (nu - 2) on average and the weights' sum with it: the
// variance 1 / sum(w) is scaled back by that factor (decision 0059). The plain mean, with
// sqrt(sum se^2) / n, when a setup has no standard error or nu <= 2.
std::pair<double, double> mean_of_setups(const std::vector<double>& values,
                                         const std::vector<double>& errors, int blocks) {
  const auto n = static_cast<double>(values.size());
  const double nu = blocks - 1.0;
  bool weighted = nu > 2.0;
  for (const double e : errors) weighted = weighted && std::isfinite(e) && e > 0.0;
  double sum = 0.0;
  double weights = 0.0;
  for (std::size_t k = 0; k < values.size(); ++k) {
    const double w = weighted ? 1.0 / (errors[k] * errors[k]) : 1.0;
    sum += w * values[k];
    weights += w;
  }
  if (weighted) return {sum / weights, std::sqrt(nu / (nu - 2.0) / weights)};
  double variance = 0.0;
  for (const double e : errors) variance += e * e / (n * n);
  return {sum / weights, std::sqrt(variance)};
}

// The merged shape, normalised at its largest entry (decision 0030), and the standard errors
// of its real and imaginary parts to first order: central differences through the merge in
// each setup's entries, taken as independent with their reported standard errors (the
// normalising entry kept where the unperturbed shape has it).
void merge_shapes(const std::vector<const OmaMode*>& modes, const SetupLayout& layout,
                  OmaMode& out) {
  std::vector<Eigen::VectorXcd> shapes;
  for (const OmaMode* m : modes) shapes.push_back(oma_detail::shape_of(*m));
  const Eigen::VectorXcd raw = oma_detail::poser_shape(shapes, layout);
  Eigen::Index at = 0;
  raw.cwiseAbs().maxCoeff(&at);
  const Eigen::VectorXcd global = raw / raw(at);
  const auto g = static_cast<std::size_t>(global.size());
  out.shape_real.assign(g, 0.0);
  out.shape_imag.assign(g, 0.0);
  for (std::size_t j = 0; j < g; ++j) {
    out.shape_real[j] = global(static_cast<Eigen::Index>(j)).real();
    out.shape_imag[j] = global(static_cast<Eigen::Index>(j)).imag();
  }
  Eigen::VectorXd var_real = Eigen::VectorXd::Zero(global.size());
  Eigen::VectorXd var_imag = Eigen::VectorXd::Zero(global.size());
  bool errors = true;
  for (std::size_t s = 0; s < modes.size(); ++s) {
    for (std::size_t j = 0; j < modes[s]->shape_real.size(); ++j) {
      for (const bool imaginary : {false, true}) {
        const double se = imaginary ? modes[s]->shape_imag_std[j] : modes[s]->shape_real_std[j];
        if (!std::isfinite(se)) errors = false;
        if (!(se > 0.0)) continue;
        const std::complex<double> step =
            imaginary ? std::complex<double>(0.0, 1e-6) : std::complex<double>(1e-6, 0.0);
        std::vector<Eigen::VectorXcd> up = shapes;
        std::vector<Eigen::VectorXcd> down = shapes;
        up[s](static_cast<Eigen::Index>(j)) += step;
        down[s](static_cast<Eigen::Index>(j)) -= step;
        const Eigen::VectorXcd u = oma_detail::poser_shape(up, layout);
        const Eigen::VectorXcd d = oma_detail::poser_shape(down, layout);
        const Eigen::VectorXcd change = (u / u(at) - d / d(at)) / 2e-6 * se;
        var_real += change.real().cwiseAbs2();
        var_imag += change.imag().cwiseAbs2();
      }
    }
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  out.shape_real_std.assign(g, nan);
  out.shape_imag_std.assign(g, nan);
  if (!errors) return;
  for (std::size_t j = 0; j < g; ++j) {
    out.shape_real_std[j] = std::sqrt(var_real(static_cast<Eigen::Index>(j)));
    out.shape_imag_std[j] = std::sqrt(var_imag(static_cast<Eigen::Index>(j)));
  }
}

}  // namespace multi_setup_detail

namespace oma_detail {

OmaMode poser_mode(const std::vector<const OmaMode*>& modes, const SetupLayout& layout,
                   int blocks) {
  OmaMode out;
  std::vector<double> f, f_se, z, z_se;
  out.supporting_orders = std::numeric_limits<int>::max();
  for (const OmaMode* m : modes) {
    f.push_back(m->frequency_hz);
    f_se.push_back(m->frequency_hz_std);
    z.push_back(m->damping_ratio);
    z_se.push_back(m->damping_ratio_std);
    out.supporting_orders = std::min(out.supporting_orders, m->supporting_orders);
  }
  std::tie(out.frequency_hz, out.frequency_hz_std) =
      multi_setup_detail::mean_of_setups(f, f_se, blocks);
  std::tie(out.damping_ratio, out.damping_ratio_std) =
      multi_setup_detail::mean_of_setups(z, z_se, blocks);
  out.order = modes.front()->order;
  multi_setup_detail::merge_shapes(modes, layout, out);
  const Eigen::VectorXcd shape = shape_of(out);
  out.mpc = oma_detail::modal_phase_collinearity(shape);
  out.mpd = oma_detail::mean_phase_deviation(shape);
  return out;
}

}  // namespace oma_detail

namespace multi_setup_detail {

// The merged result's description, shared by both merges.
OmaResult merged_frame(const std::vector<OmaResult>& setups,
                       const std::vector<std::string>& channels, std::size_t references) {
  OmaResult merged;
  merged.method = setups.front().method;
  merged.sample_time = setups.front().sample_time;
  merged.block_rows = setups.front().block_rows;
  merged.channels = channels;
  for (std::size_t k = 0; k < references; ++k) {
    merged.reference_channels.push_back(static_cast<int>(k));
  }
  for (const OmaResult& r : setups) merged.samples += r.samples;
  merged.termination = Termination::converged;
  return merged;
}

OmaResult poser_merge(const std::vector<OmaResult>& setups, const SetupLayout& layout,
                      const std::vector<std::string>& channels, const MultiSetupOptions& options) {
  OmaResult merged = merged_frame(setups, channels, options.reference_names.size());
  const OmaResult& first = setups.front();
  int left_out = 0;
  for (const OmaMode& anchor : first.modes) {
    std::vector<const OmaMode*> modes{&anchor};
    for (std::size_t s = 1; s < setups.size(); ++s) {
      const int i =
          matching_mode(anchor, layout.references[0], setups[s], layout.references[s], options);
      if (i < 0) break;
      modes.push_back(&setups[s].modes[static_cast<std::size_t>(i)]);
    }
    if (modes.size() < setups.size()) {
      ++left_out;
      continue;
    }
    merged.modes.push_back(oma_detail::poser_mode(modes, layout, options.oma.uncertainty_blocks));
  }
  merged.message = internal::concat(
      "PoSER merge of ", setups.size(), " setups: ", merged.modes.size(),
      merged.modes.size() == 1 ? " mode" : " modes", " found in every setup",
      left_out > 0 ? internal::concat(" (", left_out, " of setup 1's not in every setup)") : "");
  if (merged.modes.empty()) {
    merged.verdict.fail("no mode of setup 1 was found in every setup",
                        {"longer records, or a wider --merge-frequency-tolerance",
                         "reference channels where every mode moves"});
  }
  return merged;
}

// Each setup's observability matrix at the largest order, from block `block` of `blocks` of its
// record (1 block: the whole record), and the smallest numerical rank among them.
struct PregerSetups {
  std::vector<Eigen::MatrixXd> observabilities;
  int rank = 0;
};

PregerSetups preger_setups(const std::vector<OmaSetup>& setups, const SetupLayout& layout, int p,
                           const OmaOptions& o, int block, int blocks, int threads) {
  PregerSetups out;
  out.rank = o.max_order;
  for (std::size_t s = 0; s < setups.size(); ++s) {
    const Eigen::MatrixXd& y = setups[s].outputs;
    const Eigen::Index length = y.rows() / blocks;
    oma_detail::SsiFactor own = oma_detail::record_factor(y.middleRows(block * length, length),
                                                          layout.references[s], p, o, threads);
    out.rank = std::min(out.rank, own.rank);
    out.observabilities.push_back(std::move(own.observability));
  }
  return out;
}

// The poles of order n: each setup's observability matrix cut to its first n columns and merged
// at that order (the transforms T_s are n x n least-squares fits over the p r reference rows;
// one merge at the largest order instead lets the noise columns leak into the low orders and
// loses modes the references see, e.g. 119, 229 and 239 Hz of the flexible structure).
oma_detail::PolesOfOrder preger_poles(PregerSetups setups, const SetupLayout& layout, double h,
                                      double max_damping) {
  return [setups = std::move(setups), &layout, h, max_damping](int n) {
    std::vector<Eigen::MatrixXd> cut;
    for (const Eigen::MatrixXd& o : setups.observabilities) cut.push_back(o.leftCols(n));
    oma_detail::SsiFactor merged;
    merged.outputs = layout.global_channels;
    merged.rank = setups.rank;
    merged.observability = oma_detail::preger_observability(cut, layout);
    oma_detail::shift_factor(merged);
    return oma_detail::ssi_poles(merged, n, h, max_damping);
  };
}

// PreGER: one identification of the global observability matrix with the smallest of the
// setups' block rows, and segment standard errors (block b of every setup merged alike).
OmaResult preger_merge(const std::vector<OmaSetup>& setups, const std::vector<OmaResult>& own,
                       const SetupLayout& layout, const std::vector<std::string>& channels,
                       const MultiSetupOptions& options) {
  OmaResult merged = merged_frame(own, channels, options.reference_names.size());
  int p = own.front().block_rows;
  for (const OmaResult& r : own) p = std::min(p, r.block_rows);
  merged.block_rows = p;
  const OmaOptions& o = options.oma;
  const double h = merged.sample_time;
  oma_detail::ssi_modes(
      preger_poles(preger_setups(setups, layout, p, o, 0, 1, 0), layout, h, o.max_damping), o,
      merged);
  const int nb = o.uncertainty_blocks;
  bool blocks_long_enough = nb >= 2;
  for (const OmaSetup& setup : setups) {
    const auto l = setup.outputs.cols();
    const auto r = static_cast<Eigen::Index>(options.reference_names.size());
    blocks_long_enough = blocks_long_enough &&
                         setup.outputs.rows() / nb >= oma_detail::ssi_samples_needed(o, p, l, r);
  }
  std::string errors;
  if (blocks_long_enough && !merged.modes.empty()) {
    oma_detail::segment_standard_errors(
        nb,
        [&](int b) {
          return preger_poles(preger_setups(setups, layout, p, o, b, nb, 1), layout, h,
                              o.max_damping);
        },
        o, merged.modes);
    errors = internal::concat("; standard errors from ", nb, " segments of every setup");
  } else if (nb >= 2 && !merged.modes.empty()) {
    errors = internal::concat("; no standard errors: ", nb, " blocks of a setup are too short for ",
                              p, " block rows");
  }
  merged.message =
      internal::concat("PreGER merge of ", setups.size(), " setups: ", merged.modes.size(),
                       " mode(s) from orders 2..", o.max_order, " (", p, " block rows)", errors);
  return merged;
}

}  // namespace multi_setup_detail

MultiSetupResult oma_multi_setup(const std::vector<OmaSetup>& setups,
                                 const MultiSetupOptions& options) {
  namespace md = multi_setup_detail;
  options.validate();
  require(options.merge != OmaMerge::preger || options.oma.method == OmaMethod::ssi_cov ||
              options.oma.method == OmaMethod::ssi_data,
          "the PreGER merge needs an SSI method (ssi-cov or ssi-data); ",
          enum_name(options.oma.method), " has no observability matrix (use --merge poser)");
  std::vector<std::string> channels;
  const oma_detail::SetupLayout layout = md::setup_layout(setups, options, channels);
  MultiSetupResult result;
  for (std::size_t s = 0; s < setups.size(); ++s) {
    OmaOptions o = options.oma;
    o.reference_channels = layout.references[s];
    try {
      result.setups.push_back(
          oma(setups[s].outputs, setups[s].sample_time, o, setups[s].channel_names));
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(internal::concat("setup ", s + 1, ": ", e.what()));
    }
  }
  result.merged = options.merge == OmaMerge::preger
                      ? md::preger_merge(setups, result.setups, layout, channels, options)
                      : md::poser_merge(result.setups, layout, channels, options);
  return result;
}

}  // namespace ctid
