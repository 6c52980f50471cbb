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


def informative_record(delay, noise_sd=0.0, seed=0):
    """30 s of a smooth multisine (8 harmonics of a 15-s period), continued linearly between
    samples of 50 ms, through the loop with feedback delay `delay`."""
    h = 0.05
    rng = np.random.default_rng(3)
    phases = rng.uniform(0, 2 * np.pi, 8)
    t = h * np.arange(601)
    u = sum(np.cos(2 * np.pi * j * t / 15.0 + phases[j - 1]) for j in range(1, 9)) / 2.0
    loop = ctid.DelayedFeedbackLoop(F, H, delay)
    y = ctid.simulate_delayed(ctid.to_delayed_state_space(loop), u, h, ctid.Hold.first_order_hold,
                              substeps=4)
    y = y + np.random.default_rng(seed).normal(0.0, noise_sd, y.size) if noise_sd else y
    return ctid.SampledData(h, u, y)


def test_pipeline_recovers_f_and_h_at_a_fractional_delay():
    data = informative_record(0.523)
    result = ctid.identify_delayed_feedback(data, 3, 3, 0.523)
    assert result.output_rms < 1e-8, result.message
    assert_same_transfer_function(result.loop.forward, F, 1e-5)
    assert_same_transfer_function(result.loop.feedback, H, 1e-5)
    assert any(c.source.startswith("structured iv") for c in result.candidates)
    with pytest.raises(ValueError):
        ctid.identify_delayed_feedback(data, 3, 3, 0.523, iv_filter_poles=[-1.0])


def test_structured_iv_improves_a_perturbed_start():
    data = informative_record(0.5)
    start = ctid.DelayedFeedbackLoop(
        ctid.TransferFunction([2.1, 0.95, 2.0], [3.1, 2.05, 2.9, 1.0]),
        ctid.TransferFunction([1.05, 4.8, 1.0], [2.1, 1.9, 3.05, 1.0]), 0.5)
    regressors = ctid.FeedbackRegressorOptions(filter=ctid.RegressorFilter.linear_integral_filter,
                                               filter_pole=1.0, initial_condition_terms=True)
    result = ctid.estimate_structured_step1_iv(data, start, regressors, iterations=4)
    history = result.output_rms_history
    assert history[0] > 1e-3
    assert result.output_rms == min(h for h in history if np.isfinite(h))
    assert result.output_rms < 1e-2 * history[0], result.message
    with pytest.raises(TypeError):
        ctid.estimate_structured_step1_iv(data, start, regressors, iteration=4)


def test_a_failed_fit_is_a_result_not_a_value_error():
    # An all-zero record: step 1 is singular. That is an outcome of the fit, not bad input.
    zero = ctid.SampledData(0.05, np.zeros(200), np.zeros(200))
    regression = ctid.build_feedback_regression(zero, 3, 3, 0.5)
    step1 = ctid.estimate_closed_loop_batch(regression)
    assert step1.termination == ctid.Termination.singular_equations
    assert not step1.converged()
    assert "singular regressor" in step1.message
    result = ctid.identify_delayed_feedback(zero, 2, 1, 0.5, iv_filter_poles=[])
    assert result.step1.termination == ctid.Termination.singular_equations
    assert result.termination != ctid.Termination.not_run
    assert result.brief_report()


def test_identification_options_are_reachable_from_python():
    options = ctid.FeedbackIdentificationOptions()
    assert options.fields[0] == "regressors"
    assert options.output_error.hold == ctid.Hold.first_order_hold
    assert options.step1 == ctid.Step1Method.batch
    assert options.separation == ctid.SeparationMethod.both
    assert options.regressors.filter == ctid.RegressorFilter.linear_integral_filter
    assert options.iv.hold is None
    assert list(options.iv_filter_poles) == [0.3, 0.5, 1.0, 2.0]
    options.output_error.substeps = 0
    with pytest.raises(ValueError,
                       match=r"FeedbackIdentificationOptions\.output_error\.substeps is 0; "
                             r"it must be >= 1"):
        options.validate()
    options.output_error.substeps = 4
    options.iv.hold = ctid.Hold.zero_order_hold
    with pytest.raises(ValueError, match=r"iv\.hold is zero_order_hold"):
        options.validate()
    scan = ctid.DelayIdentificationOptions()
    assert scan.scan.criterion == ctid.DelayCriterion.refined_output_error
    for enum in (ctid.RegressorFilter, ctid.LeastSquaresSolver, ctid.Regularisation,
                 ctid.DelayCriterion, ctid.Step1Method, ctid.SeparationMethod):
        assert all(name == name.lower() for name in enum.__members__)


def test_identification_takes_options_or_keywords_alike():
    data = informative_record(0.5)
    options = ctid.FeedbackIdentificationOptions(iv_filter_poles=[0.5])
    by_object = ctid.identify_delayed_feedback(data, 3, 3, 0.5, options=options)
    by_keywords = ctid.identify_delayed_feedback(data, 3, 3, 0.5, iv_filter_poles=[0.5])
    assert by_object.output_rms == by_keywords.output_rms
    assert by_object.termination == ctid.Termination.converged
    assert by_object.best_candidate is not None
    with pytest.raises(TypeError):
        ctid.identify_delayed_feedback(data, 3, 3, 0.5, options=options, refine=False)
    with pytest.raises(TypeError):
        ctid.identify_delayed_feedback(data, 3, 3, 0.5, holdd=ctid.Hold.zero_order_hold)
