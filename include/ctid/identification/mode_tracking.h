// Mode tracking (issue 17): consecutive windows of one record, each fitted by identify() with a
// warm start from the previous window's model, and the second-order modes of the windows
// matched into tracks (a mode followed across windows) by an optimal assignment on frequency
// and damping. What it does and why: docs/tracking.md, docs/decisions/0024-mode-tracking.md.
#pragma once

#include <array>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "ctid/core/additive_model.h"
#include "ctid/core/fields.h"
#include "ctid/core/mimo_data.h"
#include "ctid/core/mimo_model.h"
#include "ctid/core/sampled_data.h"
#include "ctid/estimation/mimo_modes.h"
#include "ctid/estimation/termination.h"
#include "ctid/estimation/verdict.h"
#include "ctid/identification/identification.h"
#include "ctid/oma/oma.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/mimo_srivc.h"

namespace ctid {

struct TrackingOptions {
  /// Length of every window [s], rounded to whole samples (round(window / h) samples). It has
  /// no sensible default: 0 (the default) means not set, and track_modes() refuses it.
  double window = 0.0;
  /// Distance between the starts of consecutive windows [s], rounded to whole samples (at
  /// least one); none: the window length (adjacent windows, no overlap).
  std::optional<double> step;
  /// Options of identify() for every window. Its refined_iv.initial_model, if given, starts
  /// the first window (and every window whose warm start is not available); none: the
  /// automatic start of the structure.
  IdentificationOptions identification;
  /// Start window k > 1 from window k - 1's model (when that fit was usable).
  bool warm_start = true;
  /// A warm-started fit that is not usable is fitted again from the automatic start, and the
  /// refit is kept.
  bool retry_unusable = true;
  /// Gate of the matching: a mode is matched to a track only if their natural frequencies
  /// differ by at most this fraction of the track's; otherwise it starts a new track.
  double max_frequency_jump = 0.1;
  /// Weight of the damping-ratio difference in the matching cost
  /// |w - w_track| / w_track + damping_weight |zeta - zeta_track|.
  double damping_weight = 1.0;

  static constexpr std::string_view type_name = "TrackingOptions";
  static constexpr auto fields() {
    using O = TrackingOptions;
    return std::tuple{
        field("window", &O::window, Finite{AtLeast{0.0}},
              "Window length [s], rounded to whole samples; 0: not set (refused)."),
        field("step", &O::step, Finite{GreaterThan{0.0}},
              "Step between window starts [s], rounded to whole samples; none: the window."),
        field("identification", &O::identification,
              "IdentificationOptions of every window's identify()."),
        field("warm_start", &O::warm_start,
              "Start each window from the previous window's model when that fit was usable."),
        field("retry_unusable", &O::retry_unusable,
              "Refit a warm-started window that is not usable from the automatic start."),
        field("max_frequency_jump", &O::max_frequency_jump, Finite{GreaterThan{0.0}},
              "Largest relative frequency difference of a mode and the track it joins."),
        field("damping_weight", &O::damping_weight, Finite{AtLeast{0.0}},
              "Weight of the damping-ratio difference in the matching cost."),
    };
  }
  /// Throws InvalidArgument naming the first bad field by its full path, its value and the rule.
  void validate() const { validate_fields(*this); }
};

/// Where a window's fit started.
enum class WindowStart {
  automatic,        ///< the structure's automatic start (or the given initial model)
  previous_window,  ///< the model of the previous window (warm start)
  after_unusable,   ///< automatic, because the previous window's fit was not usable
  retried,          ///< automatic, after the warm-started fit was not usable
};

inline constexpr std::array<Enumerator<WindowStart>, 4> window_start_enumerators{{
    {WindowStart::automatic, "automatic",
     "The automatic start of the structure (or the given initial model)."},
    {WindowStart::previous_window, "previous_window", "The previous window's model."},
    {WindowStart::after_unusable, "after_unusable",
     "The automatic start, because the previous window's fit was not usable."},
    {WindowStart::retried, "retried",
     "The automatic start, after the warm-started fit was not usable."},
}};
constexpr std::span<const Enumerator<WindowStart>> enumerators(WindowStart) {
  return window_start_enumerators;
}

/// One window: where it lies, how its fit started and ended, and its modes. Termination,
/// message and iterations (Outcome) are the fit's.
struct TrackingWindow : Outcome {
  int first_sample = 0;      ///< index of its first sample in the record
  int samples = 0;           ///< samples in the window
  double start_time = 0.0;   ///< time of its first sample [s]
  double end_time = 0.0;     ///< time of its last sample [s]
  double centre_time = 0.0;  ///< (start_time + end_time) / 2 [s]
  WindowStart start = WindowStart::automatic;
  Verdict verdict;  ///< the fit's quality verdict (estimation/verdict.h)
  double fit_percent = std::numeric_limits<double>::quiet_NaN();
  std::optional<AdditiveModel> model;  ///< the fitted model (input delay in seconds)
  std::vector<ModalEstimate> modes;    ///< every second-order mode of the fit (rad/s)
  /// The track of each mode (same order as modes); -1 for the modes of an unusable window,
  /// which are not matched.
  std::vector<int> tracks;

  static constexpr std::string_view type_name = "TrackingWindow";
  static constexpr auto fields() {
    using W = TrackingWindow;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("first_sample", &W::first_sample, "Index of its first sample in the record."),
            field("samples", &W::samples, "Samples in the window."),
            field("start_time", &W::start_time, "Time of its first sample [s]."),
            field("end_time", &W::end_time, "Time of its last sample [s]."),
            field("centre_time", &W::centre_time, "(start_time + end_time) / 2 [s]."),
            field("start", &W::start, "Where the fit started."),
            field("verdict", &W::verdict, "The fit's quality verdict."),
            field("fit_percent", &W::fit_percent, "Output-error fit of the window [%]."),
            field("model", &W::model, "The fitted AdditiveModel, or none."),
            field("modes", &W::modes, "ModalEstimate of every second-order mode (rad/s)."),
            field("tracks", &W::tracks,
                  "Track of each mode; -1 for the modes of an unusable window."),
        });
  }
};

/// A mode followed across windows: per window (NaN where it was not matched) its natural
/// frequency [rad/s], damping ratio and their standard errors.
struct ModeTrack {
  std::vector<double> natural_frequency;
  std::vector<double> natural_frequency_se;
  std::vector<double> damping_ratio;
  std::vector<double> damping_ratio_se;
  int windows_matched = 0;
  /// Mean of the matched natural frequencies [rad/s].
  double mean_natural_frequency = std::numeric_limits<double>::quiet_NaN();
  /// Last matched natural frequency minus the first [rad/s].
  double frequency_drift = std::numeric_limits<double>::quiet_NaN();

  static constexpr std::string_view type_name = "ModeTrack";
  static constexpr auto fields() {
    using T = ModeTrack;
    return std::tuple{
        field("natural_frequency", &T::natural_frequency,
              "Per window, w_n [rad/s]; NaN where not matched."),
        field("natural_frequency_se", &T::natural_frequency_se,
              "Per window, its standard error [rad/s]."),
        field("damping_ratio", &T::damping_ratio, "Per window, zeta; NaN where not matched."),
        field("damping_ratio_se", &T::damping_ratio_se, "Per window, its standard error."),
        field("windows_matched", &T::windows_matched, "Windows in which the mode was matched."),
        field("mean_natural_frequency", &T::mean_natural_frequency,
              "Mean of the matched natural frequencies [rad/s]."),
        field("frequency_drift", &T::frequency_drift,
              "Last matched natural frequency minus the first [rad/s]."),
    };
  }
};

struct TrackingResult {
  double sample_time = 0.0;
  int window_samples = 0;  ///< samples per window
  int step_samples = 0;    ///< samples between window starts
  std::vector<TrackingWindow> windows;
  std::vector<ModeTrack> tracks;
  int usable_windows = 0;  ///< windows whose fit passed the verdict

  static constexpr std::string_view type_name = "TrackingResult";
  static constexpr auto fields() {
    using R = TrackingResult;
    return std::tuple{
        field("sample_time", &R::sample_time, "Sample time of the record [s]."),
        field("window_samples", &R::window_samples, "Samples per window."),
        field("step_samples", &R::step_samples, "Samples between window starts."),
        field("windows", &R::windows, "TrackingWindow of every window, in time order."),
        field("tracks", &R::tracks, "ModeTrack of every mode followed across windows."),
        field("usable_windows", &R::usable_windows, "Windows whose fit passed the verdict."),
    };
  }
};

/// The windows track_modes() cuts a record of `samples` samples at sample time h into: their
/// length and step in samples and their count. Throws InvalidArgument (naming the option and
/// the record) for a window shorter than 2 samples or longer than the record, a step that
/// rounds to 0 samples, or fewer than 2 windows.
struct WindowLayout {
  int window_samples = 0;
  int step_samples = 0;
  int count = 0;
};
WindowLayout window_layout(const TrackingOptions& options, int samples, double sample_time);

/// The optimal assignment of `modes` (natural frequency [rad/s] and damping ratio) to the
/// `tracks`' last matched values: each mode joins at most one track and each track takes at
/// most one mode; a pair is allowed only if the relative frequency difference is at most
/// options.max_frequency_jump; among the assignments with the most pairs the one of least
/// total cost |w - w_t| / w_t + damping_weight |zeta - zeta_t| is chosen (exact for up to 12
/// modes, greedy by cost beyond). Returns the track of each mode, -1 where none.
std::vector<int> assign_modes(const std::vector<ModalParameters>& tracks,
                              const std::vector<ModalParameters>& modes,
                              const TrackingOptions& options);

/// Fits `structure` to consecutive windows of `data` (window_layout) with identify(), each
/// window after the first started from the previous window's model (options.warm_start) when
/// that fit was usable and from the automatic start otherwise, and matches the modes of the
/// usable windows into tracks (assign_modes against each track's last matched mode; a mode
/// left over starts a new track). Throws InvalidArgument for bad options or windows (before
/// any fit), and when the estimator refuses every window (its message for window 1); a window
/// it refuses for that window's data alone (a stretch without excitation) is kept as not
/// usable, its reason the estimator's message. How each fit ended is in its window.
/// `progress`, if given, is called with (windows done, windows) after each window.
TrackingResult track_modes(const SampledData& data, const ModelStructure& structure,
                           const TrackingOptions& options,
                           const std::function<void(int, int)>& progress = {});

// --- Several outputs: shared-pole fits and matching by mode shape (docs/decisions/0026) ---------

/// The refined IV options of a tracking window: those of mimo_srivc with the initial state
/// estimated (windows cut from a running record start mid-motion).
inline MimoRefinedIvOptions mimo_tracking_refined_iv() {
  MimoRefinedIvOptions options;
  options.initial_conditions = InitialConditions::estimate;
  return options;
}

struct MimoTrackingOptions {
  /// Length of every window [s], rounded to whole samples; 0 (the default) means not set, and
  /// track_modes() refuses it.
  double window = 0.0;
  /// Distance between the starts of consecutive windows [s], rounded to whole samples (at
  /// least one); none: the window length.
  std::optional<double> step;
  /// Options of mimo_srivc for every window; by default with initial_conditions = estimate.
  MimoRefinedIvOptions refined_iv = mimo_tracking_refined_iv();
  /// Start of the first window (and of every window whose warm start is not available); none:
  /// mimo_srivc's automatic start.
  std::optional<MimoAdditiveModel> initial_model;
  /// Start window k > 1 from window k - 1's model (when that fit was usable).
  bool warm_start = true;
  /// A warm-started fit that is not usable is fitted again from the automatic start.
  bool retry_unusable = true;
  /// Frequency gate: a mode joins a track only if their natural frequencies differ by at most
  /// this fraction of the track's.
  double max_frequency_jump = 0.1;
  /// Weight of the damping-ratio difference in the matching cost.
  double damping_weight = 1.0;
  /// Weight of 1 - MAC (the modal assurance criterion of the mode's shape and the track's last
  /// shape) in the matching cost |w - w_t| / w_t + damping_weight |zeta - zeta_t|
  /// + mac_weight (1 - MAC).
  double mac_weight = 1.0;
  /// Shape gate: a mode joins a track only if their MAC is at least this.
  double min_mac = 0.5;

  static constexpr std::string_view type_name = "MimoTrackingOptions";
  static constexpr auto fields() {
    using O = MimoTrackingOptions;
    return std::tuple{
        field("window", &O::window, Finite{AtLeast{0.0}},
              "Window length [s], rounded to whole samples; 0: not set (refused)."),
        field("step", &O::step, Finite{GreaterThan{0.0}},
              "Step between window starts [s], rounded to whole samples; none: the window."),
        field("refined_iv", &O::refined_iv,
              "MimoRefinedIvOptions of every window (initial conditions estimated by default)."),
        field("initial_model", &O::initial_model,
              "Start of the first window; none: the automatic start.")
            .with_flag("initial"),
        field("warm_start", &O::warm_start,
              "Start each window from the previous window's model when that fit was usable."),
        field("retry_unusable", &O::retry_unusable,
              "Refit a warm-started window that is not usable from the automatic start."),
        field("max_frequency_jump", &O::max_frequency_jump, Finite{GreaterThan{0.0}},
              "Largest relative frequency difference of a mode and the track it joins."),
        field("damping_weight", &O::damping_weight, Finite{AtLeast{0.0}},
              "Weight of the damping-ratio difference in the matching cost."),
        field("mac_weight", &O::mac_weight, Finite{AtLeast{0.0}},
              "Weight of 1 - MAC in the matching cost."),
        field("min_mac", &O::min_mac, Between{0.0, 1.0, true, true},
              "Smallest MAC of a mode's shape and the shape of the track it joins."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// One window of track_mimo_modes(): as TrackingWindow, with the shared-pole fit's modes (and
/// their shapes) and the MAC of each mode with the last shape of the track it joined.
struct MimoTrackingWindow : Outcome {
  int first_sample = 0;
  int samples = 0;
  double start_time = 0.0;
  double end_time = 0.0;
  double centre_time = 0.0;
  WindowStart start = WindowStart::automatic;
  Verdict verdict;
  Eigen::VectorXd fit_percent;  ///< per output [%]
  std::optional<MimoAdditiveModel> model;
  std::vector<MimoMode> modes;  ///< every second-order mode of the fit (rad/s)
  std::vector<int> tracks;      ///< track of each mode; -1 for those of an unusable window
  /// MAC of each mode's shape with its track's last shape; NaN for a mode that starts a track
  /// or is not matched.
  std::vector<double> mac;

  static constexpr std::string_view type_name = "MimoTrackingWindow";
  static constexpr auto fields() {
    using W = MimoTrackingWindow;
    return join_fields(
        Outcome::fields(),
        std::tuple{
            field("first_sample", &W::first_sample, "Index of its first sample in the record."),
            field("samples", &W::samples, "Samples in the window."),
            field("start_time", &W::start_time, "Time of its first sample [s]."),
            field("end_time", &W::end_time, "Time of its last sample [s]."),
            field("centre_time", &W::centre_time, "(start_time + end_time) / 2 [s]."),
            field("start", &W::start, "Where the fit started."),
            field("verdict", &W::verdict, "The fit's quality verdict."),
            field("fit_percent", &W::fit_percent, "Per output, the output-error fit [%]."),
            field("model", &W::model, "The fitted MimoAdditiveModel, or none."),
            field("modes", &W::modes, "MimoMode of every second-order mode (rad/s)."),
            field("tracks", &W::tracks,
                  "Track of each mode; -1 for the modes of an unusable window."),
            field("mac", &W::mac,
                  "MAC of each mode with its track's last shape; NaN where it starts a track."),
        });
  }
};

/// A mode followed across windows of several outputs: ModeTrack's series and the MAC of each
/// window's shape with the track's previous one (NaN where not matched or first matched).
struct MimoModeTrack : ModeTrack {
  std::vector<double> mac;

  static constexpr std::string_view type_name = "MimoModeTrack";
  static constexpr auto fields() {
    using T = MimoModeTrack;
    return join_fields(
        ModeTrack::fields(),
        std::tuple{field("mac", &T::mac, "Per window, MAC with the track's previous shape.")});
  }
};

struct MimoTrackingResult {
  double sample_time = 0.0;
  int window_samples = 0;
  int step_samples = 0;
  std::vector<std::string> output_names;  ///< the outputs the shapes run over
  std::vector<MimoTrackingWindow> windows;
  std::vector<MimoModeTrack> tracks;
  int usable_windows = 0;

  static constexpr std::string_view type_name = "MimoTrackingResult";
  static constexpr auto fields() {
    using R = MimoTrackingResult;
    return std::tuple{
        field("sample_time", &R::sample_time, "Sample time of the record [s]."),
        field("window_samples", &R::window_samples, "Samples per window."),
        field("step_samples", &R::step_samples, "Samples between window starts."),
        field("output_names", &R::output_names, "Names of the outputs of the mode shapes."),
        field("windows", &R::windows, "MimoTrackingWindow of every window, in time order."),
        field("tracks", &R::tracks, "MimoModeTrack of every mode followed across windows."),
        field("usable_windows", &R::usable_windows, "Windows whose fit passed the verdict."),
    };
  }
};

/// The optimal assignment of assign_modes() with the mode shapes as well: a pair is allowed
/// only if the relative frequency difference is at most options.max_frequency_jump and the MAC
/// of the shapes at least options.min_mac; its cost is |w - w_t| / w_t + damping_weight
/// |zeta - zeta_t| + mac_weight (1 - MAC). Returns the track of each mode, -1 where none.
/// Throws InvalidArgument for shapes of different lengths.
std::vector<int> assign_mimo_modes(const std::vector<MimoMode>& tracks,
                                   const std::vector<MimoMode>& modes,
                                   const MimoTrackingOptions& options);

/// track_modes() for a record of several outputs: consecutive windows fitted by mimo_srivc
/// with the submodels `orders` (shared poles; by default with each window's initial state
/// estimated), each window after the first started from the previous window's model when that fit
/// was usable and from the automatic start otherwise, and the modes of the usable windows matched
/// into tracks by frequency, damping and mode shape (assign_mimo_modes against each track's last
/// mode). Throws InvalidArgument for bad options or windows (before any fit) and when mimo_srivc
/// refuses every window; a window refused for its own data is kept as not usable.
MimoTrackingResult track_mimo_modes(const MimoData& data, const std::vector<SubmodelOrder>& orders,
                                    const MimoTrackingOptions& options,
                                    const std::function<void(int, int)>& progress = {});

/// Options of track_output_only_modes(): the windows and matching gates of MimoTrackingOptions,
/// each window analysed output-only by oma() with `oma` (issue 34's monitoring).
struct OmaTrackingOptions {
  /// Length of every window [s], rounded to whole samples; 0 means not set (refused).
  double window = 0.0;
  /// Distance between window starts [s], rounded to whole samples; none: the window length.
  std::optional<double> step;
  /// The output-only analysis of every window.
  OmaOptions oma;
  double max_frequency_jump = 0.1;
  double damping_weight = 1.0;
  double mac_weight = 1.0;
  double min_mac = 0.5;

  static constexpr std::string_view type_name = "OmaTrackingOptions";
  static constexpr auto fields() {
    using O = OmaTrackingOptions;
    return std::tuple{
        field("window", &O::window, Finite{AtLeast{0.0}},
              "Window length [s], rounded to whole samples; 0: not set (refused)."),
        field("step", &O::step, Finite{GreaterThan{0.0}},
              "Step between window starts [s], rounded to whole samples; none: the window."),
        field("oma", &O::oma, "OmaOptions of every window's output-only analysis."),
        field("max_frequency_jump", &O::max_frequency_jump, Finite{GreaterThan{0.0}},
              "Largest relative frequency difference of a mode and the track it joins."),
        field("damping_weight", &O::damping_weight, Finite{AtLeast{0.0}},
              "Weight of the damping-ratio difference in the matching cost."),
        field("mac_weight", &O::mac_weight, Finite{AtLeast{0.0}},
              "Weight of 1 - MAC in the matching cost."),
        field("min_mac", &O::min_mac, Between{0.0, 1.0, true, true},
              "Smallest MAC of a mode's shape and the shape of the track it joins."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// Modes of a record of several outputs and no input, followed through time: consecutive
/// windows (N x l `outputs` from `start_time`, sample time h, channels `channel_names`, empty:
/// y1..yl) each analysed by oma() with options.oma, and the modes of the windows where it found
/// any matched into tracks by frequency, damping and mode shape as track_mimo_modes matches
/// them. The result is a MimoTrackingResult: each window's modes as MimoMode (rad/s; shapes
/// normalised as oma's, decision 0030; no participation), no model, no fit. Throws
/// InvalidArgument for bad options or windows (before any analysis) and when oma() refuses
/// every window; a window refused for its own data is kept as not usable (decision 0060).
MimoTrackingResult track_output_only_modes(const Eigen::MatrixXd& outputs, double sample_time,
                                           double start_time,
                                           std::vector<std::string> channel_names,
                                           const OmaTrackingOptions& options,
                                           const std::function<void(int, int)>& progress = {});

}  // namespace ctid
