"""Closed loops with a continuous-time controller C(p) (decision 0067) from Python: the analog
loop simulation against SciPy's exact ZOH discretisation of the closed-loop maps, the plant
from noise-free data to 1e-8 through ctid.identify, and a noisy fit at a stationary point of
the closed-loop output error, checked by an independent NumPy/SciPy criterion."""

import numpy as np
import pytest

import ctid

# SciPy's cont2discrete warns when a discretised numerator has coefficients near rounding
# (the closed-loop maps' leading terms); the responses are compared to 1e-9 all the same.
pytestmark = pytest.mark.filterwarnings("ignore:Badly conditioned filter coefficients")

H = 0.02
# G = 2 / (1 - 0.5 p + 0.1 p^2) (unstable), C = (1 + 0.6 p) / (1 + 0.05 p).
PLANT_NUM, PLANT_DEN = [2.0], [1.0, -0.5, 0.1]
CTRL_NUM, CTRL_DEN = [1.0, 0.6], [1.0, 0.05]


def polymul(a, b):
    return np.polynomial.polynomial.polymul(a, b)


def polyadd(a, b):
    return np.polynomial.polynomial.polyadd(a, b)


def zoh_response(num, den, x):
    """y_k of num/den (ascending powers) to x held between samples, by SciPy."""
    signal = pytest.importorskip("scipy.signal")
    system = signal.cont2discrete((num[::-1], den[::-1]), H, method="zoh")
    _, y = signal.dlsim(system, x)
    return np.ravel(y)


def closed_loop_output(plant_num, plant_den, r):
    """x = G C / (1 + G C) r by SciPy, for the plant (plant_num, plant_den)."""
    acl = polyadd(polymul(plant_den, CTRL_DEN), polymul(plant_num, CTRL_NUM))
    return zoh_response(polymul(plant_num, CTRL_NUM), acl, r)


def analog_record(seed, noise_std):
    rng = np.random.default_rng(seed)
    r = rng.standard_normal(3000)
    v = noise_std * rng.standard_normal(3000) if noise_std > 0 else np.zeros(0)
    loop = ctid.simulate_closed_loop(ctid.TransferFunction(PLANT_NUM, PLANT_DEN),
                                     ctid.TransferFunction(CTRL_NUM, CTRL_DEN), r, H, v)
    return r, loop


def test_the_analog_loop_simulation_is_scipys_exact_discretisation():
    r, loop = analog_record(1, 0.0)
    expected = closed_loop_output(PLANT_NUM, PLANT_DEN, r)
    assert np.max(np.abs(np.asarray(loop.output) - expected)) < 1e-9 * np.max(np.abs(expected))
    acl = polyadd(polymul(PLANT_DEN, CTRL_DEN), polymul(PLANT_NUM, CTRL_NUM))
    u = zoh_response(polymul(CTRL_NUM, PLANT_DEN), acl, r)
    assert np.max(np.abs(np.asarray(loop.input) - u)) < 1e-9 * np.max(np.abs(u))


def test_identify_gives_the_unstable_plant_from_noise_free_data():
    r, loop = analog_record(2, 0.0)
    data = ctid.SampledData(H, loop.input, loop.output, r)
    result = ctid.identify(data, ctid.ModelStructure.unfactored(2, 0),
                           continuous_controller=ctid.TransferFunction(CTRL_NUM, CTRL_DEN))
    assert result.estimator == ctid.RefinedIvEstimator.clsrivc_continuous
    assert result.closed_loop
    truth = np.array([-0.5, 0.1, 2.0])
    estimate = np.asarray(result.estimate.parameters)
    assert np.linalg.norm(estimate - truth) / np.linalg.norm(truth) < 1e-8
    assert result.estimate.verdict.usable


def test_a_noisy_fit_is_a_stationary_point_of_scipys_closed_loop_output_error():
    r, loop = analog_record(3, 0.2)
    y = np.asarray(loop.output)
    data = ctid.SampledData(H, loop.input, y, r)
    result = ctid.identify(data, ctid.ModelStructure.unfactored(2, 0),
                           continuous_controller=ctid.TransferFunction(CTRL_NUM, CTRL_DEN))
    theta = np.asarray(result.estimate.parameters)

    def criterion(t):
        x = closed_loop_output([t[2]], [1.0, t[0], t[1]], r)
        return np.sum((y - x) ** 2)

    # Central differences of V(theta) at the estimate, against its curvature 2 sum(psi^2).
    gradient = np.empty(3)
    for i in range(3):
        step = np.zeros(3)
        step[i] = 1e-6 * max(abs(theta[i]), 1.0)
        gradient[i] = (criterion(theta + step) - criterion(theta - step)) / (2 * step[i])
    standard_errors = np.asarray(result.estimate.standard_errors)
    # Off the stationary point by k standard errors, |dV/dtheta_i| times the standard error is
    # about 2 k sigma^2; below 0.03 sigma^2 means within 0.015 standard errors of it.
    sigma2 = np.mean((y - closed_loop_output([theta[2]], [1.0, theta[0], theta[1]], r)) ** 2)
    assert np.all(np.abs(gradient) * standard_errors < 0.03 * sigma2)
    assert np.all(np.abs(theta - [-0.5, 0.1, 2.0]) < 4 * standard_errors)


def test_a_controller_with_a_plant_delay_is_refused():
    r, loop = analog_record(4, 0.0)
    data = ctid.SampledData(H, loop.input, loop.output, r)
    with pytest.raises(ValueError, match="delay in an analog loop is not supported"):
        ctid.identify(data, ctid.ModelStructure.unfactored(2, 0),
                      continuous_controller=ctid.TransferFunction(CTRL_NUM, CTRL_DEN),
                      delay_scan_samples=ctid.DelayRange(min=0, max=3))
