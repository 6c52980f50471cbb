// Every result document: written, read back through read_result and written again, it is the
// same JSON (doubles compare exactly, NaN is null both times), and the values read back equal
// the ones written bit for bit. Unknown types, versions and fields are refused with the source.
#include "ctid/io/documents.h"

#include <cmath>
#include <complex>
#include <cstdint>
#include <cstring>
#include <limits>
#include <variant>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/io/json.h"
#include "ctid/io/report_json.h"
#include "ctid/io/result_json.h"
#include "io/test_directory.h"

namespace ctid::io::documents_test {
namespace {

using ::testing::HasSubstr;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

AdditiveModel two_modes() {
  return AdditiveModel({Submodel{Polynomial{1.0, 0.25, 0.25}, Polynomial{3.0}, 0},
                        Submodel{Polynomial{1.0, 0.01, 0.025}, Polynomial{1.0, 0.002}, 0}},
                       0.1);
}

EstimationResult example_estimate() {
  const AdditiveModel model = two_modes();
  EstimationResult r(model, model.to_transfer_function());
  r.additive_view = model;
  r.parameters = model.parameters();
  const Eigen::Index p = r.parameters.size();
  r.covariance = Eigen::MatrixXd::Identity(p, p) * (1.0 / 3.0);
  r.covariance(0, 1) = r.covariance(1, 0) = 0.1 / 7.0;
  r.standard_errors = r.covariance.diagonal().cwiseSqrt();
  ModalEstimate mode;
  mode.submodel = 1;
  mode.value = *model.modal_parameters(1);
  mode.standard_error = {0.01, kNaN, 1.0 / 9.0};
  r.modes.push_back(mode);
  r.termination = Termination::iteration_limit;
  r.message = "stopped after 3 iterations";
  r.iterations = 3;
  r.relative_change = 1.0 / 11.0;
  r.off_diagonal_norm = 0.125;
  r.unstable_reflections = 2;
  r.sensitivity_fallbacks = 1;
  r.step_halvings = 5;
  r.input_delay_samples = 2;
  r.noise_variance = 0.5;
  r.mean_squared_error = std::sqrt(2.0);
  r.fit_percent = 97.5;
  r.checks.excitation_order = 7;
  r.checks.excitation_order_required = 8;
  r.checks.persistently_exciting = false;
  r.checks.largest_pole_frequency = 6.3;
  r.checks.nyquist_frequency = 31.4;
  r.checks.warnings.push_back("the input is not persistently exciting");
  IterationRecord record;
  record.iteration = 1;
  record.parameters = r.parameters * (1.0 + 1e-3);
  record.relative_change = 1.0 / 13.0;
  record.off_diagonal_norm = 0.25;
  r.history.push_back(record);
  return r;
}

ModeRelocationResult example_relocation() {
  ModeRelocationResult r(example_estimate());
  r.initial_mean_squared_error = 0.3;
  r.initial_projected_mean_squared_error = 0.2;
  r.projected_mean_squared_error = 0.1 / 3.0;
  r.initial_score = 0.2;
  r.score = 0.1 / 3.0;
  r.rounds = 2;
  r.relocations = 1;
  RelocationTrial trial;
  trial.round = 1;
  trial.submodel = 1;
  trial.moved_from = 6.0;
  trial.peak_frequency = 12.5;
  trial.peak_to_floor = 40.0;
  trial.start_frequency = 12.4;
  trial.start_damping = 1e-3;
  trial.start_mean_squared_error = 0.05;
  trial.mean_squared_error = kNaN;
  trial.projected_mean_squared_error = 0.04;
  trial.score = 0.04;
  trial.termination = Termination::converged;
  trial.accepted = true;
  r.trials = {trial, trial};
  r.trials[1].accepted = false;
  r.message = "moved submodel 1 to 12.4 rad/s";
  return r;
}

InputDelayScanResult example_scan() {
  InputDelayScanResult scan{example_estimate(), {0, 1, 2}, {0.5, kNaN, 0.25}, {}, {}, true, {}};
  scan.terminations = {Termination::converged, Termination::not_run, Termination::converged};
  return scan;
}

ValidationReport example_report() {
  ValidationReport report;
  report.fit_percent = 98.25;
  report.mean_squared_error = 1.0 / 3.0;
  report.residual_mean = -1e-3;
  report.residual_std = 0.2;
  report.max_lag = 2;
  report.residual_autocorrelation = Eigen::Vector2d(0.01, -0.02);
  report.cross_correlation = Eigen::VectorXd::LinSpaced(5, -0.1, 0.1);
  report.max_residual_autocorrelation = 0.02;
  report.max_cross_correlation = 0.1;
  report.whiteness_bound = 2.58 / std::sqrt(1000.0);
  return report;
}

Frf example_frf() {
  Frf frf;
  frf.lines = {1, 2, 3};
  frf.frequencies = Eigen::Vector3d(0.1, 0.2, 0.3);
  frf.response = Eigen::VectorXcd(3);
  frf.response << std::complex<double>(1.0 / 3.0, -0.5), std::complex<double>(-2.0, 1e-17),
      std::complex<double>(0.0, kNaN);
  frf.variance = Eigen::Vector3d(1e-3, 2e-3, 3e-3);
  frf.coherence = Eigen::Vector3d(0.99, 0.5, 0.0);
  frf.averages = 7;
  frf.block_length = 256;
  return frf;
}

StudySummary example_summary() {
  StudySummary s;
  s.kind = StudyKind::closed_loop;
  s.estimators = {StudyEstimator::srivc, StudyEstimator::additive_clsrivc};
  s.runs = 3;
  s.seed = std::numeric_limits<std::uint64_t>::max() - 5;
  s.sample_sizes = {500, 1000};
  s.parameter_names = {"a11", "b10"};
  s.true_parameters = Eigen::Vector2d(0.5, 1.0 / 3.0);
  MseRow row;
  row.estimator = StudyEstimator::additive_clsrivc;
  row.size_index = 1;
  row.samples = 1000;
  row.parameter = 1;
  row.true_value = 1.0 / 3.0;
  row.mean_squared_error = 1e-5;
  row.bias = -1e-4;
  row.predicted_mean_squared_error = kNaN;
  row.valid_runs = 3;
  row.converged_runs = 2;
  s.mse = {row};
  ParameterTrend trend;
  trend.estimator = StudyEstimator::srivc;
  trend.parameter = 0;
  trend.slope = -1.01;
  trend.mse_over_prediction = kNaN;
  trend.mse_over_reference = 1.0;
  trend.scaled_mse_at_largest = 0.7;
  s.trends = {trend};
  return s;
}

// Two candidates of a scan: one usable two-mode fit with its diagram, one that the estimator
// refused (NaN scores, the placeholder transfer function 1/1).
StructureScanResult example_structure_scan() {
  StructureScanResult scan;
  StructureFit good;
  good.structure = ModelStructure::modes(2);
  good.parameters = 6;
  good.termination = Termination::converged;
  good.message = "converged after 7 iterations";
  good.iterations = 7;
  good.usable = true;
  good.estimation_fit = 91.0 / 3.0;
  good.validation_fit = 89.5;
  good.validation_error = 1e-3 / 7.0;
  good.yic = -9.25;
  good.rt2 = 0.99;
  good.aic = -1234.5;
  good.bic = -1200.25;
  good.transfer_function = two_modes().to_transfer_function();
  StructureFit refused;
  refused.structure = ModelStructure::unfactored(12, 11, 1);
  refused.message = "too many parameters";
  refused.reasons = {"the fit failed"};
  refused.estimation_fit = refused.validation_fit = refused.validation_error = kNaN;
  refused.yic = refused.rt2 = refused.aic = refused.bic = kNaN;
  scan.fits = {good, refused};
  scan.recommended = 0;
  scan.rule = "fewest parameters among the usable fits";
  scan.estimation_samples = 700;
  scan.validation_samples = 300;
  StabilisationPoint point;
  point.fit = 0;
  point.order = 4;
  point.frequency = 6.25;
  point.damping_ratio = 1.0 / 30.0;
  point.stable_pole = true;
  point.stable_frequency = true;
  scan.stabilisation = {point};
  return scan;
}

// Written, read back through the dispatcher (as JSON text, as from a file), written again.
template <class T>
T round_trip(const T& result, const char* type) {
  const nlohmann::json written = to_json(ResultDocument(result));
  EXPECT_EQ(written.at("type"), type);
  EXPECT_EQ(written.at("version"), kResultDocumentVersion);
  const nlohmann::json parsed = parse_json(written.dump(2), "doc.json");
  const ResultDocument read = result_from_json(parsed, "doc.json");
  EXPECT_EQ(document_type(read), type);
  const T* back = std::get_if<T>(&read);
  EXPECT_NE(back, nullptr);
  EXPECT_EQ(to_json(read), written);
  return *back;
}

bool same_bits(double a, double b) {
  return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0;
}

TEST(Documents, EstimationResultRoundTripsBitForBit) {
  const EstimationResult r = example_estimate();
  const EstimationResult back = round_trip(r, kEstimationResultType);
  EXPECT_EQ(back.parameters, r.parameters);
  EXPECT_EQ(back.covariance, r.covariance);
  EXPECT_EQ(back.model.parameters(), r.model.parameters());
  EXPECT_EQ(back.model.input_delay(), r.model.input_delay());
  EXPECT_TRUE(back.additive_view.has_value());
  EXPECT_EQ(back.termination, Termination::iteration_limit);
  EXPECT_EQ(back.step_halvings, 5);
  EXPECT_EQ(back.input_delay_samples, 2);
  EXPECT_TRUE(same_bits(back.mean_squared_error, r.mean_squared_error));
  ASSERT_EQ(back.modes.size(), 1u);
  EXPECT_EQ(back.modes[0].submodel, 1);
  EXPECT_TRUE(same_bits(back.modes[0].value.natural_frequency, r.modes[0].value.natural_frequency));
  EXPECT_TRUE(std::isnan(back.modes[0].standard_error.damping_ratio));
  EXPECT_EQ(back.checks.warnings, r.checks.warnings);
  ASSERT_EQ(back.history.size(), 1u);
  EXPECT_EQ(back.history[0].parameters, r.history[0].parameters);
}

TEST(Documents, EstimationResultKeepsItsDocumentedKeys) {
  const nlohmann::json j = to_json(example_estimate());
  for (const char* key : {"type",
                          "version",
                          "model",
                          "transfer_function",
                          "additive_view",
                          "parameter_names",
                          "parameters",
                          "standard_errors",
                          "covariance",
                          "modes",
                          "termination",
                          "converged",
                          "message",
                          "iterations",
                          "relative_change",
                          "off_diagonal_norm",
                          "unstable_reflections",
                          "sensitivity_fallbacks",
                          "step_halvings",
                          "input_delay_samples",
                          "input_delay",
                          "noise_variance",
                          "mean_squared_error",
                          "fit_percent",
                          "data_checks",
                          "history"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_FALSE(j.contains("checks"));
  EXPECT_EQ(j.at("input_delay_samples"), 2);
  EXPECT_EQ(j.at("input_delay"), 0.1);
  EXPECT_TRUE(j.at("modes")[0].contains("natural_frequency_hz"));
  EXPECT_TRUE(j.at("modes")[0].at("damping_ratio_standard_error").is_null());
}

TEST(Documents, FitContextKeysAreAcceptedBesideTheResult) {
  nlohmann::json j = to_json(example_estimate());
  j["estimator"] = "additive_srivc";
  j["loop"] = "open";
  j["data"] = {{"file", "d.csv"}, {"samples", 10}, {"sample_time", 0.1}};
  j["delay_scan"] = delay_scan_summary_to_json(example_scan());
  j["mode_relocation"] = relocation_summary_to_json(example_relocation());
  const ResultDocument read = result_from_json(j, "fit.json");
  EXPECT_EQ(std::get<EstimationResult>(read).step_halvings, 5);
  // The relocation sub-document reads back with the enclosing estimate.
  const ModeRelocationResult relocation =
      mode_relocation_result_from_json(j.at("mode_relocation"), example_estimate(), "fit.json");
  EXPECT_EQ(relocation.trials.size(), 2u);
  EXPECT_EQ(relocation.relocations, 1);
}

TEST(Documents, ModeRelocationResultRoundTrips) {
  const ModeRelocationResult r = example_relocation();
  const ModeRelocationResult back = round_trip(r, kModeRelocationResultType);
  EXPECT_EQ(back.estimate.parameters, r.estimate.parameters);
  ASSERT_EQ(back.trials.size(), 2u);
  EXPECT_TRUE(back.trials[0].accepted);
  EXPECT_FALSE(back.trials[1].accepted);
  EXPECT_TRUE(std::isnan(back.trials[0].mean_squared_error));
  EXPECT_TRUE(same_bits(back.score, r.score));
  EXPECT_EQ(back.message, r.message);
  EXPECT_EQ(to_json(r).at("estimate").at("type"), kEstimationResultType);
}

TEST(Documents, InputDelayScanResultRoundTrips) {
  const InputDelayScanResult back = round_trip(example_scan(), kInputDelayScanResultType);
  EXPECT_EQ(back.delays, (std::vector<int>{0, 1, 2}));
  EXPECT_TRUE(std::isnan(back.mean_squared_errors[1]));
  EXPECT_EQ(back.terminations[1], Termination::not_run);
  EXPECT_EQ(back.best.iterations, 3);
}

TEST(Documents, ValidationReportRoundTripsWithItsRestatedKeys) {
  const ValidationReport r = example_report();
  const nlohmann::json j = to_json(r);
  EXPECT_EQ(j.at("bound_99"), j.at("whiteness_bound"));
  EXPECT_EQ(j.at("cross_correlation_lags"), (nlohmann::json{-2, -1, 0, 1, 2}));
  EXPECT_EQ(j.at("autocorrelation_lags"), (nlohmann::json{1, 2}));
  EXPECT_EQ(j.at("residual_white"), true);
  const ValidationReport back = round_trip(r, kValidationReportType);
  EXPECT_EQ(back.cross_correlation, r.cross_correlation);
  EXPECT_EQ(back.residual_autocorrelation, r.residual_autocorrelation);
  EXPECT_TRUE(same_bits(back.whiteness_bound, r.whiteness_bound));
}

TEST(Documents, FrfRoundTripsItsComplexResponse) {
  const Frf r = example_frf();
  const nlohmann::json j = to_json(r);
  EXPECT_EQ(j.at("response")[0], (nlohmann::json{1.0 / 3.0, -0.5}));
  const Frf back = round_trip(r, kFrfType);
  EXPECT_EQ(back.lines, r.lines);
  EXPECT_EQ(back.response(0), r.response(0));
  EXPECT_EQ(back.response(1), r.response(1));
  EXPECT_TRUE(std::isnan(back.response(2).imag()));
  EXPECT_EQ(back.coherence, r.coherence);
  EXPECT_EQ(back.block_length, 256);
}

// Two lines of a 2-output, 2-input FRF matrix with an unknown (NaN) entry.
MimoFrf example_mimo_frf() {
  MimoFrf frf;
  frf.lines = {3, 4};
  frf.frequencies = Eigen::Vector2d(0.75, 1.0);
  Eigen::MatrixXcd h(2, 2);
  h << std::complex<double>(1.0 / 3.0, -0.5), std::complex<double>(2.0, 0.125),
      std::complex<double>(-1e-300, kNaN), std::complex<double>(0.1, 0.2);
  frf.response = {h, 2.0 * h};
  Eigen::MatrixXd v(2, 2);
  v << 0.01, 0.02, 0.03, kNaN;
  frf.variance = {v, v};
  frf.coherence = Eigen::MatrixXd::Constant(2, 2, 0.875);
  frf.output_power = Eigen::MatrixXd::Constant(2, 2, 4.0);
  frf.input_level = Eigen::MatrixXd::Ones(2, 2);
  frf.input_condition = Eigen::Vector2d(1.5, 2.0);
  frf.averages = 7;
  frf.block_length = 64;
  frf.input_names = {"f1", "f2"};
  frf.output_names = {"a1", "a2"};
  return frf;
}

TEST(Documents, OmaResultRoundTripsWithUnknownStandardErrorsAsNull) {
  OmaResult r;
  r.termination = Termination::converged;
  r.sample_time = 0.01;
  r.channels = {"a", "b"};
  OmaMode mode;
  mode.frequency_hz = 1.0 / 3.0;
  mode.frequency_hz_std = std::numeric_limits<double>::quiet_NaN();
  mode.shape_real = {1.0, -0.25};
  mode.shape_imag = {0.0, 0.1};
  r.modes.push_back(mode);
  r.stabilisation.push_back({4, 1.0 / 3.0, 0.01, PoleStability::stable, 0.99});
  r.verdict.fail("no mode found", {"a longer record"});
  const nlohmann::json written = to_json(ResultDocument(r));
  EXPECT_TRUE(written.at("modes").at(0).at("frequency_hz_std").is_null());
  EXPECT_EQ(written.at("stabilisation").at(0).at("stability"), "stable");
  const OmaResult back = round_trip(r, kOmaResultType);
  EXPECT_TRUE(same_bits(back.modes.at(0).frequency_hz, mode.frequency_hz));
  EXPECT_TRUE(std::isnan(back.modes.at(0).frequency_hz_std));
  EXPECT_FALSE(back.verdict.usable);
}

TEST(Documents, MimoFrfRoundTripsBitForBit) {
  const MimoFrf r = example_mimo_frf();
  const MimoFrf back = round_trip(r, kMimoFrfType);
  EXPECT_EQ(back.lines, r.lines);
  EXPECT_EQ(back.frequencies, r.frequencies);
  ASSERT_EQ(back.response.size(), 2u);
  EXPECT_EQ(back.response[1](0, 1), r.response[1](0, 1));
  EXPECT_EQ(back.response[0](1, 0).real(), -1e-300);
  EXPECT_TRUE(std::isnan(back.response[0](1, 0).imag()));
  EXPECT_TRUE(std::isnan(back.variance[1](1, 1)));
  EXPECT_EQ(back.coherence, r.coherence);
  EXPECT_EQ(back.input_condition, r.input_condition);
  EXPECT_EQ(back.input_names, r.input_names);
  EXPECT_EQ(back.output_names, r.output_names);
  EXPECT_EQ(back.averages, 7);
  EXPECT_EQ(back.block_length, 64);
}

TEST(Documents, MimoFrfOfTheWrongShapeNamesTheEntry) {
  nlohmann::json j = to_json(example_mimo_frf());
  j["method"] = "welch";  // the context ctid frf writes is accepted
  EXPECT_NO_THROW(result_from_json(j, "m.json"));
  j["response"][1][0] = nlohmann::json::array({{1.0, 2.0}});
  EXPECT_THAT([&] { result_from_json(j, "m.json"); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("m.json: response[1][0]: expected an array of 2 entries")));
  j = to_json(example_mimo_frf());
  j.erase("coherence");
  EXPECT_THAT([&] { result_from_json(j, "m.json"); },
              ::testing::ThrowsMessage<InvalidArgument>(
                  HasSubstr("m.json: coherence: required field is missing")));
}

TEST(Documents, StudySummaryRoundTrips) {
  const StudySummary s = example_summary();
  const StudySummary back = round_trip(s, kStudySummaryType);
  EXPECT_EQ(back.kind, StudyKind::closed_loop);
  EXPECT_EQ(back.estimators, s.estimators);
  EXPECT_EQ(back.seed, s.seed);
  EXPECT_EQ(back.true_parameters, s.true_parameters);
  ASSERT_EQ(back.mse.size(), 1u);
  EXPECT_EQ(back.mse[0].estimator, StudyEstimator::additive_clsrivc);
  EXPECT_TRUE(std::isnan(back.mse[0].predicted_mean_squared_error));
  ASSERT_EQ(back.trends.size(), 1u);
  EXPECT_TRUE(same_bits(back.trends[0].slope, -1.01));
}

TEST(Documents, StructureScanResultRoundTripsWithItsEstimates) {
  const StructureScanResult s = example_structure_scan();
  nlohmann::json j = to_json(s);
  EXPECT_EQ(j.at("fits")[0].at("transfer_function").at("type"), "transfer_function");
  EXPECT_TRUE(j.at("fits")[1].at("validation_fit").is_null());
  const StructureScanResult back = round_trip(s, kStructureScanResultType);
  ASSERT_EQ(back.fits.size(), 2u);
  const StructureFit& good = back.fits[0];
  EXPECT_EQ(good.structure.kind, ModelKind::additive);
  EXPECT_EQ(good.structure.orders.size(), 2u);
  EXPECT_EQ(good.termination, Termination::converged);
  EXPECT_TRUE(good.usable);
  EXPECT_TRUE(same_bits(good.estimation_fit, s.fits[0].estimation_fit));
  EXPECT_TRUE(same_bits(good.validation_error, s.fits[0].validation_error));
  const TransferFunction& g = s.fits[0].transfer_function;
  EXPECT_EQ(good.transfer_function.numerator().coefficients(), g.numerator().coefficients());
  EXPECT_EQ(good.transfer_function.denominator().coefficients(), g.denominator().coefficients());
  EXPECT_EQ(good.transfer_function.input_delay(), g.input_delay());
  const StructureFit& refused = back.fits[1];
  EXPECT_FALSE(refused.usable);
  EXPECT_EQ(refused.structure.orders[0].integrators, 1);
  EXPECT_EQ(refused.reasons, s.fits[1].reasons);
  EXPECT_TRUE(std::isnan(refused.validation_fit));
  EXPECT_TRUE(std::isnan(refused.yic));
  EXPECT_EQ(back.recommended, 0);
  EXPECT_EQ(back.rule, s.rule);
  EXPECT_EQ(back.validation_samples, 300);
  ASSERT_EQ(back.stabilisation.size(), 1u);
  EXPECT_TRUE(same_bits(back.stabilisation[0].damping_ratio, 1.0 / 30.0));
  EXPECT_FALSE(back.stabilisation[0].stable_damping);

  // The context `ctid structure` writes beside it is set aside; other keys are refused.
  j["data"] = {{"file", "d.csv"}, {"samples", 1000}, {"sample_time", 0.01}};
  EXPECT_NO_THROW(result_from_json(j, "s.json"));
  j["fits"][0]["surprise"] = 1;
  EXPECT_THAT([&] { result_from_json(j, "s.json"); },
              ::testing::ThrowsMessage<InvalidArgument>(HasSubstr("unknown field 'surprise'")));
}

TEST(Documents, WrittenFilesReadBack) {
  const testing::TestDirectory dir;
  write_result(dir / "frf.json", example_frf());
  EXPECT_TRUE(std::holds_alternative<Frf>(read_result(dir / "frf.json")));
  EXPECT_THROW(write_result(dir / "frf.json", example_frf()), InvalidArgument);
  write_result(dir / "frf.json", example_report(), Overwrite::yes);
  EXPECT_TRUE(std::holds_alternative<ValidationReport>(read_result(dir / "frf.json")));
}

std::string error_of(const nlohmann::json& value) {
  try {
    result_from_json(value, "r.json");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(Documents, UnknownTypesVersionsAndFieldsAreRefused) {
  EXPECT_THAT(error_of(nlohmann::json::array()), HasSubstr("r.json: expected a JSON object"));
  EXPECT_THAT(error_of({{"fit_percent", 1.0}}), HasSubstr("r.json: \"type\" is missing"));
  EXPECT_THAT(error_of({{"type", "additive_model"}}),
              HasSubstr("\"additive_model\", which is not a result document"));
  nlohmann::json future = to_json(example_frf());
  future["version"] = 2;
  EXPECT_THAT(error_of(future), HasSubstr("r.json: frf version 2 is not one this ctid reads"));
  nlohmann::json extra = to_json(example_report());
  extra["fit_precent"] = 1.0;
  EXPECT_THAT(error_of(extra), HasSubstr("r.json: unknown field 'fit_precent'"));
  nlohmann::json bad = to_json(example_summary());
  bad["kind"] = "sideways";
  EXPECT_THAT(error_of(bad), HasSubstr("r.json: StudySummary.kind: 'sideways' is not one of"));
  nlohmann::json nested = to_json(example_estimate());
  nested["data_checks"]["excitation_order"] = "seven";
  EXPECT_THAT(error_of(nested),
              HasSubstr("r.json: EstimationResult.checks.excitation_order: expected an integer"));
}

TEST(Documents, ValidateReadsTheModelOfEveryEstimateDocument) {
  const EstimationResult r = example_estimate();
  for (const nlohmann::json& doc :
       {to_json(r), to_json(example_relocation()), to_json(example_scan())}) {
    const FittedModel fitted = fitted_model_from_json(doc, "r.json");
    EXPECT_EQ(fitted.model.parameters(), r.model.parameters());
    EXPECT_EQ(fitted.covariance, r.covariance);
  }
}

}  // namespace
}  // namespace ctid::io::documents_test
