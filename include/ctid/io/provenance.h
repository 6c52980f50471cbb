// Where a result came from: the "data" block of every result document a command writes (fit,
// validate, frf, fit-frf, oma, structure, track). The commands fill what they know; this one
// function turns it into the block, so every document names its data the same way.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "ctid/core/hold.h"
#include "ctid/core/preprocessing.h"

namespace ctid::io {

/// The data a result was computed from. Each field that is set is one key of the block.
struct DataProvenance {
  std::vector<std::string> files{};  ///< "file": the first; "files": all, when there are several
  std::optional<long long> samples{};
  std::optional<double> sample_time{};                ///< [s]; the median step of irregular stamps
  std::optional<double> start_time{};                 ///< [s]
  std::optional<long long> lines{};                   ///< frequency lines of an FRF
  std::optional<std::vector<std::string>> inputs{};   ///< input channel names
  std::optional<std::vector<std::string>> outputs{};  ///< output channel names
  std::optional<Hold> input_hold{};
  std::optional<PreprocessingRecord> preprocessing{};
  std::vector<int> record_samples{};  ///< "record_samples": each record's length, when several
  /// Irregular time stamps: "time_stamps": "irregular" and the count of duplicate stamps.
  std::optional<int> duplicate_stamps{};
  std::optional<std::string> detrend{};  ///< the trend removed, when not in `preprocessing`
};

/// The "data" block of a result document.
nlohmann::json to_json(const DataProvenance& provenance);

}  // namespace ctid::io
