// The result document of the delayed-feedback identification (ctid feedback, Python and the
// library write and read it): {"type": "delayed_feedback_result", "version": 1, ...} with one
// key per field of FeedbackIdentificationResult (io/fields_json.h) under "identification" and,
// when the delay was scanned, the scan under "delay_scan". Loops are written as the model
// documents of io/model_json.h ("type": "delayed_feedback_loop", transfer functions with
// numerator_ascending / denominator_ascending), polynomials as ascending coefficient arrays.
// Doubles are written with full precision and read back bit-identical; a non-finite double is
// written as null and read back as NaN.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>

#include <nlohmann/json.hpp>

#include "ctid/core/fields.h"
#include "ctid/core/polynomial.h"
#include "ctid/delayed_feedback/feedback_delay_scan.h"
#include "ctid/delayed_feedback/identification.h"
#include "ctid/io/file.h"
#include "ctid/simulation/delayed_feedback.h"

namespace ctid {

// JSON of the non-field types inside delayed-feedback results, found by argument-dependent
// lookup from io/fields_json.h. A loop is read without validation (a result may hold the
// zero placeholder loop of a candidate that was never refined).
nlohmann::json to_json_value(const Polynomial& polynomial);
Polynomial from_json_value(const nlohmann::json& value, std::type_identity<Polynomial>,
                           const std::string& where);
nlohmann::json to_json_value(const DelayedFeedbackLoop& loop);
DelayedFeedbackLoop from_json_value(const nlohmann::json& value,
                                    std::type_identity<DelayedFeedbackLoop>,
                                    const std::string& where);

}  // namespace ctid

namespace ctid::io {

inline constexpr std::string_view kDelayedFeedbackResultType = "delayed_feedback_result";
inline constexpr int kDelayedFeedbackResultVersion = 1;

/// What `ctid feedback` computes: the identification at the known or scanned delay, and the
/// scan when the delay was unknown.
struct DelayedFeedbackResult {
  FeedbackIdentificationResult identification;
  std::optional<FeedbackDelayScanResult> delay_scan;

  static constexpr std::string_view type_name = "DelayedFeedbackResult";
  static constexpr auto fields() {
    using R = DelayedFeedbackResult;
    return std::tuple{
        field("identification", &R::identification,
              "FeedbackIdentificationResult at the known or scanned delay."),
        field("delay_scan", &R::delay_scan, "The delay scan, when the delay was unknown."),
    };
  }
};

/// The typed, versioned document of a delayed-feedback result.
nlohmann::json to_json(const DelayedFeedbackResult& result);
/// Reads it back; InvalidArgument naming `source` and the field on a wrong type, version or
/// field.
DelayedFeedbackResult delayed_feedback_result_from_json(const nlohmann::json& value,
                                                        const std::string& source);
/// True when `value` is a delayed_feedback_result document.
bool is_delayed_feedback_result(const nlohmann::json& value);

DelayedFeedbackResult read_delayed_feedback_result(const std::filesystem::path& path);
void write_delayed_feedback_result(const std::filesystem::path& path,
                                   const DelayedFeedbackResult& result,
                                   Overwrite overwrite = Overwrite::no);

}  // namespace ctid::io
