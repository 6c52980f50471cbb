"""additive_srivc_relocated from Python: the three-mode case of
tests/refined_iv/mode_relocation_test.cc, where a weak, lightly damped mode started far off
makes the plain iteration stop at a wrong stationary point."""

import math

import numpy as np
import pytest

import ctid

H = 1.0 / 512.0
N = 2048
ORDERS = [ctid.SubmodelOrder(2, 0)] * 3


def mode(hz, zeta, gain):
    w = 2.0 * math.pi * hz
    return [2.0 * zeta / w, 1.0 / (w * w), gain]


TRUTH = ctid.AdditiveModel.from_parameters(
    ORDERS, mode(2.0, 0.01, 1.0) + mode(9.0, 2e-3, 0.02) + mode(31.3, 5e-4, 1e-3))
START = ctid.AdditiveModel.from_parameters(
    ORDERS, mode(1.8, 0.02, 0.8) + mode(9.5, 5e-3, 0.05) + mode(20.0, 1e-3, 1e-2))


@pytest.fixture(scope="module")
def data():
    u = ctid.multisine(period_length=N, sample_time=H, min_frequency=0.25, max_frequency=60.0,
                       seed=3).signal
    y = ctid.simulate(TRUTH, u, H)
    y = y + ctid.scale_noise_to_snr(y, ctid.white_noise(N, 1.0, 1), 30.0)
    return ctid.SampledData(H, u, y)


def weak_mode(result):
    truth = TRUTH.modal_parameters(2).natural_frequency
    return min(result.modes, key=lambda m: abs(m.value.natural_frequency - truth))


def test_relocation_moves_the_weak_mode_to_the_truth(data):
    options = ctid.RefinedIvOptions(initial_model=START, noise=ctid.NoiseAssumption.white,
                                    max_iterations=200)
    plain = ctid.additive_srivc(data, ORDERS, options)
    truth = TRUTH.modal_parameters(2)
    stuck = weak_mode(plain)
    assert abs(stuck.value.natural_frequency - truth.natural_frequency) > \
        10 * stuck.standard_error.natural_frequency

    r = ctid.additive_srivc_relocated(data, ORDERS, options)
    assert r.estimate.termination == ctid.Termination.converged, r.message
    assert r.relocations >= 1 and "relocation(s) kept" in r.message
    assert r.initial_mean_squared_error == plain.mean_squared_error
    found = weak_mode(r.estimate)
    assert abs(found.value.natural_frequency - truth.natural_frequency) < \
        3 * found.standard_error.natural_frequency
    kept = [t for t in r.trials if t.accepted]
    assert kept and all(t.termination == ctid.Termination.converged for t in kept)
    assert r.score <= r.initial_score
    assert all(t.score < r.initial_score for t in kept)


def test_relocation_options_by_keyword_and_validation(data):
    none = ctid.ModeRelocationOptions(max_relocations=0)
    r = ctid.additive_srivc_relocated(data, ORDERS, relocation=none, initial_model=START,
                                      noise=ctid.NoiseAssumption.white, max_iterations=200)
    assert r.relocations == 0 and len(r.trials) == 0
    with pytest.raises(ValueError, match="max_relocations"):
        ctid.additive_srivc_relocated(data, ORDERS,
                                      relocation=ctid.ModeRelocationOptions(max_relocations=-1))
    with pytest.raises(TypeError):
        ctid.ModeRelocationOptions(max_moves=2)
