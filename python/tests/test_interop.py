"""Models and results in the Python ecosystem (ctid.interop): descending coefficients in and
out build the same system (checked by frequency response against SciPy's own evaluation),
SciPy and python-control objects carry those coefficients, a delay is never dropped silently,
pandas tables hold the result's numbers, and notebooks get an HTML view with the verdict."""

import sys
import types

import numpy as np
import pytest
from scipy import signal

import ctid

W = np.array([0.1, 0.7, 2.0, 2.3, 9.0])


def response(model):
    return np.array([model.frequency_response(w) for w in W])


def fitted_second_order(seed=3):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(600)
    g = ctid.from_descending([4.0], [1.0, 0.8, 4.0])
    y = np.asarray(ctid.simulate(g, u, 0.05)) + 0.01 * rng.standard_normal(600)
    return ctid.srivc(ctid.SampledData(0.05, u, y), ctid.SubmodelOrder(n=2, m=0))


def test_from_descending_is_the_system_scipy_means():
    num, den = [2.0, 3.0], [1.0, 0.8, 4.0, 0.5]
    g = ctid.from_descending(num, den)
    np.testing.assert_array_equal(g.numerator.coefficients, [3.0, 2.0])
    np.testing.assert_array_equal(g.denominator.coefficients, [0.5, 4.0, 0.8, 1.0])
    _, h = signal.freqs(num, den, worN=W)
    np.testing.assert_allclose(response(g), h, rtol=1e-13)
    # Leading zeros are not powers: [0, 0, 1, 2] is s + 2.
    same = ctid.from_descending([0.0, 2.0, 3.0], [0.0, 0.0, 1.0, 0.8, 4.0, 0.5])
    np.testing.assert_array_equal(same.numerator.coefficients, [3.0, 2.0])
    assert same.denominator.degree() == 3


def test_round_trip_through_descending_is_exact():
    g = ctid.from_descending([1.5, -2.0, 7.0], [1.0, 3.0, 0.25, 9.0], input_delay=0.3)
    num, den, delay = ctid.to_descending(g)
    np.testing.assert_array_equal(num, [1.5, -2.0, 7.0])
    np.testing.assert_array_equal(den, [1.0, 3.0, 0.25, 9.0])
    assert delay == 0.3


def test_an_additive_model_converts_as_the_sum_of_its_submodels():
    g = ctid.from_descending([1.0, 5.0, 2.0], [1.0, 1.2, 10.0, 3.0, 9.0])
    additive = ctid.AdditiveModel.from_transfer_function(g)
    assert len(additive) == 2
    num, den, _ = ctid.to_descending(additive)
    _, h = signal.freqs(num, den, worN=W)
    np.testing.assert_allclose(h, response(g), rtol=1e-10)


def test_scipy_system_of_a_fit_has_the_fits_response():
    result = fitted_second_order()
    lti = ctid.to_scipy(result)
    assert isinstance(lti, signal.TransferFunction)
    _, h = signal.freqs(lti.num, lti.den, worN=W)
    np.testing.assert_allclose(h, response(result.model), rtol=1e-12)
    # SciPy's step response of the converted system ends at the fit's DC gain.
    t, y = signal.step(lti, T=np.linspace(0.0, 40.0, 4001))
    assert y[-1] == pytest.approx(result.model.to_transfer_function().dc_gain(), rel=1e-6)


def test_a_delay_is_never_dropped_silently():
    g = ctid.from_descending([2.0], [0.5, 1.0], input_delay=0.25)
    with pytest.raises(ValueError, match=r"input delay of 0.25 s.*delay='drop'"):
        ctid.to_scipy(g)
    with pytest.raises(ValueError, match="input delay"):
        ctid.to_control(g)
    with pytest.raises(ValueError, match="'refuse' or 'drop'"):
        ctid.to_scipy(g, delay="pade")
    lti = ctid.to_scipy(g, delay="drop")
    np.testing.assert_array_equal(lti.den, [1.0, 2.0])  # SciPy normalises to a monic den
    np.testing.assert_array_equal(lti.num, [4.0])


def test_to_control_hands_python_control_the_descending_coefficients(monkeypatch):
    # python-control is not a Debian package: a stand-in module records what it is given.
    seen = {}

    class TransferFunction:
        def __init__(self, num, den):
            seen["num"], seen["den"] = np.asarray(num), np.asarray(den)

    monkeypatch.setitem(sys.modules, "control", types.SimpleNamespace(
        TransferFunction=TransferFunction))
    ctid.to_control(ctid.TransferFunction([4.0], [4.0, 0.8, 1.0]))
    np.testing.assert_array_equal(seen["num"], [4.0])
    np.testing.assert_array_equal(seen["den"], [1.0, 0.8, 4.0])


def test_to_control_without_python_control_says_what_to_use(monkeypatch):
    monkeypatch.setitem(sys.modules, "control", None)  # import control raises ImportError
    with pytest.raises(ImportError, match="python-control.*to_descending"):
        ctid.to_control(ctid.TransferFunction([1.0], [1.0, 1.0]))


def test_bad_coefficients_and_objects_are_one_clear_error():
    with pytest.raises(ValueError, match="denominator is zero"):
        ctid.from_descending([1.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="numerator: coefficients must be finite"):
        ctid.from_descending([np.nan], [1.0, 1.0])
    with pytest.raises(ValueError, match="one-dimensional"):
        ctid.from_descending([[1.0]], [1.0, 1.0])
    with pytest.raises(TypeError, match="to_descending: expected a ctid.TransferFunction.*str"):
        ctid.to_descending("4/(s+1)")
    with pytest.raises(TypeError, match="to_dataframe: expected"):
        ctid.to_dataframe(ctid.TransferFunction([1.0], [1.0, 1.0]))


def test_dataframes_hold_the_results_numbers():
    pandas = pytest.importorskip("pandas")
    result = fitted_second_order()
    table = ctid.to_dataframe(result)
    assert isinstance(table, pandas.DataFrame)
    assert list(table.parameter) == ["theta1.a1", "theta1.a2", "theta1.b0"]
    np.testing.assert_array_equal(table.value.to_numpy(), result.parameters)
    np.testing.assert_array_equal(table.standard_error.to_numpy(), result.standard_errors)

    r = ctid.step_response(result, final_time=5.0, points=11)
    frame = ctid.to_dataframe(r)
    assert list(frame.columns) == ["t", "y", "y_std", "lower", "upper"]
    np.testing.assert_array_equal(frame.y.to_numpy(), r.output)
    plain = ctid.to_dataframe(ctid.step_response(result.model, final_time=5.0, points=11))
    assert list(plain.columns) == ["t", "y"]


def test_notebook_view_shows_the_verdict_and_the_parameters():
    result = fitted_second_order()
    page = result._repr_html_()
    assert "EstimationResult" in page and ">usable<" in page
    assert page.count("<tr>") == 1 + 3  # header and a1, a2, b0
    assert f"{result.parameters[0]:.6g}" in page
    # A result whose verdict is not usable says so, with its reasons (a first-order fit of
    # unrelated noise: its fit is negative).
    rng = np.random.default_rng(1)
    noise = ctid.SampledData(0.05, rng.standard_normal(300), rng.standard_normal(300))
    bad = ctid.srivc(noise, ctid.SubmodelOrder(n=1, m=0))
    assert not bad.verdict.usable
    view = bad._repr_html_()
    assert "not usable" in view and "is negative" in view


def test_a_transfer_function_is_taken_wherever_an_additive_model_is():
    # model_output takes an AdditiveModel only; a TransferFunction (with an integrator and a
    # delay) gives what its one-submodel AdditiveModel gives, bit for bit.
    g = ctid.from_descending([2.0, 1.0], [1.0, 3.0, 2.0, 0.0], input_delay=0.1)
    one = ctid.AdditiveModel(g)
    assert len(one) == 1 and one.input_delay == 0.1
    assert one.submodels[0].integrators == 1
    u = np.random.default_rng(4).standard_normal(400)
    np.testing.assert_array_equal(ctid.model_output(g, u, 0.05), ctid.model_output(one, u, 0.05))
    assert ctid.largest_pole_frequency(g) == ctid.largest_pole_frequency(one)
    with pytest.raises(ValueError, match="improper"):
        ctid.AdditiveModel(ctid.TransferFunction([1.0, 1.0, 1.0], [1.0, 1.0]))
