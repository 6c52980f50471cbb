"""Every result document the ctid command line writes reads back with ctid.read_result as the
Python class of its result, with the values the command reported; result_to_json and
write_result give documents that read back equal."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import ctid

ROOT = pathlib.Path(__file__).resolve().parents[2]
MODELS = ROOT / "examples" / "models"


def _cli():
    candidates = []
    if os.environ.get("CTID_BUILD_DIR"):
        candidates.append(pathlib.Path(os.environ["CTID_BUILD_DIR"]) / "apps" / "ctid" / "ctid")
    candidates.append(pathlib.Path(ctid.__file__).resolve().parents[2] / "apps" / "ctid" / "ctid")
    for binary in candidates:
        if binary.exists():
            return binary
    return None


@pytest.fixture(scope="module")
def cli():
    binary = _cli()
    if binary is None:
        pytest.fail("the ctid command line was not found (set CTID_BUILD_DIR)")
    return binary


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
