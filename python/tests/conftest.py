"""Shared fixtures: the build folder holding ctid_python_reference, and a seeded experiment
that mirrors the inputs of reference.cc."""

import os
import pathlib

import numpy as np
import pytest

import ctid

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _reference_binary():
    candidates = []
    if os.environ.get("CTID_BUILD_DIR"):
        candidates.append(pathlib.Path(os.environ["CTID_BUILD_DIR"]) / "python")
    candidates.append(pathlib.Path(ctid.__file__).resolve().parents[1])
    for folder in candidates:
        binary = folder / "ctid_python_reference"
        if binary.exists():
            return binary
    return None


@pytest.fixture(scope="session")
def reference_binary():
    binary = _reference_binary()
    if binary is None:
        pytest.fail("ctid_python_reference was not built next to the ctid package")
    return binary


H = 0.05


@pytest.fixture(scope="session")
def experiment():
    """The experiment of reference.cc: resonant model, seeded multisine, white noise."""
    g = ctid.TransferFunction([4.0], [4.0, 0.8, 1.0])
    u = ctid.multisine(period_length=256, sample_time=H, max_frequency=4.0, periods=4, seed=7)
    y0 = ctid.simulate(g, u.signal, H)
    noise = ctid.white_noise(len(y0), 0.01, 99)
    data = ctid.SampledData(H, u.signal, y0 + noise)
    return {"g": g, "u": u, "y0": y0, "noise": noise, "data": data}


@pytest.fixture(scope="session")
def fitted(experiment):
    return ctid.srivc(experiment["data"], ctid.SubmodelOrder(2, 0), max_iterations=30)


def rng(seed=0):
    return np.random.default_rng(seed)
