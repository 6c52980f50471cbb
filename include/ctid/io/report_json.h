// Documents of the analyses around an estimate (docs/formats.md): the residual tests of a
// model on data (`ctid validate -o`), a nonparametric FRF (`ctid frf -o X.json`), the
// summary of a Section 6 study of González et al. (`ctid study`) and a structure scan
// (`ctid structure -o`). Each is a typed, versioned JSON object written from its struct's
// field list and read back bit for bit (NaN as null).
#pragma once

#include <string>
#include <type_traits>

#include <nlohmann/json.hpp>

#include "ctid/estimation/validation.h"
#include "ctid/frequency/frf.h"
#include "ctid/frequency/mimo_frf.h"
#include "ctid/frf_fit/frf_matrix_fit.h"
#include "ctid/identification/mimo_structure_scan.h"
#include "ctid/identification/structure_scan.h"
#include "ctid/oma/oma.h"
#include "ctid/refined_iv/mimo_srivc.h"
#include "ctid/study/paper_study.h"
#include "ctid/study/study_output.h"

namespace ctid::io {

/// The "type" values of these documents.
inline constexpr const char* kValidationReportType = "validation_report";
inline constexpr const char* kFrfType = "frf";
inline constexpr const char* kMimoFrfType = "mimo_frf";
inline constexpr const char* kOmaResultType = "oma_result";
inline constexpr const char* kStudySummaryType = "study_summary";
inline constexpr const char* kStructureScanResultType = "structure_scan_result";
inline constexpr const char* kMimoStructureScanResultType = "mimo_structure_scan_result";
inline constexpr const char* kMimoEstimationResultType = "mimo_estimation_result";
inline constexpr const char* kFrfMatrixFitResultType = "frf_matrix_fit_result";

/// {"type": "validation_report", "version": 1, <fields>} with, restating them for readers,
/// "autocorrelation_lags" [1, max_lag], "cross_correlation_lags" (-max_lag..max_lag),
/// "residual_white", "residual_uncorrelated_with_input" and "bound_99" (= whiteness_bound).
nlohmann::json to_json(const ValidationReport& report);
/// Reads it back; the restated keys and the context `ctid validate` writes ("model_file",
/// "data", and with --horizon "prediction") are accepted and not read.
ValidationReport validation_report_from_json(const nlohmann::json& value,
                                             const std::string& source);

/// {"type": "frf", "version": 1, <fields>}, the complex response as [real, imag] pairs.
nlohmann::json to_json(const Frf& frf);
/// Reads it back; the context `ctid frf` writes ("method", "data", "peaks") is accepted and
/// not read.
Frf frf_from_json(const nlohmann::json& value, const std::string& source);

/// {"type": "mimo_frf", "version": 1, "inputs": [names], "outputs": [names], "lines",
/// "frequencies", "response": [line][output][input] as [real, imag], "variance":
/// [line][output][input], "coherence" and "output_power": [line][output], "input_level":
/// [line][input], "input_condition": [line], "averages", "block_length"} (NaN as null).
nlohmann::json to_json(const MimoFrf& frf);
/// Reads it back (null as NaN); the context `ctid frf` writes ("method", "data", "peaks_of",
/// "peaks") is accepted and not read. Every array's length is checked against the lines,
/// outputs and inputs, and an error names the entry.
MimoFrf mimo_frf_from_json(const nlohmann::json& value, const std::string& source);

/// {"type": "oma_result", "version": 1, <fields>}: output-only modal analysis (docs/oma.md);
/// `ctid oma` adds "data", which the reader accepts.
nlohmann::json to_json(const OmaResult& result);
OmaResult oma_result_from_json(const nlohmann::json& value, const std::string& source);

/// {"type": "study_summary", "version": 1, <fields>}.
nlohmann::json to_json(const StudySummary& summary);
StudySummary study_summary_from_json(const nlohmann::json& value, const std::string& source);

/// {"type": "structure_scan_result", "version": 1, <fields>}: every fit with its estimate as
/// a transfer_function document (model_json.h), the recommendation and the stabilisation
/// diagram.
nlohmann::json to_json(const StructureScanResult& scan);
/// The shared-pole estimate (`ctid fit --input-columns ...`): its fields; `ctid fit` adds
/// "data", which the reader accepts.
nlohmann::json to_json(const MimoEstimationResult& result);
MimoEstimationResult mimo_estimation_result_from_json(const nlohmann::json& value,
                                                      const std::string& source);
/// The modal model fitted to an FRF matrix (`ctid fit-frf -o`): its fields; `ctid fit-frf`
/// adds "data" (the FRF file and its size), which the reader accepts.
nlohmann::json to_json(const FrfMatrixFitResult& result);
FrfMatrixFitResult frf_matrix_fit_result_from_json(const nlohmann::json& value,
                                                   const std::string& source);
/// Reads it back; the context `ctid structure` writes ("data") is accepted and not read.
StructureScanResult structure_scan_result_from_json(const nlohmann::json& value,
                                                    const std::string& source);
/// {"type": "mimo_structure_scan_result", "version": 1, <fields>} (`ctid structure
/// --input-columns ... --output-columns ...`): every mode count's scores, the recommendation
/// and the stabilisation diagram; the reader accepts the "data" the command adds.
nlohmann::json to_json(const MimoStructureScanResult& scan);
MimoStructureScanResult mimo_structure_scan_result_from_json(const nlohmann::json& value,
                                                             const std::string& source);

}  // namespace ctid::io
