"""Shared fixtures: the build folder holding ctid_python_reference, a seeded experiment
that mirrors the inputs of reference.cc, and the example systems of the papers."""

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


def _ctid_binary():
    candidates = []
    if os.environ.get("CTID_BUILD_DIR"):
        candidates.append(pathlib.Path(os.environ["CTID_BUILD_DIR"]))
    candidates.append(pathlib.Path(ctid.__file__).resolve().parents[2])
    for build in candidates:
        binary = build / "apps" / "ctid" / "ctid"
        if binary.exists():
            return binary
    return None


@pytest.fixture(scope="session")
def cli():
    """The ctid command line of the build the package comes from (or CTID_BUILD_DIR's)."""
    binary = _ctid_binary()
    if binary is None:
        pytest.fail("the ctid command line was not found (set CTID_BUILD_DIR)")
    return binary


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


@pytest.fixture(scope="session")
def paper_systems():
    """González et al. Section 6: the open-loop system (6.1, four modes) and its noise filter
    (q + 0.5)/(q - 0.85), the closed-loop plant of eq. (46) and the PID (6.2), and their sample
    time. Taken from the library's study set-up, which tests/study checks bit for bit against
    the C++ tests' fixtures (tests/support/paper_systems.h), so the systems are written once."""
    open_loop = ctid.study_setup(ctid.StudyKind.open_loop)
    closed_loop = ctid.study_setup(ctid.StudyKind.closed_loop)
    assert open_loop.sample_time == closed_loop.sample_time
    return {"open_loop": open_loop.system, "noise_filter": open_loop.noise_filter,
            "closed_loop": closed_loop.system, "pid": closed_loop.controller,
            "sample_time": open_loop.sample_time}


def rng(seed=0):
    return np.random.default_rng(seed)
