"""The shared-pole estimator from Python (ctid.mimo_srivc, issue 13): modes, shapes and the MAC
from a noise-free two-input, three-output record, options as keywords, and the result document
read back by read_result."""

import math

import numpy as np
import pytest

import ctid


def two_modes():
    shapes = [[1.0, 0.5, -0.3], [-0.4, 1.0, 0.6]]
    participation = [[1.0, 0.6], [-0.5, 0.8]]
    submodels = []
    for i, w in enumerate((1.4, 4.0)):
        b = [ctid.Polynomial([shapes[i][j] * participation[i][k]])
             for j in range(3) for k in range(2)]
        submodels.append(ctid.MimoSubmodel(ctid.Polynomial([1.0, 0.1 / w, 1 / w ** 2]), b))
    return ctid.MimoAdditiveModel(2, 3, submodels)


def record(model, h=0.05, n=2000):
    u = np.column_stack([ctid.white_noise(n, 1.0, 5 + k) for k in range(2)])
    y = np.zeros((n, 3))
    for j in range(3):
        for k in range(2):
            y[:, j] += ctid.simulate(model.channel(j, k), u[:, k], h)
    return ctid.MimoData(h, u, y)


def test_modes_shapes_and_mac(tmp_path):
    truth = two_modes()
    r = ctid.mimo_srivc(record(truth), [ctid.SubmodelOrder(2, 0)] * 2, max_iterations=50)
    assert r.converged(), r.message
    assert r.verdict.usable
    assert [m.natural_frequency for m in r.modes] == pytest.approx([1.4, 4.0], rel=1e-9)
    psi = np.array([-0.4, 1.0, 0.6])
    assert ctid.modal_assurance(r.modes[1].shape, psi) == pytest.approx(1.0, abs=1e-9)
    mac = ctid.modal_assurance(r.modes, r.modes)
    assert np.allclose(np.diag(mac), 1.0)
    assert mac[0, 1] < 0.5
    assert np.linalg.norm(r.modes[0].shape) == pytest.approx(1.0)
    path = tmp_path / "r.json"
    ctid.write_result(str(path), r)
    back = ctid.read_result(str(path))
    assert isinstance(back, ctid.MimoEstimationResult)
    assert back.modes[1].natural_frequency == r.modes[1].natural_frequency
    assert np.array_equal(back.covariance, r.covariance)


def test_bad_input_is_one_clear_error():
    data = record(two_modes(), n=400)
    with pytest.raises(ctid.InvalidArgument, match="has no poles"):
        ctid.mimo_srivc(data, [ctid.SubmodelOrder(0, 0)])
    with pytest.raises(ctid.InvalidArgument, match="tolerance"):
        ctid.mimo_srivc(data, [ctid.SubmodelOrder(2, 0)], tolerance=2.0)
