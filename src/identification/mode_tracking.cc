// Mode tracking over consecutive windows (mode_tracking.h, docs/decisions/0024-mode-tracking.md).
#include "ctid/identification/mode_tracking.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <utility>

#include "ctid/core/error.h"
#include "ctid/core/format.h"
#include "ctid/oma/ssi_cov.h"

namespace ctid {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Exact assignment (a dynamic programme over subsets of the window's modes) up to this many
// modes; 2^12 subsets times the tracks is instant.
constexpr int kExactModes = 12;

struct Score {
  int pairs = 0;
  double cost = 0.0;
  // More pairs first, then less cost.
  bool better_than(const Score& other) const {
    if (pairs != other.pairs) return pairs > other.pairs;
    return cost < other.cost;
  }
};

// The matching cost of a mode and a track's last value, or none beyond the gate.
std::optional<double> pair_cost(const ModalParameters& track, const ModalParameters& mode,
                                double max_frequency_jump, double damping_weight) {
  const double w = track.natural_frequency;
  if (!(w > 0.0) || !std::isfinite(mode.natural_frequency)) return std::nullopt;
  const double jump = std::abs(mode.natural_frequency - w) / w;
  if (!(jump <= max_frequency_jump)) return std::nullopt;
  const double damping = std::abs(mode.damping_ratio - track.damping_ratio);
  return jump + damping_weight * (std::isfinite(damping) ? damping : 0.0);
}

ModalParameters modal_value(const MimoMode& mode) {
  ModalParameters v;
  v.natural_frequency = mode.natural_frequency;
  v.damping_ratio = mode.damping_ratio;
  return v;
}

std::vector<int> assign_exact(const std::vector<std::vector<std::optional<double>>>& cost,
                              int track_count, int mode_count) {
  const std::size_t subsets = std::size_t{1} << mode_count;
  // best[t][mask]: the best score of tracks t.. using only modes outside `mask`; choice
  // remembers the mode given to track t (-1 none) there.
  std::vector<std::vector<Score>> best(static_cast<std::size_t>(track_count) + 1,
                                       std::vector<Score>(subsets));
  std::vector<std::vector<int>> choice(static_cast<std::size_t>(track_count),
                                       std::vector<int>(subsets, -1));
  for (int t = track_count - 1; t >= 0; --t) {
    const auto ts = static_cast<std::size_t>(t);
    for (std::size_t mask = 0; mask < subsets; ++mask) {
      Score chosen = best[ts + 1][mask];
      int pick = -1;
      for (int k = 0; k < mode_count; ++k) {
        const std::size_t bit = std::size_t{1} << k;
        const auto& c = cost[ts][static_cast<std::size_t>(k)];
        if ((mask & bit) != 0 || !c) continue;
        Score candidate = best[ts + 1][mask | bit];
        candidate.pairs += 1;
        candidate.cost += *c;
        if (candidate.better_than(chosen)) {
          chosen = candidate;
          pick = k;
        }
      }
      best[ts][mask] = chosen;
      choice[ts][mask] = pick;
    }
  }
  std::vector<int> assigned(static_cast<std::size_t>(mode_count), -1);
  std::size_t mask = 0;
  for (int t = 0; t < track_count; ++t) {
    const int k = choice[static_cast<std::size_t>(t)][mask];
    if (k < 0) continue;
    assigned[static_cast<std::size_t>(k)] = t;
    mask |= std::size_t{1} << k;
  }
  return assigned;
}

std::vector<int> assign_greedy(const std::vector<std::vector<std::optional<double>>>& cost,
                               int track_count, int mode_count) {
  struct Pair {
    double cost;
    int track;
    int mode;
  };
  std::vector<Pair> pairs;
  for (int t = 0; t < track_count; ++t) {
    for (int k = 0; k < mode_count; ++k) {
      const auto& c = cost[static_cast<std::size_t>(t)][static_cast<std::size_t>(k)];
      if (c) pairs.push_back({*c, t, k});
    }
  }
  std::stable_sort(pairs.begin(), pairs.end(),
                   [](const Pair& a, const Pair& b) { return a.cost < b.cost; });
  std::vector<int> assigned(static_cast<std::size_t>(mode_count), -1);
  std::vector<bool> taken(static_cast<std::size_t>(track_count), false);
  for (const Pair& p : pairs) {
    if (taken[static_cast<std::size_t>(p.track)] || assigned[static_cast<std::size_t>(p.mode)] >= 0)
      continue;
    taken[static_cast<std::size_t>(p.track)] = true;
    assigned[static_cast<std::size_t>(p.mode)] = p.track;
  }
  return assigned;
}

ModeTrack empty_track(int windows) {
  ModeTrack track;
  const auto n = static_cast<std::size_t>(windows);
  track.natural_frequency.assign(n, kNaN);
  track.natural_frequency_se.assign(n, kNaN);
  track.damping_ratio.assign(n, kNaN);
  track.damping_ratio_se.assign(n, kNaN);
  return track;
}

// Where window w of `layout` lies in a record starting at t0 with sample time h.
template <class Window>
void place_window(Window& window, const WindowLayout& layout, int w, double t0, double h) {
  window.first_sample = w * layout.step_samples;
  window.samples = layout.window_samples;
  window.start_time = t0 + window.first_sample * h;
  window.end_time = window.start_time + (layout.window_samples - 1) * h;
  window.centre_time = 0.5 * (window.start_time + window.end_time);
}

// A refused window: not run, not usable, the estimator's reason.
template <class Window>
void refuse_window(Window& window, const InvalidArgument& e) {
  window.termination = Termination::not_run;
  window.message = e.what();
  window.verdict.fail(internal::concat("the estimator refused the window: ", e.what()), {});
}

// Matched-window count, mean and drift of a track's natural frequencies.
void summarise(ModeTrack& track) {
  double sum = 0.0;
  double first = kNaN;
  double latest = kNaN;
  for (double value : track.natural_frequency) {
    if (std::isnan(value)) continue;
    ++track.windows_matched;
    sum += value;
    if (std::isnan(first)) first = value;
    latest = value;
  }
  if (track.windows_matched > 0) {
    track.mean_natural_frequency = sum / track.windows_matched;
    track.frequency_drift = latest - first;
  }
}

void fill_window(TrackingWindow& window, const EstimationResult& estimate) {
  static_cast<Outcome&>(window) = estimate;
  window.verdict = estimate.verdict;
  window.fit_percent = estimate.fit_percent;
  window.model = estimate.model;
  window.modes = estimate.modes;
  window.tracks.assign(estimate.modes.size(), -1);
}

}  // namespace

namespace {

// window_layout() of either options (`who`: their type's name, for the messages).
template <class Options>
WindowLayout layout_windows(const Options& options, int samples, double sample_time,
                            std::string_view who) {
  options.validate();
  const double record = samples * sample_time;
  require(options.window > 0.0, who, ".window is 0; give the window length in seconds (> 0)");
  WindowLayout layout;
  const double window_samples = std::round(options.window / sample_time);
  require(window_samples <= samples, who, ".window is ", format_number(options.window), " s (",
          format_number(window_samples), " samples); the record has ", samples, " samples (",
          format_number(record), " s), so the window must not be longer");
  require(window_samples >= 2, who, ".window is ", format_number(options.window),
          " s, less than 2 samples of ", format_number(sample_time), " s");
  layout.window_samples = static_cast<int>(window_samples);
  const double step = options.step.value_or(options.window);
  const double step_samples = options.step ? std::round(step / sample_time) : window_samples;
  require(step_samples >= 1, who, ".step is ", format_number(step), " s, less than half a sample (",
          format_number(sample_time), " s)");
  layout.step_samples = static_cast<int>(std::min<double>(step_samples, samples));
  layout.count = 1 + (samples - layout.window_samples) / layout.step_samples;
  require(layout.count >= 2, who, ": a window of ", layout.window_samples, " samples moved by ",
          layout.step_samples, " samples fits ", layout.count, " time in a record of ", samples,
          " samples; tracking needs at least 2 windows (a shorter window or step)");
  return layout;
}

}  // namespace

WindowLayout window_layout(const TrackingOptions& options, int samples, double sample_time) {
  return layout_windows(options, samples, sample_time, TrackingOptions::type_name);
}

namespace {

// The assignment of assign_modes() for the costs of every track (rows) and mode (columns).
std::vector<int> assign_by_cost(const std::vector<std::vector<std::optional<double>>>& cost,
                                int mode_count) {
  const int track_count = static_cast<int>(cost.size());
  if (track_count == 0 || mode_count == 0) {
    return std::vector<int>(static_cast<std::size_t>(mode_count), -1);
  }
  return mode_count <= kExactModes ? assign_exact(cost, track_count, mode_count)
                                   : assign_greedy(cost, track_count, mode_count);
}

}  // namespace

std::vector<int> assign_modes(const std::vector<ModalParameters>& tracks,
                              const std::vector<ModalParameters>& modes,
                              const TrackingOptions& options) {
  std::vector<std::vector<std::optional<double>>> cost(
      tracks.size(), std::vector<std::optional<double>>(modes.size()));
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    for (std::size_t k = 0; k < modes.size(); ++k)
      cost[t][k] =
          pair_cost(tracks[t], modes[k], options.max_frequency_jump, options.damping_weight);
  }
  return assign_by_cost(cost, static_cast<int>(modes.size()));
}

std::vector<int> assign_mimo_modes(const std::vector<MimoMode>& tracks,
                                   const std::vector<MimoMode>& modes,
                                   const MimoTrackingOptions& options) {
  options.validate();
  std::vector<std::vector<std::optional<double>>> cost(
      tracks.size(), std::vector<std::optional<double>>(modes.size()));
  for (std::size_t t = 0; t < tracks.size(); ++t) {
    for (std::size_t k = 0; k < modes.size(); ++k) {
      require(modes[k].shape.size() == tracks[t].shape.size(), "assign_mimo_modes: mode ", k + 1,
              " has a shape of ", modes[k].shape.size(), " outputs; track ", t + 1, "'s has ",
              tracks[t].shape.size());
      const double mac = modal_assurance(tracks[t].shape, modes[k].shape);
      if (!(mac >= options.min_mac)) continue;
      const std::optional<double> c = pair_cost(modal_value(tracks[t]), modal_value(modes[k]),
                                                options.max_frequency_jump, options.damping_weight);
      if (c) cost[t][k] = *c + options.mac_weight * (1.0 - mac);
    }
  }
  return assign_by_cost(cost, static_cast<int>(modes.size()));
}

TrackingResult track_modes(const SampledData& data, const ModelStructure& structure,
                           const TrackingOptions& options,
                           const std::function<void(int, int)>& progress) {
  const WindowLayout layout = window_layout(options, data.size(), data.sample_time());
  validate_identification(structure, options.identification);

  TrackingResult result;
  result.sample_time = data.sample_time();
  result.window_samples = layout.window_samples;
  result.step_samples = layout.step_samples;
  // Each track's last matched mode, the reference the next window's modes are matched to.
  std::vector<ModalParameters> last;
  const double h = data.sample_time();
  bool previous_usable = false;
  bool ran = false;                          // some window was fitted
  std::optional<std::string> first_refusal;  // the first window the estimator refused
  for (int w = 0; w < layout.count; ++w) {
    TrackingWindow window;
    place_window(window, layout, w, data.start_time(), h);
    const SampledData piece = data.segment(window.first_sample, layout.window_samples);

    IdentificationOptions cold = options.identification;
    // A window the estimator refuses for its own data (a quiet stretch: no excitation) is
    // recorded as not usable; bad input that every window shares is thrown after the loop.
    std::optional<EstimationResult> estimate;
    try {
      if (w > 0 && options.warm_start && previous_usable) {
        IdentificationOptions warm = cold;
        warm.refined_iv.initial_model = *result.windows.back().model;
        window.start = WindowStart::previous_window;
        estimate = identify(piece, structure, warm).estimate;
        if (!estimate->verdict.usable && options.retry_unusable) {
          window.start = WindowStart::retried;
          estimate = identify(piece, structure, cold).estimate;
        }
      } else {
        window.start =
            w > 0 && options.warm_start ? WindowStart::after_unusable : WindowStart::automatic;
        estimate = identify(piece, structure, cold).estimate;
      }
    } catch (const InvalidArgument& e) {
      if (!first_refusal) first_refusal = e.what();
      estimate.reset();
      refuse_window(window, e);
    }
    if (!estimate) {
      previous_usable = false;
      result.windows.push_back(std::move(window));
      if (progress) progress(w + 1, layout.count);
      continue;
    }
    ran = true;
    fill_window(window, *estimate);
    previous_usable = estimate->verdict.usable;

    if (previous_usable) {
      ++result.usable_windows;
      std::vector<ModalParameters> values;
      for (const ModalEstimate& m : window.modes) values.push_back(m.value);
      window.tracks = assign_modes(last, values, options);
      for (std::size_t k = 0; k < window.modes.size(); ++k) {
        if (window.tracks[k] < 0) {
          window.tracks[k] = static_cast<int>(result.tracks.size());
          result.tracks.push_back(empty_track(layout.count));
          last.push_back(values[k]);
        }
        const int t = window.tracks[k];
        const ModalEstimate& m = window.modes[k];
        ModeTrack& track = result.tracks[static_cast<std::size_t>(t)];
        const auto ws = static_cast<std::size_t>(w);
        track.natural_frequency[ws] = m.value.natural_frequency;
        track.natural_frequency_se[ws] = m.standard_error.natural_frequency;
        track.damping_ratio[ws] = m.value.damping_ratio;
        track.damping_ratio_se[ws] = m.standard_error.damping_ratio;
        last[static_cast<std::size_t>(t)] = m.value;
      }
    }
    result.windows.push_back(std::move(window));
    if (progress) progress(w + 1, layout.count);
  }

  if (!ran) {
    // Every window refused alike: bad input for this record, not an outcome.
    throw InvalidArgument(internal::concat("every window was refused; window 1: ", *first_refusal));
  }
  for (ModeTrack& track : result.tracks) summarise(track);
  return result;
}

namespace {

// A usable window w (of `windows`) of several outputs: its modes join the tracks (those left
// over start new ones), each with its MAC against its track's last shape; `last` holds each
// track's last matched mode.
void join_tracks(MimoTrackingResult& result, MimoTrackingWindow& window,
                 std::vector<MimoMode>& last, const MimoTrackingOptions& options, int w,
                 int windows) {
  ++result.usable_windows;
  window.tracks = assign_mimo_modes(last, window.modes, options);
  for (std::size_t k = 0; k < window.modes.size(); ++k) {
    const MimoMode& m = window.modes[k];
    if (window.tracks[k] < 0) {
      window.tracks[k] = static_cast<int>(result.tracks.size());
      MimoModeTrack track;
      static_cast<ModeTrack&>(track) = empty_track(windows);
      track.mac.assign(static_cast<std::size_t>(windows), kNaN);
      result.tracks.push_back(std::move(track));
      last.push_back(m);
    } else {
      window.mac[k] =
          modal_assurance(last[static_cast<std::size_t>(window.tracks[k])].shape, m.shape);
    }
    const auto t = static_cast<std::size_t>(window.tracks[k]);
    const auto ws = static_cast<std::size_t>(w);
    MimoModeTrack& track = result.tracks[t];
    track.natural_frequency[ws] = m.natural_frequency;
    track.natural_frequency_se[ws] = m.natural_frequency_se;
    track.damping_ratio[ws] = m.damping_ratio;
    track.damping_ratio_se[ws] = m.damping_ratio_se;
    track.mac[ws] = window.mac[k];
    last[t] = m;
  }
}

// An output-only mode as the tracker's MimoMode: rad/s, the complex shape with its standard
// errors, no participation.
MimoMode as_mimo_mode(const OmaMode& m, int index) {
  MimoMode out;
  out.submodel = index;
  out.natural_frequency = 2.0 * std::numbers::pi * m.frequency_hz;
  out.natural_frequency_se = 2.0 * std::numbers::pi * m.frequency_hz_std;
  out.damping_ratio = m.damping_ratio;
  out.damping_ratio_se = m.damping_ratio_std;
  const auto l = static_cast<Eigen::Index>(m.shape_real.size());
  out.shape = oma_detail::shape_of(m);
  out.shape_se_real = Eigen::Map<const Eigen::VectorXd>(m.shape_real_std.data(), l);
  out.shape_se_imag = Eigen::Map<const Eigen::VectorXd>(m.shape_imag_std.data(), l);
  return out;
}

}  // namespace

MimoTrackingResult track_output_only_modes(const Eigen::MatrixXd& outputs, double sample_time,
                                           double start_time,
                                           std::vector<std::string> channel_names,
                                           const OmaTrackingOptions& options,
                                           const std::function<void(int, int)>& progress) {
  const auto samples = static_cast<int>(outputs.rows());
  const WindowLayout layout =
      layout_windows(options, samples, sample_time, OmaTrackingOptions::type_name);
  options.oma.validate();
  if (channel_names.empty()) {
    for (Eigen::Index j = 0; j < outputs.cols(); ++j) {
      channel_names.push_back("y" + std::to_string(j + 1));
    }
  }
  MimoTrackingOptions gates;  // the matching of track_mimo_modes, with these gates
  gates.max_frequency_jump = options.max_frequency_jump;
  gates.damping_weight = options.damping_weight;
  gates.mac_weight = options.mac_weight;
  gates.min_mac = options.min_mac;
  MimoTrackingResult result;
  result.sample_time = sample_time;
  result.window_samples = layout.window_samples;
  result.step_samples = layout.step_samples;
  result.output_names = channel_names;
  std::vector<MimoMode> last;
  bool ran = false;
  std::optional<std::string> first_refusal;
  for (int w = 0; w < layout.count; ++w) {
    MimoTrackingWindow window;
    place_window(window, layout, w, start_time, sample_time);
    std::optional<OmaResult> analysed;
    try {
      analysed = oma(outputs.middleRows(window.first_sample, layout.window_samples), sample_time,
                     options.oma, channel_names);
    } catch (const InvalidArgument& e) {
      if (!first_refusal) first_refusal = e.what();
      refuse_window(window, e);
    }
    if (analysed) {
      ran = true;
      window.termination = analysed->termination;
      window.message = analysed->message;
      window.iterations = analysed->iterations;
      window.verdict = analysed->verdict;
      for (std::size_t k = 0; k < analysed->modes.size(); ++k) {
        window.modes.push_back(as_mimo_mode(analysed->modes[k], static_cast<int>(k)));
      }
      window.tracks.assign(window.modes.size(), -1);
      window.mac.assign(window.modes.size(), kNaN);
      if (window.verdict.usable) join_tracks(result, window, last, gates, w, layout.count);
    }
    result.windows.push_back(std::move(window));
    if (progress) progress(w + 1, layout.count);
  }
  if (!ran) {
    throw InvalidArgument(internal::concat("every window was refused; window 1: ", *first_refusal));
  }
  for (MimoModeTrack& track : result.tracks) summarise(track);
  return result;
}

MimoTrackingResult track_mimo_modes(const MimoData& data, const std::vector<SubmodelOrder>& orders,
                                    const MimoTrackingOptions& options,
                                    const std::function<void(int, int)>& progress) {
  const WindowLayout layout =
      layout_windows(options, data.size(), data.sample_time(), MimoTrackingOptions::type_name);
  options.refined_iv.validate();

  MimoTrackingResult result;
  result.sample_time = data.sample_time();
  result.window_samples = layout.window_samples;
  result.step_samples = layout.step_samples;
  result.output_names = data.output_names();
  std::vector<MimoMode> last;  // each track's last matched mode
  const double h = data.sample_time();
  bool previous_usable = false;
  bool ran = false;
  std::optional<std::string> first_refusal;
  for (int w = 0; w < layout.count; ++w) {
    MimoTrackingWindow window;
    place_window(window, layout, w, data.start_time(), h);
    const MimoData piece = data.segment(window.first_sample, layout.window_samples);
    std::optional<MimoEstimationResult> estimate;
    try {
      if (w > 0 && options.warm_start && previous_usable) {
        window.start = WindowStart::previous_window;
        estimate = mimo_srivc(piece, orders, options.refined_iv, result.windows.back().model);
        if (!estimate->verdict.usable && options.retry_unusable) {
          window.start = WindowStart::retried;
          estimate = mimo_srivc(piece, orders, options.refined_iv, options.initial_model);
        }
      } else {
        window.start =
            w > 0 && options.warm_start ? WindowStart::after_unusable : WindowStart::automatic;
        estimate = mimo_srivc(piece, orders, options.refined_iv, options.initial_model);
      }
    } catch (const InvalidArgument& e) {
      if (!first_refusal) first_refusal = e.what();
      estimate.reset();
      refuse_window(window, e);
    }
    previous_usable = estimate && estimate->verdict.usable && estimate->model;
    if (estimate) {
      ran = true;
      window.termination = estimate->termination;
      window.message = estimate->message;
      window.iterations = estimate->iterations;
      window.verdict = estimate->verdict;
      window.fit_percent = estimate->fit_percent;
      window.model = estimate->model;
      window.modes = estimate->modes;
      window.tracks.assign(window.modes.size(), -1);
      window.mac.assign(window.modes.size(), kNaN);
    }
    if (previous_usable) join_tracks(result, window, last, options, w, layout.count);
    result.windows.push_back(std::move(window));
    if (progress) progress(w + 1, layout.count);
  }
  if (!ran) {
    throw InvalidArgument(internal::concat("every window was refused; window 1: ", *first_refusal));
  }
  for (MimoModeTrack& track : result.tracks) summarise(track);
  return result;
}

}  // namespace ctid
