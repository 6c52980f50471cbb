// Mode tracking results as JSON and CSV (tracking_json.h).
#include "ctid/io/tracking_json.h"

#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "ctid/estimation/mimo_modes.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/model_json.h"
#include "ctid/io/result_json.h"

namespace ctid::io {
namespace {

using internal::number_or_null;

nlohmann::json hz(const std::vector<double>& rad_per_s) {
  nlohmann::json out = nlohmann::json::array();
  for (double w : rad_per_s) out.push_back(number_or_null(w / internal::kTwoPi));
  return out;
}

// A number as the table writes it: the shortest text that reads back exactly; empty when not
// finite.
std::string cell(double x) {
  if (!std::isfinite(x)) return "";
  std::array<char, 32> text{};
  const auto written = std::to_chars(text.data(), text.data() + text.size(), x);
  return std::string(text.data(), written.ptr);
}

// Each track's per-window frequencies and their summary in Hz beside the rad/s fields.
template <class Result>
void add_track_hz(nlohmann::json& value, const Result& result) {
  for (std::size_t t = 0; t < result.tracks.size(); ++t) {
    const ModeTrack& track = result.tracks[t];
    nlohmann::json& out = value["tracks"][t];
    out["natural_frequency_hz"] = hz(track.natural_frequency);
    out["natural_frequency_se_hz"] = hz(track.natural_frequency_se);
    out["mean_natural_frequency_hz"] =
        number_or_null(track.mean_natural_frequency / internal::kTwoPi);
    out["frequency_drift_hz"] = number_or_null(track.frequency_drift / internal::kTwoPi);
  }
}

}  // namespace

nlohmann::json to_json(const TrackingResult& result) {
  nlohmann::json value = fields_to_json(result);
  for (std::size_t w = 0; w < result.windows.size(); ++w) {
    const TrackingWindow& window = result.windows[w];
    nlohmann::json modes = nlohmann::json::array();
    for (std::size_t k = 0; k < window.modes.size(); ++k) {
      nlohmann::json mode = modal_json(window.modes[k]);  // keys sorted: "track" joins them
      mode["track"] = window.tracks[k];
      modes.push_back(std::move(mode));
    }
    value["windows"][w]["modes"] = std::move(modes);
  }
  add_track_hz(value, result);
  value["type"] = kModeTrackingResultType;
  value["version"] = kResultDocumentVersion;
  return value;
}

nlohmann::json to_json(const MimoTrackingResult& result) {
  nlohmann::json value = fields_to_json(result);
  for (std::size_t w = 0; w < result.windows.size(); ++w) {
    nlohmann::json& modes = value["windows"][w]["modes"];
    for (std::size_t k = 0; k < result.windows[w].modes.size(); ++k) {
      const MimoMode& m = result.windows[w].modes[k];
      modes[k]["track"] = result.windows[w].tracks[k];
      modes[k]["mac"] = number_or_null(result.windows[w].mac[k]);
      modes[k]["natural_frequency_hz"] = number_or_null(m.natural_frequency / internal::kTwoPi);
      modes[k]["natural_frequency_se_hz"] =
          number_or_null(m.natural_frequency_se / internal::kTwoPi);
    }
  }
  add_track_hz(value, result);
  value["type"] = kMimoModeTrackingResultType;
  value["version"] = kResultDocumentVersion;
  return value;
}

namespace {

// The table of either result; a MimoTrackingResult's has the column mac (the MAC with the
// track's previous shape) before usable.
template <class Result>
std::string table_csv(const Result& result) {
  constexpr bool mac = std::is_same_v<Result, MimoTrackingResult>;
  std::ostringstream out;
  out << "window,t_start,t_centre,t_end,track,frequency_hz,frequency_se_hz,damping,damping_se,"
      << (mac ? "mac," : "") << "usable\n";
  for (std::size_t w = 0; w < result.windows.size(); ++w) {
    const auto& window = result.windows[w];
    const std::string head = std::to_string(w + 1) + "," + cell(window.start_time) + "," +
                             cell(window.centre_time) + "," + cell(window.end_time) + ",";
    const std::string usable = window.verdict.usable ? "1" : "0";
    if (result.tracks.empty()) {
      out << head << ",,,,," << (mac ? "," : "") << usable << "\n";
      continue;
    }
    for (std::size_t t = 0; t < result.tracks.size(); ++t) {
      const auto& track = result.tracks[t];
      out << head << t + 1 << "," << cell(track.natural_frequency[w] / internal::kTwoPi) << ","
          << cell(track.natural_frequency_se[w] / internal::kTwoPi) << ","
          << cell(track.damping_ratio[w]) << "," << cell(track.damping_ratio_se[w]) << ",";
      if constexpr (mac) out << cell(track.mac[w]) << ",";
      out << usable << "\n";
    }
  }
  return out.str();
}

}  // namespace

std::string tracking_table_csv(const TrackingResult& result) { return table_csv(result); }
std::string tracking_table_csv(const MimoTrackingResult& result) { return table_csv(result); }

void write_tracking_table(const std::filesystem::path& path, const MimoTrackingResult& result,
                          Overwrite overwrite) {
  write_text_file(path, tracking_table_csv(result), overwrite);
}

void write_tracking_table(const std::filesystem::path& path, const TrackingResult& result,
                          Overwrite overwrite) {
  write_text_file(path, tracking_table_csv(result), overwrite);
}

}  // namespace ctid::io
