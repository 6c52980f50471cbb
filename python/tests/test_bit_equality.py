"""Python results equal the C++ results bit for bit: ctid_python_reference (a C++ program
linked to the same library, reference.cc) prints hexadecimal floats for the inputs that the
`experiment` fixture rebuilds through the bindings."""

import subprocess

import numpy as np
import pytest

import ctid


@pytest.fixture(scope="module")
def reference(reference_binary):
    out = subprocess.run([str(reference_binary)], check=True, capture_output=True, text=True)
    table = {}
    for line in out.stdout.splitlines():
        key, count, *values = line.split()
        assert int(count) == len(values)
        table[key] = np.array([float.fromhex(v) for v in values])
    return table


def same_bits(a, b):
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def complex_parts(reference, key):
    return reference[key + ".real"], reference[key + ".imag"]


def test_signals_and_simulation(reference, experiment):
    assert same_bits(experiment["u"].signal, reference["multisine"])
    assert same_bits(experiment["y0"], reference["simulate"])
    assert same_bits(experiment["noise"], reference["white_noise"])


def test_frfs(reference, experiment):
    frf = ctid.periodic_frf(experiment["data"], period_length=256, transient_periods=1)
    re, im = complex_parts(reference, "periodic_frf.response")
    assert same_bits(frf.response.real, re) and same_bits(frf.response.imag, im)
    assert same_bits(frf.variance, reference["periodic_frf.variance"])
    welch = ctid.welch_frf(experiment["data"], segment_length=128, overlap=0.5)
    re, im = complex_parts(reference, "welch_frf.response")
    assert same_bits(welch.response.real, re) and same_bits(welch.response.imag, im)
    assert same_bits(welch.coherence, reference["welch_frf.coherence"])


def test_frequency_response(reference, experiment):
    g = ctid.frequency_response(experiment["g"], ctid.log_frequency_grid(0.1, 50.0, 40))
    re, im = complex_parts(reference, "frequency_response")
    assert same_bits(g.real, re) and same_bits(g.imag, im)


def test_estimators(reference, experiment, fitted):
    assert same_bits(fitted.parameters, reference["srivc.parameters"])
    # Eigen stores column-major; the reference printed the covariance in that order.
    assert same_bits(np.asarray(fitted.covariance).flatten(order="F"),
                     reference["srivc.covariance"])
    additive = ctid.additive_srivc(experiment["data"], [ctid.SubmodelOrder(2, 0)],
                                   options=ctid.RefinedIvOptions(max_iterations=30))
    assert same_bits(additive.parameters, reference["additive_srivc.parameters"])


def test_options_object_and_keywords_agree(experiment):
    by_keyword = ctid.srivc(experiment["data"], ctid.SubmodelOrder(2, 0), max_iterations=30)
    by_object = ctid.srivc(experiment["data"], ctid.SubmodelOrder(2, 0),
                           options=ctid.RefinedIvOptions(max_iterations=30))
    assert same_bits(by_keyword.parameters, by_object.parameters)
