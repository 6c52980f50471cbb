"""Recursive SRIVC from Python: the binding runs, options as keywords, the documented shapes,
and the free function equals the estimator class stepped sample by sample from Python."""

import numpy as np
import pytest

import ctid

H = 0.05
ORDER = ctid.SubmodelOrder(n=2, m=1)


def model(theta):
    a1, a2, b0, b1 = theta
    return ctid.TransferFunction(ctid.Polynomial([b0, b1]), ctid.Polynomial([1.0, a1, a2]))


TRUTH = np.array([0.3, 0.25, 1.0, 0.5])


def record(n=600, noise=0.1, seed=5):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    y = ctid.simulate(model(TRUTH), u, H) + noise * rng.standard_normal(n)
    return ctid.SampledData(H, u, y)


def test_keywords_shapes_and_verdict():
    data = record()
    r = ctid.recursive_srivc(data, ORDER, model(1.1 * TRUTH), forgetting_factor=0.995,
                             covariance_history=ctid.CovarianceHistory.full)
    n, np_ = data.size(), 4
    assert r.times.shape == (n,)
    assert r.parameters.shape == (n, np_)
    assert r.standard_errors.shape == (n, np_)
    assert r.covariance.shape == (n, np_ * np_)
    assert r.noise_variance.shape == (n,)
    assert r.final_covariance.shape == (np_, np_)
    # Row k of the full history is the column-major covariance of sample k.
    np.testing.assert_allclose(r.covariance[-1].reshape(np_, np_, order="F"),
                               r.final_covariance, rtol=1e-12)
    np.testing.assert_allclose(r.standard_errors[-1], np.sqrt(np.diag(r.final_covariance)))
    assert r.stable and r.finite and r.skipped_updates == 0
    assert np.max(np.abs(r.parameters[-1] - TRUTH) / TRUTH) < 0.1
    diagonal = ctid.recursive_srivc(data, ORDER, model(1.1 * TRUTH), forgetting_factor=0.995)
    assert diagonal.covariance.shape == (n, np_)
    np.testing.assert_allclose(diagonal.parameters, r.parameters)


def test_options_object_and_bad_keywords():
    options = ctid.RecursiveSrivcOptions(refresh_interval=5, random_walk=[1e-6])
    assert options.refresh_interval == 5
    data = record()
    r = ctid.recursive_srivc(data, ORDER, model(TRUTH), options)
    assert r.parameters.shape == (data.size(), 4)
    with pytest.raises(TypeError):
        ctid.recursive_srivc(data, ORDER, model(TRUTH), no_such_option=1)
    with pytest.raises(ValueError, match="forgetting_factor is 1.5; it must be in"):
        ctid.recursive_srivc(data, ORDER, model(TRUTH), forgetting_factor=1.5)


def test_free_function_equals_the_class_stepped_from_python():
    data = record(n=400)
    start = model(0.9 * TRUTH)
    r = ctid.recursive_srivc(data, ORDER, start, forgetting_factor=0.99, warmup_samples=50)
    estimator = ctid.RecursiveSrivc(ORDER, H, start, forgetting_factor=0.99, warmup_samples=50)
    for k, (u, y) in enumerate(zip(data.input, data.output)):
        estimator.update(u, y)
        if k in (0, 49, 200):
            np.testing.assert_array_equal(estimator.parameters, r.parameters[k])
    assert estimator.steps == data.size()
    np.testing.assert_array_equal(estimator.parameters, r.parameters[-1])
    np.testing.assert_array_equal(estimator.covariance, r.final_covariance)
    np.testing.assert_allclose(estimator.model().denominator.coefficients,
                               r.model.denominator.coefficients)
