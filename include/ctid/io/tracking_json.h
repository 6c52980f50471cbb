// Mode tracking results as JSON (docs/formats.md, "mode_tracking_result"): every field of a
// TrackingResult (identification/mode_tracking.h), with frequencies in rad/s and Hz beside, and the
// per-window, per-track table `ctid track --table` writes.
#pragma once

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "ctid/identification/mode_tracking.h"
#include "ctid/io/file.h"

namespace ctid::io {

/// The "type" of a mode tracking document.
inline constexpr const char* kModeTrackingResultType = "mode_tracking_result";
/// The "type" of a mode tracking document of several outputs (track_mimo_modes).
inline constexpr const char* kMimoModeTrackingResultType = "mimo_mode_tracking_result";

/// The result as one JSON object with "type": "mode_tracking_result" and "version": 1: the
/// fields of TrackingResult, each window's modes flat as in an estimation_result
/// (natural_frequency, natural_frequency_standard_error, natural_frequency_hz, ...,
/// damping_ratio, gain, with "track"), and each track's per-window arrays with
/// natural_frequency_hz and natural_frequency_se_hz beside (null where not matched).
nlohmann::json to_json(const TrackingResult& result);

/// The tracking table as CSV text: one row per window and track, columns window, t_start,
/// t_centre, t_end, track, frequency_hz, frequency_se_hz, damping, damping_se, usable
/// (windows and tracks counted from 1; empty cells where the track has no mode in the window;
/// usable is 1 or 0). A result without tracks gives one row per window with empty track cells.
std::string tracking_table_csv(const TrackingResult& result);

/// Writes tracking_table_csv() to `path` (through a temporary moved into place).
void write_tracking_table(const std::filesystem::path& path, const TrackingResult& result,
                          Overwrite overwrite = Overwrite::no);

/// A MimoTrackingResult as one JSON object with "type": "mimo_mode_tracking_result" and
/// "version": 1: its fields (every window's MimoMode with its shape), each window's mode with
/// "track", "mac" and natural_frequency_hz / natural_frequency_se_hz beside, and each track's
/// per-window arrays in Hz as in to_json(const TrackingResult&).
nlohmann::json to_json(const MimoTrackingResult& result);

/// The table of tracking_table_csv() with a column mac (the MAC of the track's mode with its
/// previous shape; empty in the window where the track starts) before usable.
std::string tracking_table_csv(const MimoTrackingResult& result);
void write_tracking_table(const std::filesystem::path& path, const MimoTrackingResult& result,
                          Overwrite overwrite = Overwrite::no);

}  // namespace ctid::io
