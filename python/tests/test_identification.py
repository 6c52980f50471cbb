"""ctid.identify, the front door of the refined IV module: in one call it runs what `ctid fit`
runs. The CLI (the C++ identify() behind flags) is run on a CSV of the same samples and its
result file must hold the very numbers Python returns; identify() must also equal the direct
estimator bit for bit, and bad options raise ctid.InvalidArgument naming the field."""

import json
import pathlib
import subprocess

import numpy as np
import pytest

import ctid

H = 0.05
N = 1500
MODES = [ctid.SubmodelOrder(2, 0)] * 2
# Section 6.2, eq. (46): 3/(0.25p^2 + 0.25p + 1) + 1/(0.025p^2 + 0.01p + 1).
TRUTH = ctid.AdditiveModel.from_parameters(MODES, [0.25, 0.25, 3.0, 0.01, 0.025, 1.0])
# The shipped PID of Section 6.2 (examples/models/gonzalez_6_2_pid.json).
PID = ctid.DiscreteTransferFunction(ctid.Polynomial([0.00454, -0.02058, 0.02329]),
                                    ctid.Polynomial([0.0, -1.0, 1.0]), H)
PID_FILE = pathlib.Path(__file__).resolve().parents[2] / "examples/models/gonzalez_6_2_pid.json"


def write_csv(path, columns):
    """Every sample in its shortest round-trip form, so the CLI reads the same doubles."""
    names = list(columns)
    with open(path, "w") as out:
        out.write(",".join(names) + "\n")
        for row in zip(*(columns[name] for name in names)):
            out.write(",".join(repr(float(x)) for x in row) + "\n")


@pytest.fixture(scope="module")
def open_loop(tmp_path_factory):
    """Two modes, a 2-sample input delay, white output noise; no time column (the CLI gets -T)."""
    u = ctid.white_noise(N, 1.0, 41)
    delayed = np.concatenate([np.zeros(2), u[:-2]])
    y = ctid.simulate(TRUTH, delayed, H) + ctid.white_noise(N, 0.05, 43)
    path = tmp_path_factory.mktemp("identify") / "open.csv"
    write_csv(path, {"u": u, "y": y})
    return ctid.SampledData(H, u, y), path


@pytest.fixture(scope="module")
def closed_loop(tmp_path_factory):
    r = ctid.white_noise(N, 1.0, 42)
    loop = ctid.simulate_closed_loop(TRUTH, PID, r, ctid.white_noise(N, 0.05, 44))
    path = tmp_path_factory.mktemp("identify") / "closed.csv"
    write_csv(path, {"u": loop.input, "y": loop.output, "r": r})
    return ctid.SampledData(H, loop.input, loop.output, r), path


def fit(cli, csv, *flags):
    result = csv.with_name(csv.stem + "_result.json")
    run = subprocess.run([str(cli), "fit", str(csv), "-T", str(H), "-o", str(result), "--force",
                          "-q", *flags], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return json.loads(result.read_text())


def bits(values):
    """A float64 array's bytes; JSON null (a non-finite number) becomes NaN."""
    array = np.array([np.nan if v is None else v for v in np.ravel(values)], dtype=np.float64)
    return array.tobytes()


def expect_same_as_cli(result, document):
    e = result.estimate
    assert document["estimator"] == result.estimator.name
    assert document["loop"] == ("closed" if result.closed_loop else "open")
    assert bits(document["parameters"]) == bits(e.parameters)
    assert bits(document["covariance"]) == bits(np.asarray(e.covariance))  # row by row
    assert bits(document["standard_errors"]) == bits(e.standard_errors)
    for key in ("mean_squared_error", "noise_variance", "fit_percent", "off_diagonal_norm",
                "relative_change"):
        assert bits([document[key]]) == bits([getattr(e, key)]), key
    assert document["termination"] == e.termination.name
    assert document["message"] == e.message
    assert document["iterations"] == e.iterations
    assert document["input_delay_samples"] == e.input_delay_samples


def test_delay_scan_equals_ctid_fit(cli, open_loop):
    data, csv = open_loop
    result = ctid.identify(data, ctid.ModelStructure.modes(2),
                           delay_scan_samples=ctid.DelayRange(min=0, max=3))
    document = fit(cli, csv, "--modes", "2", "--delay-scan-samples", "0:3")
    expect_same_as_cli(result, document)
    assert result.estimate.input_delay_samples == 2
    scan = result.delay_scan
    assert document["delay_scan"]["delays"] == list(scan.delays)
    assert bits(document["delay_scan"]["mean_squared_errors"]) == bits(scan.mean_squared_errors)
    assert document["delay_scan"]["terminations"] == [t.name for t in scan.terminations]
    assert result.mode_relocation is None


def test_delay_range_estimates_a_fractional_delay_as_ctid_fit_does(cli, tmp_path):
    # One mode delayed by 2.6 samples, noise-free: the delay comes back to 1e-9 with a
    # standard error, and the CLI's --delay-range gives the very same numbers.
    u = ctid.white_noise(N, 1.0, 45)
    mode = ctid.AdditiveModel.from_parameters([ctid.SubmodelOrder(2, 0)], [0.25, 0.25, 3.0])
    y = ctid.simulate(mode.with_input_delay(2.6 * H), u, H)
    csv = tmp_path / "fractional.csv"
    write_csv(csv, {"u": u, "y": y})
    data = ctid.SampledData(H, u, y)
    result = ctid.identify(data, ctid.ModelStructure.modes(1),
                           delay_range=ctid.DelayInterval(min=0.0, max=5 * H))
    e = result.estimate
    assert abs(e.model.input_delay - 2.6 * H) < 1e-9 * 2.6 * H
    assert (e.input_delay_samples, round(e.input_delay_fraction, 6)) == (2, 0.6)
    assert e.delay_standard_error > 0
    np.testing.assert_allclose(e.parameters, [0.25, 0.25, 3.0], rtol=1e-9)
    document = fit(cli, csv, "--modes", "1", "--delay-range", f"0:{5 * H!r}")
    expect_same_as_cli(result, document)
    assert bits([document["delay_standard_error"]]) == bits([e.delay_standard_error])
    assert list(result.delay_scan.delays) == [0, 1, 2, 3, 4, 5]


def test_several_records_equal_ctid_fit_on_several_files(cli, tmp_path):
    # Two pieces of one noise-free run, neither at rest: a list of SampledData in Python and
    # two files on the command line give the same numbers, and the exact model.
    u = ctid.white_noise(3000, 1.0, 46)
    y = ctid.simulate(TRUTH, u, H)
    pieces = [(300, 1100), (1700, 1200)]
    records, files = [], []
    for k, (first, count) in enumerate(pieces):
        part = slice(first, first + count)
        records.append(ctid.SampledData(H, u[part], y[part]))
        files.append(tmp_path / f"piece{k}.csv")
        write_csv(files[-1], {"u": u[part], "y": y[part]})
    options = ctid.IdentificationOptions(refined_iv=ctid.RefinedIvOptions(
        initial_conditions=ctid.InitialConditions.estimate))
    result = ctid.identify(records, ctid.ModelStructure.modes(2), options)
    np.testing.assert_allclose(result.estimate.parameters, TRUTH.parameters(), rtol=1e-9)
    assert len(result.estimate.initial_conditions) == 2 * 4
    document = fit(cli, files[0], str(files[1]), "--modes", "2", "--initial-conditions",
                   "estimate")
    expect_same_as_cli(result, document)
    assert document["data"]["record_samples"] == [1100, 1200]
    with pytest.raises(ctid.InvalidArgument, match="record 2 is sampled every"):
        ctid.identify([records[0], ctid.SampledData(2 * H, u[:500], y[:500])],
                      ctid.ModelStructure.modes(2))


def test_unfactored_with_options_equals_ctid_fit(cli, open_loop):
    data, csv = open_loop
    options = ctid.IdentificationOptions(refined_iv=ctid.RefinedIvOptions(
        input_delay_samples=2, max_iterations=50, noise=ctid.NoiseAssumption.white,
        output_interpolation=ctid.Hold.zero_order_hold))
    result = ctid.identify(data, ctid.ModelStructure.unfactored(4, 2), options)
    assert result.estimator == ctid.RefinedIvEstimator.srivc
    document = fit(cli, csv, "--poles", "4", "--zeros", "2", "--input-delay-samples", "2", "--max-iterations",
                   "50", "--noise", "white", "--interpolation", "zoh")
    expect_same_as_cli(result, document)


def test_closed_loop_equals_ctid_fit(cli, closed_loop):
    data, csv = closed_loop
    result = ctid.identify(data, ctid.ModelStructure.modes(2), controller=PID)
    assert result.estimator == ctid.RefinedIvEstimator.additive_clsrivc and result.closed_loop
    expect_same_as_cli(result, fit(cli, csv, "--modes", "2", "-c", str(PID_FILE)))


def test_two_stage_equals_ctid_fit_and_needs_no_controller(cli, closed_loop):
    data, csv = closed_loop
    result = ctid.identify(data, ctid.ModelStructure.modes(2),
                           two_stage=ctid.TwoStageOptions())
    assert result.closed_loop and result.estimator == ctid.RefinedIvEstimator.additive_srivc
    stage = result.two_stage
    assert stage.sensitivity_model in (ctid.SensitivityModel.fir, ctid.SensitivityModel.rational)
    assert "uncorrelated with the noise" in stage.assumptions
    document = fit(cli, csv, "--modes", "2", "--two-stage")
    expect_same_as_cli(result, document)
    assert document["two_stage"]["sensitivity_order"] == stage.sensitivity_order
    assert document["two_stage"]["sensitivity_model"] == stage.sensitivity_model.name
    # Close to the truth without the controller: within 10 % on every parameter at this noise
    # (the lightly damped mode's a1 = 0.01 is the farthest, at 8 %).
    error = np.abs(np.asarray(result.estimate.parameters) / np.asarray(TRUTH.parameters()) - 1)
    assert error.max() < 0.1, error
    with pytest.raises(ctid.InvalidArgument, match="two_stage and .*controller are both set"):
        ctid.identify(data, ctid.ModelStructure.modes(2), controller=PID,
                      two_stage=ctid.TwoStageOptions())
    with pytest.raises(ctid.InvalidArgument, match="but sensitivity_model is automatic"):
        ctid.identify(data, ctid.ModelStructure.modes(2),
                      two_stage=ctid.TwoStageOptions(sensitivity_order=3))


def test_relocation_equals_ctid_fit(cli, open_loop):
    data, csv = open_loop
    refined = ctid.RefinedIvOptions(input_delay_samples=2)
    result = ctid.identify(data, ctid.ModelStructure.modes(2), relocate_modes=True,
                           refined_iv=refined)
    document = fit(cli, csv, "--modes", "2", "--input-delay-samples", "2", "--relocate-modes")
    expect_same_as_cli(result, document)
    report = document["mode_relocation"]
    assert report["message"] == result.mode_relocation.message
    assert report["relocations"] == result.mode_relocation.relocations
    assert bits([report["score"]]) == bits([result.mode_relocation.score])


def test_identify_is_the_direct_estimator_bit_for_bit(open_loop, closed_loop):
    data, _ = open_loop
    refined = ctid.RefinedIvOptions(input_delay_samples=2)
    a = ctid.identify(data, ctid.ModelStructure.additive(MODES), refined_iv=refined).estimate
    b = ctid.additive_srivc(data, MODES, refined)
    assert bits(a.parameters) == bits(b.parameters)
    assert bits(np.asarray(a.covariance)) == bits(np.asarray(b.covariance))
    closed, _ = closed_loop
    c = ctid.identify(closed, ctid.ModelStructure.unfactored(4, 2), controller=PID).estimate
    d = ctid.clsrivc(closed, PID, ctid.SubmodelOrder(4, 2))
    assert bits(c.parameters) == bits(d.parameters)


def test_options_and_structure_are_checked_with_the_field_path(open_loop):
    data, _ = open_loop
    modes = ctid.ModelStructure.modes(2)
    with pytest.raises(ctid.InvalidArgument, match=r"IdentificationOptions\.delay_scan_samples\.max is 1"):
        ctid.identify(data, modes, delay_scan_samples=ctid.DelayRange(min=3, max=1))
    with pytest.raises(ctid.InvalidArgument,
                       match=r"IdentificationOptions\.refined_iv\.max_iterations is 0"):
        ctid.identify(data, modes, refined_iv=ctid.RefinedIvOptions(max_iterations=0))
    with pytest.raises(ctid.InvalidArgument, match="structure is unfactored"):
        ctid.identify(data, ctid.ModelStructure.unfactored(2, 0), relocate_modes=True)
    with pytest.raises(ctid.InvalidArgument, match="exactly one"):
        ctid.identify(data, ctid.ModelStructure(kind=ctid.ModelKind.unfactored, orders=MODES))
    with pytest.raises(TypeError, match="unexpected keyword argument 'max_iterations'"):
        ctid.identify(data, modes, max_iterations=5)
    with pytest.raises(TypeError, match="not both"):
        ctid.identify(data, modes, ctid.IdentificationOptions(), relocate_modes=True)


def test_classes_follow_the_cpp_field_lists():
    assert ctid.IdentificationOptions.fields == (
        "controller", "continuous_controller", "delay_scan_samples", "delay_range",
        "relocate_modes", "relocation", "polish", "polish_options", "constraints", "refined_iv",
        "two_stage")
    assert ctid.IdentificationResult.fields == (
        "estimator", "closed_loop", "estimate", "delay_scan", "mode_relocation", "two_stage",
        "polish", "restarted_from_polish")
    assert ctid.ModelStructure.fields == ("kind", "orders")
    assert ctid.DelayRange.fields == ("min", "max")
    options = ctid.IdentificationOptions()
    assert options.controller is None and options.delay_scan_samples is None
    assert options.continuous_controller is None
    assert not options.relocate_modes
    assert options.refined_iv == ctid.RefinedIvOptions()
    options.refined_iv.max_iterations = 7  # nested options are edited in place
    assert options.refined_iv.max_iterations == 7
    structure = ctid.ModelStructure.unfactored(3, 1, 1)
    assert structure.kind == ctid.ModelKind.unfactored and not structure.is_additive()
    assert (structure.orders[0].n, structure.orders[0].m, structure.orders[0].integrators) == \
        (3, 1, 1)
    assert len(ctid.ModelStructure.modes(3).orders) == 3


def test_two_stage_structure_scan_equals_ctid_structure(cli, closed_loop):
    """scan_structures with the two-stage method is `ctid structure --two-stage`: every
    candidate scored from the simulated input (decision 0071), the same numbers in both."""
    data, csv = closed_loop
    options = ctid.StructureScanOptions()
    options.identification.two_stage = ctid.TwoStageOptions()
    scan = ctid.scan_structures(data, [ctid.ModelStructure.modes(k) for k in (1, 2, 3)], options)
    assert scan.recommended == 1, scan.rule
    out = csv.with_name("closed_scan.json")
    run = subprocess.run([str(cli), "structure", str(csv), "-T", str(H), "--modes", "1:3",
                          "--two-stage", "-o", str(out), "--force", "-q"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    document = json.loads(out.read_text())
    assert document["recommended"] == scan.recommended
    for fit, row in zip(scan.fits, document["fits"], strict=True):
        for key in ("estimation_fit", "validation_fit", "validation_error", "aic"):
            assert row[key] == pytest.approx(getattr(fit, key), rel=1e-14, abs=0), key
