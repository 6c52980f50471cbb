"""Forward/feedback separation from Python (De Iuliis et al., eqs. 19-24): exact recovery
from exact alpha, beta, gamma, and the white-noise validation against SciPy."""

import numpy as np
import pytest
from scipy import signal

import ctid

F = ctid.TransferFunction([2.0, 1.0, 2.0], [3.0, 2.0, 3.0, 1.0])  # (2s^2+s+2)/(s^3+3s^2+2s+3)
H = ctid.TransferFunction([1.0, 5.0, 1.0], [2.0, 2.0, 3.0, 1.0])  # (s^2+5s+1)/(s^3+3s^2+2s+2)


def coefficients(tf):
    """Numerator and denominator scaled to a monic denominator, ascending."""
    den = np.asarray(tf.denominator.coefficients)
    return np.asarray(tf.numerator.coefficients) / den[-1], den / den[-1]


def assert_same_transfer_function(estimate, truth, tol):
    for e, t in zip(coefficients(estimate), coefficients(truth)):
        np.testing.assert_allclose(e, t, rtol=0, atol=tol * np.max(np.abs(t)))


@pytest.fixture(scope="module")
def exact_polynomials():
    loop = ctid.DelayedFeedbackLoop(F, H, 0.5)
    return loop.alpha(), loop.beta(), loop.gamma()


def test_kronecker_separation_is_exact_on_exact_polynomials(exact_polynomials):
    a, b, g = exact_polynomials
    result = ctid.separate_kronecker(a, b, g, 3, 3)
    assert result.cost < 1e-20
    assert result.starts >= 2 and len(result.candidates) == result.starts
    assert_same_transfer_function(result.forward, F, 1e-9)
    assert_same_transfer_function(result.feedback, H, 1e-9)
    assert ctid.kronecker_cost(a, b, g, F, H) == pytest.approx(0.0, abs=1e-24)


def test_gcd_separation_is_exact_and_reports_a_gap(exact_polynomials):
    a, b, g = exact_polynomials
    result = ctid.separate_approximate_gcd(a, b, g, 3, 3)
    assert_same_transfer_function(result.forward, F, 1e-9)
    assert_same_transfer_function(result.feedback, H, 1e-9)
    assert len(result.forward_singular_values) == 6
    assert result.forward_gap > 1e6 and result.feedback_gap > 1e6


def test_separation_rejects_inconsistent_orders(exact_polynomials):
    a, b, g = exact_polynomials
    with pytest.raises(ValueError):
        ctid.separate_approximate_gcd(a, b, g, 0, 3)


def test_expected_white_noise_mse_matches_scipy_impulse_response():
    # (1/N) sum_k sum_{j<=k} g_j^2 with g the impulse response of the ZOH-discretised H - F.
    h, samples = 0.005, 1000
    diff_num = np.polysub(np.polymul(H.numerator.coefficients[::-1], F.denominator.coefficients[::-1]),
                          np.polymul(F.numerator.coefficients[::-1], H.denominator.coefficients[::-1]))
    diff_den = np.polymul(H.denominator.coefficients[::-1], F.denominator.coefficients[::-1])
    # State space throughout: a degree-6 polynomial in z with poles near 1 is ill-conditioned.
    a, b, c, d = signal.tf2ss(diff_num, diff_den)
    phi, gamma, c_d, d_d, _ = signal.cont2discrete((a, b, c, d), h, method="zoh")
    g = np.empty(samples + 1)
    g[0] = d_d[0, 0]
    x = gamma[:, 0]
    for k in range(1, samples + 1):
        g[k] = c_d[0] @ x
        x = phi @ x
    reference = np.mean(np.cumsum(g**2)[1:])
    assert ctid.expected_white_noise_mse(F, H, h, samples) == pytest.approx(reference, rel=1e-8)


def test_white_noise_validation_of_a_perfect_estimate_is_zero():
    comparison = ctid.compare_white_noise_response(F, F, duration=1.0, seed=3)
    assert comparison.mse == 0.0
    assert comparison.expected_mse == pytest.approx(0.0, abs=1e-30)
    assert comparison.estimate_stable
    assert len(comparison.truth) == 200
