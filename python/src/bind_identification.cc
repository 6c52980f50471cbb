// Python binding of the front door (identification/identification.h, mimo.h, mode_tracking.h):
// ctid.identify(data, structure, options=None, **keywords) runs what `ctid fit` runs, and
// ctid.identify(mimo_data, orders, ...) what `ctid fit --input-columns/--output-columns` runs and
// ctid.identify(mimo_frf, orders, ...) what `ctid fit-frf` runs.
// Every class here is derived from its C++ field list (fields.h); no field is named in this file.
#include "common.h"
#include "ctid/identification/frf_matrix.h"
#include "ctid/identification/identification.h"
#include "ctid/identification/irregular_validation.h"
#include "ctid/identification/mimo.h"
#include "ctid/identification/mimo_structure_scan.h"
#include "ctid/identification/mode_tracking.h"
#include "ctid/identification/structure_scan.h"
#include "fields.h"

namespace ctid::python {

namespace {

// --- Mode tracking (issue 17; identification/mode_tracking.h) ------------------------------------
void bind_mode_tracking(py::module_& m) {
  bind_options<TrackingOptions>(
      m, "Options of track_modes: window and step [s], identify() options, matching gates.");
  bind_enum<WindowStart>(m, "WindowStart", "Where a tracking window's fit started.");
  bind_result<TrackingWindow>(
      m, "One tracking window: where it lies, how its fit started and ended, its modes.")
      .def("converged", &TrackingWindow::converged, "termination == converged.")
      .def("brief_report", &TrackingWindow::brief_report,
           "One line: termination, iterations and, unless converged, why.");
  bind_result<ModeTrack>(m, "A mode followed across windows (per window; NaN where unmatched).");
  bind_result<TrackingResult>(m, "Every window of track_modes and the tracks of their modes.");
  m.def(
      "track_modes",
      [](const SampledData& data, const ModelStructure& structure,
         const std::optional<TrackingOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<TrackingOptions>("track_modes", options, kwargs);
        py::gil_scoped_release release;
        return track_modes(data, structure, o);
      },
      py::arg("data"), py::arg("structure"), py::arg("options") = py::none(),
      "Fit `structure` to consecutive windows of `data` (each started from the previous "
      "window's model) and match their modes into tracks, as `ctid track` does. Options are one "
      "TrackingOptions or its fields as keywords (window [s] is required).");
  m.def(
      "assign_modes",
      [](const std::vector<ModalParameters>& tracks, const std::vector<ModalParameters>& modes,
         const std::optional<TrackingOptions>& options, const py::kwargs& kwargs) {
        return assign_modes(tracks, modes,
                            options_from<TrackingOptions>("assign_modes", options, kwargs));
      },
      py::arg("tracks"), py::arg("modes"), py::arg("options") = py::none(),
      "The track of each mode (-1: none) under the matching of track_modes.");

  // Several outputs: shared-pole windows, matching by frequency, damping and MAC.
  bind_options<MimoTrackingOptions>(
      m,
      "Options of track_mimo_modes: window and step [s], mimo_srivc options, matching gates "
      "and the MAC term.");
  bind_result<MimoTrackingWindow>(
      m, "One window of track_mimo_modes: its fit, its modes (with shapes) and their MAC.")
      .def("converged", &MimoTrackingWindow::converged, "termination == converged.")
      .def("brief_report", &MimoTrackingWindow::brief_report,
           "One line: termination, iterations and, unless converged, why.");
  bind_result<MimoModeTrack>(
      m, "A mode followed across windows of several outputs, with the MAC of each window.");
  bind_result<MimoTrackingResult>(
      m, "Every window of track_mimo_modes and the tracks of their modes.");
  m.def(
      "track_mimo_modes",
      [](const MimoData& data, const std::vector<SubmodelOrder>& orders,
         const std::optional<MimoTrackingOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<MimoTrackingOptions>("track_mimo_modes", options, kwargs);
        py::gil_scoped_release release;
        return track_mimo_modes(data, orders, o);
      },
      py::arg("data"), py::arg("orders"), py::arg("options") = py::none(),
      "Fit the shared-pole submodels `orders` to consecutive windows of a record of several "
      "outputs (each started from the previous window's model, initial state estimated) and "
      "match their modes into tracks by frequency, damping and MAC, as `ctid track` with "
      "several --output-columns does. Options are one MimoTrackingOptions or its fields as "
      "keywords (window [s] is required).");
  bind_options<OmaTrackingOptions>(
      m, "Options of track_output_only_modes: window and step [s], OmaOptions, matching gates.");
  m.def(
      "track_output_only_modes",
      [](const Eigen::MatrixXd& outputs, double sample_time,
         const std::optional<std::vector<std::string>>& channel_names, double start_time,
         const std::optional<OmaTrackingOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<OmaTrackingOptions>("track_output_only_modes", options, kwargs);
        py::gil_scoped_release release;
        return track_output_only_modes(outputs, sample_time, start_time,
                                       channel_names.value_or(std::vector<std::string>{}), o);
      },
      py::arg("outputs"), py::arg("sample_time"), py::arg("channel_names") = py::none(),
      py::arg("start_time") = 0.0, py::arg("options") = py::none(),
      "Follow the modes of an (N, l) record with no input through time: consecutive windows "
      "each analysed by oma (OmaTrackingOptions.oma), their modes matched into tracks by "
      "frequency, damping and MAC, as `ctid track --output-only` does. Returns a "
      "MimoTrackingResult. Options are one OmaTrackingOptions or its fields as keywords "
      "(window [s] is required).");
  m.def(
      "assign_mimo_modes",
      [](const std::vector<MimoMode>& tracks, const std::vector<MimoMode>& modes,
         const std::optional<MimoTrackingOptions>& options, const py::kwargs& kwargs) {
        return assign_mimo_modes(
            tracks, modes, options_from<MimoTrackingOptions>("assign_mimo_modes", options, kwargs));
      },
      py::arg("tracks"), py::arg("modes"), py::arg("options") = py::none(),
      "The track of each mode (-1: none) under the matching of track_mimo_modes.");
}

}  // namespace

void bind_identification(py::module_& m) {
  bind_enum<ModelKind>(m, "ModelKind", "One transfer function or a sum of submodels.");
  bind_enum<RefinedIvEstimator>(m, "RefinedIvEstimator", "The refined IV estimator identify ran.");

  bind_options<ModelStructure>(
      m, "The model to estimate: its kind and the SubmodelOrder of each submodel.")
      .def_static("unfactored", &ModelStructure::unfactored, py::arg("poles"), py::arg("zeros"),
                  py::arg("integrators") = 0,
                  "One transfer function B/(p^integrators A), deg A = poles, deg B = zeros.")
      .def_static("additive", &ModelStructure::additive, py::arg("orders"),
                  "Submodels with these SubmodelOrders, in any order.")
      .def_static("modes", &ModelStructure::modes, py::arg("count"),
                  "count second-order modes b0 / (1 + a1 p + a2 p^2).")
      .def("is_additive", &ModelStructure::is_additive, "kind == ModelKind.additive.");
  bind_options<DelayRange>(m, "Whole-sample input delays min..max (inclusive) to scan.");
  bind_options<DelayInterval>(
      m,
      "Input delays min..max [s] within which the delay is estimated as a continuous parameter.");
  bind_enum<SensitivityModel>(m, "SensitivityModel",
                              "Stage 1 of the two-stage method: the model of r -> u.");
  bind_options<TwoStageOptions>(
      m, "The two-stage method for an unknown controller: the model of r -> u and its order.");
  bind_result<TwoStageResult>(m, "What stage 1 of the two-stage method chose and how well it fit.");
  bind_options<CoefficientSetting>(
      m, "A held value or bounds of one coefficient (theta1.a1, ..., tau).");
  bind_options<CoefficientConstraints>(
      m, "Held and bounded coefficients and a known DC gain (identify's constraints).");
  bind_options<OutputErrorPolishOptions>(
      m, "The output-error polish of identify (polish=True): delay, initial state, stability.");
  bind_result<OutputErrorPolishResult>(
      m, "The polished model beside the IV fit: criterion, parameters, covariance, fit, verdict.")
      .def("converged", &OutputErrorPolishResult::converged, "termination == converged.")
      .def("brief_report", &OutputErrorPolishResult::brief_report,
           "One line: termination, iterations and, unless converged, why.");
  bind_options<IdentificationOptions>(
      m, "Options of identify: controller (closed loop), delay scan, mode relocation, estimator.");
  bind_result<IdentificationResult>(
      m, "What identify ran (estimator, loop) and found (estimate, delay scan, relocation).");

  m.def(
      "identify",
      [](const SampledData& data, const ModelStructure& structure,
         const std::optional<IdentificationOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<IdentificationOptions>("identify", options, kwargs);
        py::gil_scoped_release release;
        return identify(data, structure, o);
      },
      py::arg("data"), py::arg("structure"), py::arg("options") = py::none(),
      "Estimate `structure` from `data` as `ctid fit` does: SRIVC / CLSRIVC (unfactored) or the "
      "additive iteration (29), closed loop when options.controller is set, over "
      "options.delay_scan_samples or with the delay estimated in options.delay_range, then mode "
      "relocation "
      "if options.relocate_modes. Options are one "
      "IdentificationOptions or its fields as keywords.");
  m.def(
      "identify",
      [](const std::vector<SampledData>& records, const ModelStructure& structure,
         const std::optional<IdentificationOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<IdentificationOptions>("identify", options, kwargs);
        py::gil_scoped_release release;
        return identify(records, structure, o);
      },
      py::arg("records"), py::arg("structure"), py::arg("options") = py::none(),
      "identify on several records of one system (a list of SampledData, e.g. separate "
      "experiments): one parameter vector fitted to all, each record with its own initial state "
      "(with refined_iv.initial_conditions = estimate); as `ctid fit a.csv b.csv`.");

  bind_options<MimoIdentificationOptions>(
      m, "Options of identify for several inputs and outputs: MimoRefinedIvOptions and a start.");
  m.def(
      "identify",
      [](const MimoData& data, const std::vector<SubmodelOrder>& orders,
         const std::optional<MimoIdentificationOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<MimoIdentificationOptions>("identify", options, kwargs);
        py::gil_scoped_release release;
        return identify(data, orders, o);
      },
      py::arg("data"), py::arg("orders"), py::arg("options") = py::none(),
      "identify on a record of several inputs and outputs (a MimoData): the submodels `orders` "
      "(a list of SubmodelOrder) with denominators shared by every channel, by the shared-pole "
      "refined IV estimator (mimo_srivc), open loop, as `ctid fit --input-columns ... "
      "--output-columns ...`. Options are one MimoIdentificationOptions or its fields "
      "(refined_iv, initial_model) as keywords.");

  bind_options<FrfIdentificationOptions>(
      m, "Options of identify for an FRF matrix: FrfMatrixFitOptions and a start.");
  m.def(
      "identify",
      [](const MimoFrf& frf, const std::vector<SubmodelOrder>& orders,
         const std::optional<FrfIdentificationOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<FrfIdentificationOptions>("identify", options, kwargs);
        py::gil_scoped_release release;
        return identify(frf, orders, o);
      },
      py::arg("frf"), py::arg("orders"), py::arg("options") = py::none(),
      "identify on a measured FRF matrix (a MimoFrf): the submodels `orders` with poles shared "
      "by every channel, by frf_matrix_fit, as `ctid fit-frf`. Options are one "
      "FrfIdentificationOptions or its fields (frf_fit, initial_model) as keywords.");

  bind_options<StructureScanOptions>(
      m, "Options of scan_structures: held-out share, parsimony tolerance, diagram tolerances.");
  bind_result<StructureFit>(m, "One candidate structure of a scan: how it ended and scores.");
  bind_result<StabilisationPoint>(m, "One pole pair of the stabilisation diagram.");
  bind_result<StructureScanResult>(
      m, "Every candidate's fit, the recommended one and the stabilisation diagram.");
  m.def(
      "scan_structures",
      [](const SampledData& data, const std::vector<ModelStructure>& candidates,
         const std::optional<StructureScanOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<StructureScanOptions>("scan_structures", options, kwargs);
        py::gil_scoped_release release;
        return scan_structures(data, candidates, o);
      },
      py::arg("data"), py::arg("candidates"), py::arg("options") = py::none(),
      "Fit every candidate structure on the first part of the record, score it on the held-out "
      "end (fit, YIC, RT2, AIC, BIC) and recommend one, as `ctid structure` does.");
  bind_options<MimoStructureScanOptions>(
      m,
      "Options of scan_mimo_modes: held-out share, parsimony tolerance, diagram tolerances, "
      "the shared-pole fit's options.");
  bind_result<MimoStructureFit>(m, "One mode count of a scan of several channels.");
  bind_result<MimoStructureScanResult>(
      m, "Every mode count's fit, the recommended one and the stabilisation diagram.");
  m.def(
      "scan_mimo_modes",
      [](const MimoData& data, const std::vector<int>& mode_counts,
         const std::optional<MimoStructureScanOptions>& options, const py::kwargs& kwargs) {
        const auto o = options_from<MimoStructureScanOptions>("scan_mimo_modes", options, kwargs);
        py::gil_scoped_release release;
        return scan_mimo_modes(data, mode_counts, o);
      },
      py::arg("data"), py::arg("mode_counts"), py::arg("options") = py::none(),
      "Fit each number of modes shared by every channel on the first part of a record of "
      "several inputs and outputs, score it on the held-out end and recommend one, with the "
      "stabilisation diagram, as `ctid structure --input-columns ... --output-columns ...`.");
  bind_mode_tracking(m);  // mode tracking (issue 17)
  m.def(
      "validate_on_stamps",
      [](const AdditiveModel& model, const Eigen::VectorXd& time, const Eigen::VectorXd& input,
         const Eigen::VectorXd& output, Hold input_hold, const ValidationOptions& options) {
        const IrregularRecord record{time, input, output, input_hold};
        return validate_model(model, record, options);
      },
      py::arg("model"), py::arg("time"), py::arg("input"), py::arg("output"),
      py::arg("input_hold") = Hold::zero_order_hold, py::arg("options") = ValidationOptions{},
      "validate_model on irregular time stamps as logged (non-decreasing, equal stamps "
      "allowed): the model simulated from rest at the stamps with input_hold and scored on "
      "options' window; correlation lags count samples (docs/decisions/0053).");
}

}  // namespace ctid::python
