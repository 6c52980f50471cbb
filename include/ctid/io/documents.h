// Every result document ctid writes, read back through one door (docs/formats.md): the
// "type" of a JSON object picks the reader, its "version" is checked, and the result comes
// back as the C++ type that wrote it. Estimation results of the refined IV estimators
// (González et al.) with their mode relocation and delay scan, the residual tests of
// `ctid validate`, the FRF of `ctid frf`, the FRF-matrix fit of `ctid fit-frf`, the summary of
// `ctid study`, the delayed-feedback result of `ctid feedback` and the structure scan of `ctid
// structure`.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "ctid/estimation/validation.h"
#include "ctid/frequency/frf.h"
#include "ctid/frf_fit/frf_matrix_fit.h"
#include "ctid/identification/mimo_structure_scan.h"
#include "ctid/identification/structure_scan.h"
#include "ctid/io/feedback_result_json.h"
#include "ctid/io/file.h"
#include "ctid/oma/oma.h"
#include "ctid/refined_iv/estimation_result.h"
#include "ctid/refined_iv/input_delay_scan.h"
#include "ctid/refined_iv/mimo_srivc.h"
#include "ctid/refined_iv/mode_relocation.h"
#include "ctid/study/study_output.h"

namespace ctid::io {

/// A result read from a document, by its "type".
using ResultDocument = std::variant<EstimationResult, ModeRelocationResult, InputDelayScanResult,
                                    ValidationReport, Frf, StudySummary, DelayedFeedbackResult,
                                    StructureScanResult, MimoEstimationResult, FrfMatrixFitResult,
                                    MimoFrf, OmaResult, MimoStructureScanResult>;

/// The "type" values result_from_json reads, in the order of ResultDocument.
std::vector<std::string> result_document_types();

/// The result in `value`, by its "type" (estimation_result, mode_relocation_result,
/// input_delay_scan_result, validation_report, frf, study_summary, delayed_feedback_result,
/// structure_scan_result, mimo_estimation_result, frf_matrix_fit_result, mimo_frf, oma_result,
/// mimo_structure_scan_result).
/// Throws
/// InvalidArgument naming `source` for a missing or unknown type, an unknown version or a bad
/// field.
ResultDocument result_from_json(const nlohmann::json& value, const std::string& source);
ResultDocument read_result(const std::filesystem::path& path);

/// The document of any result (its own to_json).
nlohmann::json to_json(const ResultDocument& result);
/// The "type" the result is written under.
std::string_view document_type(const ResultDocument& result);
void write_result(const std::filesystem::path& path, const ResultDocument& result,
                  Overwrite overwrite = Overwrite::no);

}  // namespace ctid::io
