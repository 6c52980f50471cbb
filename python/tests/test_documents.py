"""Every result document the ctid command line writes reads back with ctid.read_result as the
Python class of its result, with the values the command reported; result_to_json and
write_result give documents that read back equal."""

import json
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import ctid

ROOT = pathlib.Path(__file__).resolve().parents[2]
MODELS = ROOT / "examples" / "models"


@pytest.fixture(scope="module")
def run(cli, tmp_path_factory):
    folder = tmp_path_factory.mktemp("documents")

    def run_ctid(*args):
        done = subprocess.run([str(cli), *map(str, args)], cwd=folder, capture_output=True,
                              text=True)
        assert done.returncode == 0, done.stderr
        return folder

    return run_ctid


@pytest.fixture(scope="module")
def data(run):
    folder = run("simulate", "-m", MODELS / "gonzalez_6_1_open_loop.json", "--excitation-spec",
                 MODELS / "multisine_0.01_3hz.json", "--noise-std", "0.01", "--noise-seed", "3",
                 "-o", "d.csv", "-q")
    return folder / "d.csv"


def test_fit_result_reads_back_as_an_estimation_result(run, data):
    folder = run("fit", data, "--modes", "4", "-o", "fit.json", "-q")
    result = ctid.read_result(folder / "fit.json")
    assert isinstance(result, ctid.EstimationResult)
    written = json.loads((folder / "fit.json").read_text())
    assert written["type"] == "estimation_result" and written["version"] == 1
    assert result.termination.name == written["termination"]
    assert result.iterations == written["iterations"]
    assert result.step_halvings == written["step_halvings"]
    assert result.fit_percent == written["fit_percent"]
    np.testing.assert_array_equal(result.parameters, written["parameters"])
    np.testing.assert_array_equal(result.model.parameters(), written["parameters"])
    assert result.converged() == written["converged"]
    assert "step_halvings" in ctid.EstimationResult.fields
    # result_to_json writes the same result again (the fit's context keys aside).
    again = json.loads(ctid.result_to_json(result))
    for key, value in again.items():
        assert written[key] == value, key
    # Models have no ==: the documents of both compare every value exactly.
    assert ctid.result_to_json(ctid.read_result(folder / "fit.json")) == ctid.result_to_json(result)


def test_validation_report_reads_back(run, data):
    folder = run("fit", data, "--modes", "4", "-o", "fit2.json", "-q")
    folder = run("validate", "fit2.json", data, "-o", "report.json", "-q")
    report = ctid.read_result(folder / "report.json")
    assert isinstance(report, ctid.ValidationReport)
    written = json.loads((folder / "report.json").read_text())
    assert written["type"] == "validation_report"
    assert report.fit_percent == written["fit_percent"]
    assert report.max_lag == 20
    np.testing.assert_array_equal(report.cross_correlation, written["cross_correlation"])
    assert len(report.residual_autocorrelation) == 20
    assert report.residual_white == written["residual_white"]
    assert report.whiteness_bound == written["bound_99"]


def test_frf_document_reads_back_and_matches_the_csv(run, data):
    folder = run("frf", data, "-o", "frf.json", "-q")
    run("frf", data, "-o", "frf.csv", "-q")
    frf = ctid.read_result(folder / "frf.json")
    assert isinstance(frf, ctid.Frf)
    assert "Frf(" in repr(frf)
    table = np.genfromtxt(folder / "frf.csv", delimiter=",", names=True)
    np.testing.assert_allclose(frf.frequencies, table["frequency"], rtol=1e-15)
    np.testing.assert_allclose(frf.response.real, table["real"], rtol=1e-15)
    np.testing.assert_allclose(frf.response.imag, table["imag"], rtol=1e-15)
    assert len(frf.coherence) == len(frf.frequencies)
    written = json.loads((folder / "frf.json").read_text())
    assert written["type"] == "frf" and written["method"] == "welch"


def test_study_summary_reads_back(run):
    folder = run("study", "closed-loop", "-o", "s", "--runs", "2", "--sizes", "2",
                 "--max-samples", "700", "--estimators", "srivc", "clsrivc", "--no-plot", "-q")
    summary = ctid.read_result(folder / "s" / "summary.json")
    assert isinstance(summary, ctid.StudySummary)
    assert summary.kind == ctid.StudyKind.closed_loop
    assert summary.runs == 2
    assert list(summary.estimators) == [ctid.StudyEstimator.srivc, ctid.StudyEstimator.clsrivc]
    table = np.genfromtxt(folder / "s" / "mse.csv", delimiter=",", names=True, dtype=None,
                          encoding="utf-8")
    assert len(summary.mse) == len(table)
    np.testing.assert_allclose([row.mean_squared_error for row in summary.mse], table["mse"],
                               rtol=1e-15)
    assert len(summary.trends) == 2 * len(summary.parameter_names)


def test_feedback_result_reads_back_as_a_delayed_feedback_result(run):
    folder = run("simulate", "-m", MODELS / "de_iuliis_section4_loop.json", "-e", "multisine",
                 "-n", "600", "-T", "0.05", "--periods", "2", "--max-frequency-hz", "0.6",
                 "-o", "loop.csv", "-q")
    run("feedback", "loop.csv", "--forward-order", "3", "--feedback-order", "3", "--delay",
        "0.5", "--hold", "foh", "-o", "fb.json", "-q")
    result = ctid.read_result(folder / "fb.json")
    assert isinstance(result, ctid.DelayedFeedbackResult)
    assert result.delay_scan is None
    identification = result.identification
    assert identification.termination == ctid.Termination.converged
    document = json.loads((folder / "fb.json").read_text())
    loop = document["identification"]["loop"]
    assert list(identification.loop.forward.numerator.coefficients) == (
        loop["forward"]["numerator_ascending"])
    assert identification.loop.delay == 0.5
    # The true loop: F = (2 s^2 + s + 2) / (s^3 + 3 s^2 + 2 s + 3), to the last digits.
    np.testing.assert_allclose(identification.loop.forward.denominator.coefficients,
                               [3.0, 2.0, 3.0, 1.0], rtol=1e-9)
    assert json.loads(ctid.result_to_json(result)) == document


def test_written_results_read_back_equal(tmp_path, fitted):
    path = tmp_path / "r.json"
    ctid.write_result(str(path), fitted)
    back = ctid.read_result(str(path))
    assert ctid.result_to_json(back) == ctid.result_to_json(fitted)
    np.testing.assert_array_equal(back.covariance, fitted.covariance)
    assert back.checks == fitted.checks
    with pytest.raises(ctid.InvalidArgument, match="exists"):
        ctid.write_result(str(path), fitted)


def test_unknown_documents_are_refused(tmp_path):
    path = tmp_path / "x.json"
    path.write_text(json.dumps({"type": "frf", "version": 9}))
    with pytest.raises(ctid.InvalidArgument, match="version 9"):
        ctid.read_result(str(path))
    path.write_text(json.dumps({"type": "transfer_function"}))
    with pytest.raises(ctid.InvalidArgument, match="not a result document"):
        ctid.read_result(str(path))
    assert "estimation_result" in ctid.result_document_types()


def test_results_have_field_reprs():
    for cls in (ctid.EstimationResult, ctid.Frf, ctid.ValidationReport, ctid.StudySummary,
                ctid.ModeRelocationResult, ctid.InputDelayScanResult, ctid.ResonancePeak):
        assert cls.fields, cls
        assert "__repr__" in cls.__dict__, cls


def test_every_public_class_has_a_repr(experiment):
    import inspect
    for name, cls in vars(ctid).items():
        if (inspect.isclass(cls) and not issubclass(cls, BaseException)
                and cls.__module__.startswith("ctid")):
            assert cls.__repr__ is not object.__repr__, name
    assert repr(experiment["data"]).startswith("SampledData(")


# --- every document the command line writes, read back and drawn (issue 15) ------------------

@pytest.fixture(scope="module")
def mimo_csv(run):
    from test_mimo_fit import two_modes

    model, n, h = two_modes(), 4096, 0.05
    u = np.column_stack([ctid.white_noise(n, 1.0, 5 + k) for k in range(model.inputs)])
    y = np.zeros((n, model.outputs))
    for j in range(model.outputs):
        for k in range(model.inputs):
            y[:, j] += ctid.simulate(model.channel(j, k), u[:, k], h)
    y += 0.01 * np.random.default_rng(4).standard_normal(y.shape)
    folder = run("--version")
    data = ctid.MimoData(h, u, y).with_names(["f1", "f2"], ["a1", "a2", "a3"])
    ctid.write_mimo_data(str(folder / "m.csv"), data, overwrite=True)
    return folder / "m.csv"


@pytest.fixture(scope="module")
def documents(run, data, mimo_csv):
    """Every result document the command line writes, by its "type": (path, class)."""
    mimo = ["--input-columns", "f1,f2", "--output-columns", "a1:a3"]
    run("fit", data, "--modes", "4", "-o", "all_fit.json", "-q")
    run("validate", "all_fit.json", data, "-o", "all_report.json", "-q")
    run("frf", data, "-o", "all_frf.json", "-q")
    run("structure", data, "--modes", "3:4", "-o", "all_scan.json", "-q")
    run("study", "closed-loop", "-o", "all_study", "--runs", "2", "--sizes", "2",
        "--max-samples", "700", "--estimators", "srivc", "--no-plot", "-q")
    run("simulate", "-m", MODELS / "de_iuliis_section4_loop.json", "-e", "multisine", "-n",
        "600", "-T", "0.05", "--periods", "2", "--max-frequency-hz", "0.6", "-o",
        "all_loop.csv", "-q")
    run("feedback", "all_loop.csv", "--forward-order", "3", "--feedback-order", "3", "--delay",
        "0.5", "--hold", "foh", "-o", "all_feedback.json", "-q")
    run("frf", mimo_csv, *mimo, "--segment-length", "512", "-o", "all_mimo_frf.json", "-q")
    run("frf", mimo_csv, *mimo, "--segment-length", "512", "-o", "all_mimo_frf.csv", "-q")
    run("fit", mimo_csv, *mimo, "--modes", "2", "-o", "all_mimo_fit.json", "-q")
    folder = run("fit-frf", "all_mimo_frf.csv", "--modes", "2", "-o", "all_fit_frf.json", "-q")
    run("oma", mimo_csv, "--output-columns", "a1:a3", "--max-order", "8", "-o", "all_oma.json",
        "-q")
    run("structure", mimo_csv, *mimo, "--modes", "1:2", "-o", "all_mimo_scan.json", "-q")
    return {
        "estimation_result": (folder / "all_fit.json", ctid.EstimationResult),
        "validation_report": (folder / "all_report.json", ctid.ValidationReport),
        "frf": (folder / "all_frf.json", ctid.Frf),
        "structure_scan_result": (folder / "all_scan.json", ctid.StructureScanResult),
        "study_summary": (folder / "all_study" / "summary.json", ctid.StudySummary),
        "delayed_feedback_result": (folder / "all_feedback.json", ctid.DelayedFeedbackResult),
        "mimo_frf": (folder / "all_mimo_frf.json", ctid.MimoFrf),
        "mimo_estimation_result": (folder / "all_mimo_fit.json", ctid.MimoEstimationResult),
        "frf_matrix_fit_result": (folder / "all_fit_frf.json", ctid.FrfMatrixFitResult),
        "oma_result": (folder / "all_oma.json", ctid.OmaResult),
        "mimo_structure_scan_result": (folder / "all_mimo_scan.json",
                                       ctid.MimoStructureScanResult),
    }


def test_every_document_the_command_line_writes_reads_back_as_its_class(documents):
    for kind, (path, cls) in documents.items():
        written = json.loads(path.read_text())
        assert written["type"] == kind
        result = ctid.read_result(path)
        assert type(result) is cls, (kind, type(result))
        assert kind in ctid.result_document_types()
        # Its repr names the class and shows values, not an address.
        assert repr(result).startswith(cls.__name__) and " at 0x" not in repr(result)
    # The mimo_frf document holds what the CSV table of the same estimate holds.
    folder = documents["mimo_frf"][0].parent
    document = ctid.read_result(documents["mimo_frf"][0])
    table = ctid.read_mimo_frf(folder / "all_mimo_frf.csv")
    np.testing.assert_array_equal(document.frequencies, table.frequencies)
    np.testing.assert_allclose(document.response, table.response, rtol=1e-15)
    assert list(document.output_names) == ["a1", "a2", "a3"]
    assert document.coherence.shape == (len(document.frequencies), 3)
    again = json.loads(ctid.result_to_json(document))
    written = json.loads(documents["mimo_frf"][0].read_text())
    for key, value in again.items():
        assert written[key] == value, key


def test_python_m_ctid_plot_draws_every_document(documents, tmp_path):
    from ctid import plot

    drawn = 0
    for kind, (path, _) in documents.items():
        for figure_kind in plot.DOCUMENT_KINDS[kind]:
            extra = []
            if figure_kind == "frf_matrix_overlay":
                extra = ["--frf", str(documents["mimo_frf"][0])]
            output = tmp_path / f"{kind}_{figure_kind}.png"
            done = subprocess.run([sys.executable, "-m", "ctid.plot", figure_kind, str(path),
                                   str(output), *extra], capture_output=True, text=True)
            assert done.returncode == 0, (kind, figure_kind, done.stderr)
            assert output.stat().st_size > 5000
            drawn += 1
    assert drawn >= 14
    # bode of a fit over the FRF document of the same data: the model and the measured lines.
    figure = plot.run("bode", str(documents["estimation_result"][0]), str(tmp_path / "b.png"),
                      frf=str(documents["frf"][0]))
    labels = [l.get_label() for l in figure.axes[0].get_lines()]
    assert "model" in labels and "FRF" in labels
    assert figure.axes[1].get_xlabel() == "frequency [Hz]"
    figure = plot.run("bode", str(documents["estimation_result"][0]), str(tmp_path / "r.png"),
                      frequency_unit="rad/s")
    assert figure.axes[1].get_xlabel() == "frequency [rad/s]"
    # A document drawn by the wrong kind is refused with the kinds that draw it.
    done = subprocess.run([sys.executable, "-m", "ctid.plot", "mse",
                           str(documents["frf"][0]), str(tmp_path / "x.png")],
                          capture_output=True, text=True)
    assert done.returncode == 2
    assert "a frf document is drawn by frf, not mse" in done.stderr


def test_read_csv_reads_a_record_as_the_command_line_does(tmp_path, data):
    record = ctid.read_csv(data)
    table = np.genfromtxt(data, delimiter=",", names=True)
    np.testing.assert_array_equal(record.input, table["u"])
    np.testing.assert_array_equal(record.output, table["y"])
    assert record.sample_time == pytest.approx(0.05, rel=1e-12)
    assert record.input_hold == ctid.Hold.zero_order_hold
    # Written and read back bit for bit, first-order hold declared in the file.
    foh = record.with_input_hold(ctid.Hold.first_order_hold)
    ctid.write_csv(tmp_path / "foh.csv", foh)
    assert (tmp_path / "foh.csv").read_text().startswith("# input_hold: foh")
    back = ctid.read_csv(tmp_path / "foh.csv")
    np.testing.assert_array_equal(back.output, record.output)
    assert back.sample_time == record.sample_time
    assert back.input_hold == ctid.Hold.first_order_hold
    with pytest.raises(ctid.InvalidArgument, match="input_hold zoh contradicts .*foh.csv:1"):
        ctid.read_csv(tmp_path / "foh.csv", input_hold="zoh")
    # Other column names; the time stamps give h and the start time.
    (tmp_path / "named.csv").write_text("# a comment\ntime,force,acc,ref\n"
                                        "10,1,0,5\n10.5,2,1,5\n11,3,4,5\n")
    named = ctid.read_csv(tmp_path / "named.csv", time="time", input="force", output="acc",
                          reference="ref")
    assert (named.sample_time, named.start_time) == (0.5, 10.0)
    np.testing.assert_array_equal(named.reference, [5.0, 5.0, 5.0])
    # sample_time overrides the stamps; without a time column it is needed.
    assert ctid.read_csv(tmp_path / "named.csv", time="time", input="force", output="acc",
                         sample_time=0.25).sample_time == 0.25
    (tmp_path / "plain.csv").write_text("u,y\n1,0\n2,1\n3,4\n")
    with pytest.raises(ctid.InvalidArgument, match="no time column 't'; give sample_time="):
        ctid.read_csv(tmp_path / "plain.csv")
    assert ctid.read_csv(tmp_path / "plain.csv", sample_time=0.1).size() == 3
    # Irregular stamps are refused with the CLI's rule, or moved onto a grid with resample.
    (tmp_path / "irregular.csv").write_text("t,u,y\n0,1,0\n0.1,2,1\n0.25,3,4\n0.3,4,5\n")
    with pytest.raises(ctid.InvalidArgument, match="not uniform.*resample=H"):
        ctid.read_csv(tmp_path / "irregular.csv")
    resampled = ctid.read_csv(tmp_path / "irregular.csv", resample=0.1)
    assert resampled.size() == 4 and resampled.sample_time == 0.1
    with pytest.raises(ctid.InvalidArgument, match="no column 'x' \\(columns: t, u, y\\)"):
        ctid.read_csv(tmp_path / "irregular.csv", output="x")
    with pytest.raises(TypeError):
        ctid.read_csv(tmp_path / "plain.csv", "u")  # columns are keywords


def _reachable_instances(roots):
    """One instance of every ctid class reachable from ``roots`` through attributes and lists,
    by class name."""
    import inspect

    exported = {name: cls for name, cls in vars(ctid).items()
                if inspect.isclass(cls) and cls.__module__.startswith("ctid")}
    found = {}

    def walk(value, depth):
        if depth > 8:
            return
        if isinstance(value, (list, tuple)):
            for item in value[:3]:
                walk(item, depth + 1)
            return
        name = type(value).__name__
        if exported.get(name) is not type(value) or name in found:
            return
        found[name] = value
        for attribute in dir(value):
            if attribute.startswith("_"):
                continue
            try:
                item = getattr(value, attribute)
            except Exception:  # noqa: BLE001 - an attribute not readable in this state
                continue
            if not callable(item):
                walk(item, depth + 1)

    for root in roots:
        walk(root, 0)
    return found


def test_every_class_reached_from_the_results_prints_its_values(documents, experiment, fitted):
    data = experiment["data"]
    roots = [ctid.read_result(path) for path, _ in documents.values()]
    mimo = ctid.read_mimo_data(str(documents["mimo_frf"][0].parent / "m.csv"),
                               inputs=["f1", "f2"], outputs=["a1:a3"], time="t")
    mimo_fit = roots[list(documents).index("mimo_estimation_result")]
    loop = roots[list(documents).index("delayed_feedback_result")].identification.loop
    space = experiment["g"].to_state_space()
    roots += [
        data, fitted, mimo, mimo_fit.model, ctid.validate_model(mimo_fit.model, mimo),
        ctid.preprocess(data, detrend=ctid.Detrend.mean), ctid.check_time_stamps(data.time),
        ctid.discretize_zoh(space.a, space.b, 0.05), ctid.discretize_foh(space.a, space.b, 0.05),
        ctid.to_delayed_state_space(loop), space,
        ctid.DiscreteTransferFunction([0.5], [-0.9, 1.0], 0.05),
        ctid.identify(data, ctid.ModelStructure.modes(1)),
        ctid.study_setup(ctid.StudyKind.open_loop),
    ]
    welch = ctid.welch_frf(data, segment_length=256)
    roots += [
        experiment["g"], experiment["u"], welch, ctid.resonance_peaks(welch),
        ctid.fit_autoregressive(experiment["noise"], 4),
        ctid.orthogonal_multisines(2, period_length=64, sample_time=0.05, periods=2),
        ctid.periodogram_peaks(data.output, 0.05),
        ctid.srivc_delay_scan(data, ctid.SubmodelOrder(2, 0), 0, 2),
        ctid.preprocess(mimo, detrend=ctid.Detrend.mean),
    ]
    # Every class that constructs without arguments (the options classes and more).
    for cls in vars(ctid).values():
        if isinstance(cls, type) and cls.__module__.startswith("ctid"):
            try:
                roots.append(cls())
            except Exception:  # noqa: BLE001 - needs arguments
                pass
    found = _reachable_instances(roots)
    for name, value in found.items():
        text = repr(value)
        assert " at 0x" not in text, f"{name} prints as an address: {text[:120]}"
    # Among them every result class of the documents and what they hold.
    for name in ("Frf", "MimoFrf", "EstimationResult", "ValidationReport", "StudySummary",
                 "MseRow", "ParameterTrend", "StructureScanResult", "DelayedFeedbackResult",
                 "FeedbackIdentificationResult", "DelayedFeedbackLoop", "MimoEstimationResult",
                 "MimoMode", "MimoAdditiveModel", "MimoSubmodel", "FrfMatrixFitResult",
                 "MimoValidationReport", "SampledData", "MimoData", "Verdict", "DataChecks",
                 "PreprocessedData", "TimeStampCheck", "StudySetup", "StateSpace",
                 "ZohDiscretization", "FohDiscretization", "DelayedStateSpace",
                 "TransferFunction", "Multisine", "ResonancePeak", "AutoregressiveModel",
                 "OrthogonalMultisines", "InputDelayScanResult", "PreprocessedMimoData",
                 "RefinedIvOptions", "IdentificationOptions", "FeedbackIdentificationOptions",
                 "StudyOptions", "WelchOptions", "ValidationOptions", "MimoCsvColumns"):
        assert name in found, f"{name} not reached"
    assert repr(found["Frf"]).startswith("Frf(lines=[1, 2, 3")


def test_model_documents_read_back_as_their_classes(tmp_path, run, data):
    # ctid fit --model-output writes the model document; read_model reads it as its class.
    folder = run("fit", data, "--modes", "4", "--model-output", "model.json", "-q")
    model = ctid.read_model(folder / "model.json")
    assert isinstance(model, ctid.AdditiveModel) and len(model) == 4
    assert json.loads(ctid.model_to_json(model)) == json.loads((folder / "model.json").read_text())
    expected = {"gonzalez_6_1_open_loop.json": ctid.AdditiveModel,
                "gonzalez_6_2_plant.json": ctid.AdditiveModel,
                "gonzalez_6_2_pid.json": ctid.DiscreteTransferFunction,
                "de_iuliis_section4_loop.json": ctid.DelayedFeedbackLoop}
    for name, cls in expected.items():
        read = ctid.read_model(MODELS / name)
        assert type(read) is cls, name
        # Written and read back, the same document (bit for bit).
        ctid.write_model(tmp_path / name, read)
        assert ctid.model_to_json(ctid.read_model(tmp_path / name)) == ctid.model_to_json(read)
    g = ctid.TransferFunction([1600.0, -6400.0], [1600.0, 416.0, 408.0, 5.0, 1.0], 0.1)
    ctid.write_model(tmp_path / "tf.json", g)
    assert type(ctid.read_model(tmp_path / "tf.json")) is ctid.TransferFunction
    assert ctid.model_to_json(ctid.read_model(tmp_path / "tf.json")) == ctid.model_to_json(g)
    with pytest.raises(ctid.InvalidArgument, match="exists"):
        ctid.write_model(tmp_path / "tf.json", g)
    from test_mimo_fit import two_modes
    mimo = two_modes()
    back = ctid.model_from_json(json.loads(ctid.model_to_json(mimo)))
    assert isinstance(back, ctid.MimoAdditiveModel)
    assert ctid.model_to_json(back) == ctid.model_to_json(mimo)
    with pytest.raises(ctid.InvalidArgument, match='x.json: "type" is "state_space"; a model '
                                                   "document is one of transfer_function"):
        ctid.model_from_json({"type": "state_space"}, "x.json")
    with pytest.raises(ctid.InvalidArgument, match="m.json: .*numerator_ascending"):
        ctid.model_from_json({"type": "transfer_function", "denominator_ascending": [1.0]},
                             "m.json")
