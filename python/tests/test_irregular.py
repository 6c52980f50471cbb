"""ctid.srivc_irregular: SRIVC on irregular time stamps (docs/decisions/0034) from Python, exact
on a noise-free jittered record with gaps and duplicate stamps, and one clear error for stamps
that go back."""

import numpy as np
import pytest

import ctid

TRUTH = [0.4, 0.25, 2.0, 0.3]  # (2 + 0.3 p) / (1 + 0.4 p + 0.25 p^2)


def jittered_record(seed=4, n=1000):
    expm = pytest.importorskip("scipy.linalg").expm
    rng = np.random.default_rng(seed)
    stamps = []
    k = 0
    while len(stamps) < n:
        if k == 0 or rng.uniform() >= 0.01:
            stamps.append(0.05 * k + 0.015 * rng.uniform(-1.0, 1.0))
        k += 1
    t = np.array(stamps)
    t[100] = t[99]  # a duplicate stamp
    u = rng.standard_normal(n)
    a = np.array([[0.0, 1.0], [-4.0, -1.6]])
    x = np.zeros(2)
    y = np.empty(n)
    for j in range(n):
        if j > 0 and t[j] > t[j - 1]:
            m = np.zeros((3, 3))
            m[:2, :2] = a
            m[1, 2] = 1.0
            e = expm(m * (t[j] - t[j - 1]))
            x = e[:2, :2] @ x + e[:2, 2] * u[j - 1]
        y[j] = 8.0 * x[0] + 1.2 * x[1]
    return t, u, y


def test_noise_free_jittered_record_is_fitted_exactly():
    t, u, y = jittered_record()
    result = ctid.srivc_irregular(t, u, y, ctid.SubmodelOrder(2, 1),
                                  input_hold=ctid.Hold.zero_order_hold, compute_covariance=False)
    assert result.converged(), result.brief_report()
    assert np.max(np.abs(np.asarray(result.parameters) - TRUTH) / np.abs(TRUTH)) < 1e-8
    assert result.verdict.usable


def test_a_stamp_that_goes_back_is_refused():
    t, u, y = jittered_record(n=200)
    t[50] = t[48]
    with pytest.raises(ValueError, match="time stamp 50 .* goes back"):
        ctid.srivc_irregular(t, u, y, ctid.SubmodelOrder(2, 1))


# (2 + 0.3 s) / (1 + 0.4 s + 0.25 s^2), the system jittered_record simulates.
def true_model():
    return ctid.TransferFunction([2.0, 0.3], [1.0, 0.4, 0.25])


def test_simulate_on_stamps_is_the_exact_response_at_the_stamps():
    t, u, y = jittered_record()
    simulated = ctid.simulate_on_stamps(true_model(), t, u, ctid.Hold.zero_order_hold)
    assert np.max(np.abs(simulated - y)) < 1e-10 * np.max(np.abs(y))


def test_simulate_on_uniform_stamps_is_simulate():
    u = np.random.default_rng(2).standard_normal(300)
    t = 0.5 + 0.05 * np.arange(300)
    expected = ctid.simulate(true_model(), u, 0.05)
    assert np.max(np.abs(ctid.simulate_on_stamps(true_model(), t, u) - expected)) < 1e-12


def test_validate_on_stamps_scores_a_noise_free_record_at_a_hundred_percent():
    t, u, y = jittered_record()
    model = ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial([1.0, 0.4, 0.25]),
                                              ctid.Polynomial([2.0, 0.3]))])
    report = ctid.validate_on_stamps(model, t, u, y, ctid.Hold.zero_order_hold)
    assert abs(report.fit_percent - 100.0) < 1e-8
    assert report.window_samples == len(t)
    with pytest.raises(ValueError, match="time stamp 7 .* goes back before stamp 6"):
        t[7] = t[5] - 0.01
        ctid.validate_on_stamps(model, t, u, y)
