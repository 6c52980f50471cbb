"""Step and impulse responses from Python (ctid.step_response / impulse_response): closed
forms, the characteristics' delta-method standard errors from an estimation result, the band,
models without a final value, bad input, and the figure with its band drawn into a given axis."""

import math

import numpy as np
import pytest

import ctid
from ctid import plotting


def first_order(gain=2.0, time_constant=0.5, delay=0.0):
    return ctid.TransferFunction([gain], [1.0, time_constant], delay)


def test_step_of_a_first_order_model_is_the_closed_form():
    r = ctid.step_response(first_order(delay=0.1), final_time=3.0, points=61)
    t = np.asarray(r.time)
    expected = np.where(t < 0.1, 0.0, 2.0 * (1.0 - np.exp(-(t - 0.1) / 0.5)))
    np.testing.assert_allclose(r.output, expected, atol=1e-12)
    assert r.kind == ctid.ResponseKind.step
    assert np.size(r.standard_deviation) == 0
    c = r.characteristics
    assert c.defined()
    assert c.dc_gain.value == pytest.approx(2.0, abs=1e-14)
    assert c.rise_time.value == pytest.approx(0.5 * math.log(9.0), abs=1e-12)
    assert c.settling_time.value == pytest.approx(0.1 + 0.5 * math.log(50.0), abs=1e-12)
    assert math.isnan(c.dc_gain.standard_error)


def test_impulse_is_the_derivative_of_the_step():
    g = ctid.TransferFunction([1.0, 0.3], [1.0, 0.2, 0.04])
    t = np.linspace(0.05, 2.0, 25)
    d = 1e-6
    slope = (np.asarray(ctid.step_response_at(g, t + d))
             - np.asarray(ctid.step_response_at(g, t - d))) / (2 * d)
    np.testing.assert_allclose(ctid.impulse_response_at(g, t), slope, rtol=1e-6, atol=1e-6)
    r = ctid.impulse_response(g, final_time=2.0, points=5)
    assert r.kind == ctid.ResponseKind.impulse


def fitted_first_order(seed=3):
    truth = first_order()
    u = ctid.white_noise(600, 1.0, seed)
    y = np.asarray(ctid.simulate(truth, u, 0.05)) + np.asarray(ctid.white_noise(600, 0.1, seed + 1))
    options = ctid.RefinedIvOptions(
        initial_model=ctid.AdditiveModel.from_transfer_function(first_order(2.2, 0.55)))
    return ctid.srivc(ctid.SampledData(0.05, u, y), ctid.SubmodelOrder(n=1, m=0), options)


def test_result_gives_delta_method_errors_and_band():
    result = fitted_first_order()
    assert result.converged()
    r = ctid.step_response(result, final_time=3.0, points=31, confidence=0.9)
    cov = np.asarray(result.covariance)
    b0 = result.model[0].b.coefficients[0]
    c = r.characteristics
    # theta = [a1, b0]: the DC gain is b0 with the variance of b0.
    assert c.dc_gain.value == pytest.approx(b0, rel=1e-13)
    assert c.dc_gain.standard_error == pytest.approx(math.sqrt(cov[1, 1]), rel=1e-6)
    # rise time a1 ln 9: its error is ln 9 times a1's.
    assert c.rise_time.standard_error == pytest.approx(math.log(9.0) * math.sqrt(cov[0, 0]),
                                                       rel=1e-5)
    assert r.z == pytest.approx(1.6448536269514722, abs=1e-12)
    sd = np.asarray(r.standard_deviation)
    assert sd.shape == (31,) and sd[0] == 0.0 and np.all(sd[1:] > 0.0)
    np.testing.assert_allclose(np.asarray(r.upper) - np.asarray(r.lower), 2 * r.z * sd,
                               rtol=1e-12, atol=1e-15)
    same = ctid.step_characteristics(result)
    assert same.dc_gain == c.dc_gain


def test_integrator_and_unstable_models_say_why():
    c = ctid.step_response(ctid.TransferFunction([1.0], [0.0, 1.0, 1.0])).characteristics
    assert not c.stable and not c.defined()
    assert "integrator" in c.not_defined_reason
    assert math.isnan(c.dc_gain.value)
    u = ctid.step_characteristics(ctid.TransferFunction([1.0], [1.0, -0.5]))
    assert "not stable" in u.not_defined_reason


def test_bad_input():
    with pytest.raises(ValueError, match="final_time is 0; it must be finite and > 0"):
        ctid.step_response(first_order(), final_time=0.0)
    with pytest.raises(ValueError, match="at most 1000000"):
        ctid.step_response(first_order(), final_time=1e4, sample_time=1e-4)
    with pytest.raises(ValueError, match="covariance is 3 x 3 but the model has 2 parameters"):
        ctid.step_response(first_order(), covariance=np.eye(3))
    with pytest.raises(TypeError, match="unexpected keyword argument 'final_tim'"):
        ctid.step_response(first_order(), final_tim=1.0)
    with pytest.raises(TypeError, match="model must be an EstimationResult"):
        ctid.step_response("g.json")


def test_step_figure_draws_the_band_into_the_given_axis():
    import matplotlib.pyplot as plt

    figure, ax = plt.subplots()
    result = fitted_first_order()
    assert plotting.step(result, ax=ax, final_time=3.0, points=31) is figure
    labels = [line.get_label() for line in ax.get_lines()]
    assert "step response" in labels and "final value" in labels
    assert any(c.get_label() == "95% band" for c in ax.collections)
    line = next(l for l in ax.get_lines() if l.get_label() == "step response")
    np.testing.assert_allclose(line.get_ydata(),
                               ctid.step_response(result, final_time=3.0, points=31).output)
    plt.close(figure)
