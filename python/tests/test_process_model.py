"""ctid.process_model: procest's process models fitted by output error (decision 0040). A P1D
record is simulated here by an independent NumPy recursion (the exact ZOH response of
K e^{-Td s}/(1 + T s) with the dead time split into whole samples and a fraction), and the fit
from the automatic start returns K, T, Td to 1e-8; `ctid fit --process P1D` on the same samples
writes the very numbers Python returns; held parameters, bounds and bad names behave."""

import json
import subprocess

import numpy as np
import pytest

import ctid

H = 0.1
N = 1200
K, T, TD = 2.0, 1.5, 0.37  # the dead time is 3.7 samples


def p1d_output(u, k, t, td, h):
    """x_{k+1} = a x_k + K (b1 u_{k-d-1} + b0 u_{k-d}): the delayed ZOH input is u_{k-d-1} on
    the first fraction f of the period and u_{k-d} on the rest."""
    d = int(np.floor(td / h))
    f = td / h - d
    a = np.exp(-h / t)
    late = np.exp(-(1.0 - f) * h / t)
    b_prev, b_cur = k * (late - a), k * (1.0 - late)
    shifted = np.concatenate([np.zeros(d + 1), u])  # shifted[j + d + 1] = u_j
    y = np.zeros(len(u))
    x = 0.0
    for i in range(len(u)):
        y[i] = x
        x = a * x + b_prev * shifted[i] + b_cur * shifted[i + 1]
    return y


@pytest.fixture(scope="module")
def record():
    rng = np.random.default_rng(7)
    u = np.repeat(np.sign(rng.standard_normal(N // 4)), 4)
    return ctid.SampledData(H, u, p1d_output(u, K, T, TD, H))


def test_parameter_names_follow_procest():
    assert ctid.process_parameter_names("P1D") == ["K", "Tp1", "Td"]
    assert ctid.process_parameter_names("P2DZU") == ["K", "Tw", "Zeta", "Tz", "Td"]


def test_p1d_recovered_exactly_from_an_independent_simulation(record):
    r = ctid.process_model(record, "P1D")
    assert r.structure == "P1D"
    assert list(r.parameter_names) == ["K", "Tp1", "Td"]
    np.testing.assert_allclose(r.parameters, [K, T, TD], rtol=1e-8)
    assert r.verdict.usable
    assert r.fit_percent > 99.9999
    g = r.transfer_function()
    assert g.input_delay == pytest.approx(TD, rel=1e-8)


def test_step_response_of_a_process_result_has_its_closed_forms(record):
    """ctid.step_response(ProcessModelResult): rise time Tp1 ln 9 and settling time
    Td + Tp1 ln 50 of the estimate, a band from the process parameters' covariance."""
    r = ctid.process_model(record, "P1D")
    k, t, td = r.parameters
    response = ctid.step_response(r, final_time=10 * t, points=2001)
    c = response.characteristics
    assert c.dc_gain.value == pytest.approx(k, rel=1e-12)
    assert c.rise_time.value == pytest.approx(t * np.log(9.0), rel=1e-5)
    assert c.settling_time.value == pytest.approx(td + t * np.log(50.0), rel=1e-5)
    assert c.dc_gain.standard_error == pytest.approx(r.standard_errors[0], rel=1e-6)
    assert len(response.standard_deviation) == len(response.time)
    with pytest.raises(TypeError, match="carries its own covariance"):
        ctid.step_response(r, covariance=np.eye(3))


def test_held_parameter_and_bounds(record):
    held = ctid.process_model(record, "P1D", fixed={"Tp1": 1.2})
    assert held.parameter("Tp1") == 1.2
    assert held.standard_error("Tp1") == 0.0
    assert list(held.fixed_parameters) == ["Tp1"]
    bounded = ctid.process_model(record, "P1D", bounds={"Tp1": (None, 1.0)})
    assert bounded.parameter("Tp1") <= 1.0


def test_bad_names_and_settings_raise_saying_why(record):
    with pytest.raises(ctid.InvalidArgument, match="4 poles; a process model has 0 to 3"):
        ctid.process_model(record, "P4")
    with pytest.raises(ctid.InvalidArgument, match="'X' is not a process-model letter"):
        ctid.process_model(record, "P1X")
    with pytest.raises(ctid.InvalidArgument, match="U .an underdamped pair. needs at least 2"):
        ctid.process_model(record, "P1U")
    with pytest.raises(ctid.InvalidArgument, match="parameter 'Tz' is not in process model P1D"):
        ctid.process_model(record, "P1D", fixed={"Tz": 1.0})


def test_the_cli_writes_the_numbers_python_returns(cli, record, tmp_path):
    rng = np.random.default_rng(8)
    noisy = ctid.SampledData(H, record.input, record.output + 0.1 * rng.standard_normal(N))
    csv = tmp_path / "d.csv"
    with open(csv, "w") as out:
        out.write("u,y\n")
        for u, y in zip(noisy.input, noisy.output):
            out.write(f"{float(u)!r},{float(y)!r}\n")
    result = tmp_path / "r.json"
    run = subprocess.run([str(cli), "fit", str(csv), "-T", str(H), "--process", "P1D",
                          "--max-iterations", "200", "-o", str(result), "-q"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    document = json.loads(result.read_text())
    python = ctid.process_model(noisy, "P1D")
    assert document["parameters"] == list(python.parameters)
    assert document["standard_errors"] == list(python.standard_errors)
