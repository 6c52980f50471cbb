"""The output-error polish through ctid.identify (polish=True, decision 0057) against an
independent reference: scipy's least_squares on the same record, the model simulated by
scipy's exact ZOH discretisation, started from the same IV estimate, must reach the same
stationary point, and its Gauss-Newton standard errors must match ctid's."""

import numpy as np
import pytest
from scipy import optimize, signal

import ctid

H = 0.05
SAMPLES = 1500


def _simulate(theta, u):
    """2-pole 1-zero model theta = [a1, a2, b0, b1] (ascending A = 1 + a1 p + a2 p^2), ZOH."""
    a1, a2, b0, b1 = theta
    b, a, _ = signal.cont2discrete(([b1, b0], [a2, a1, 1.0]), H, method="zoh")
    return signal.lfilter(np.ravel(b), a, u)


def _record(seed):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(SAMPLES)
    y = _simulate([0.4, 0.25, 2.0, 0.6], u) + 0.1 * rng.standard_normal(SAMPLES)
    return u, y


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_polish_reaches_the_least_squares_optimum_of_an_independent_solver(seed):
    u, y = _record(seed)
    result = ctid.identify(ctid.SampledData(H, u, y), ctid.ModelStructure.unfactored(2, 1),
                           polish=True,
                           polish_options=ctid.OutputErrorPolishOptions(estimate_delay=False))
    polish = result.polish
    assert polish is not None and polish.converged(), polish.message
    assert polish.criterion == "output error"
    start = np.asarray(result.estimate.parameters)
    reference = optimize.least_squares(lambda t: y - _simulate(t, u), start, xtol=1e-15,
                                       ftol=1e-15, gtol=1e-15, method="lm")
    np.testing.assert_allclose(np.asarray(polish.parameters), reference.x, rtol=1e-7)
    assert polish.cost <= polish.start_cost
    assert polish.cost == pytest.approx(np.mean(reference.fun ** 2), rel=1e-9)
    jac = reference.jac
    sigma2 = np.sum(reference.fun ** 2) / (SAMPLES - 4)
    se = np.sqrt(np.diag(sigma2 * np.linalg.inv(jac.T @ jac)))
    np.testing.assert_allclose(np.asarray(polish.standard_errors), se, rtol=1e-3)


def test_polish_is_reported_beside_the_iv_estimate():
    u, y = _record(4)
    plain = ctid.identify(ctid.SampledData(H, u, y), ctid.ModelStructure.unfactored(2, 1))
    result = ctid.identify(ctid.SampledData(H, u, y), ctid.ModelStructure.unfactored(2, 1),
                           polish=True)
    assert plain.polish is None
    np.testing.assert_array_equal(np.asarray(result.estimate.parameters),
                                  np.asarray(plain.estimate.parameters))
    assert len(result.polish.parameters) == 5  # beta, then the delay
    assert result.polish.parameters[4] >= 0.0
    assert not result.restarted_from_polish


def test_a_known_dc_gain_and_a_held_coefficient_hold_in_the_iv_fit_and_the_polish():
    u, y = _record(5)
    setting = ctid.CoefficientSetting(name="theta1.a2", fixed=0.26)
    constraints = ctid.CoefficientConstraints(dc_gain=1.95, coefficients=[setting])
    result = ctid.identify(ctid.SampledData(H, u, y), ctid.ModelStructure.unfactored(2, 1),
                           constraints=constraints,
                           polish_options=ctid.OutputErrorPolishOptions(estimate_delay=False))
    for fit in (result.estimate, result.polish):  # the constraints imply the polish
        assert fit.parameters[2] == 1.95 and fit.parameters[1] == 0.26
        assert fit.standard_errors[1] == 0.0 and fit.standard_errors[2] == 0.0
    assert result.estimate.converged(), result.estimate.message
    assert result.polish.held_parameters == ["theta1.a2", "theta1.b0"]
    # The held IV estimate is the IV estimate that knows them: an independent solve of its
    # stationary point is checked in C++ (tests/refined_iv); here, its output error is no
    # better than the free fit's.
    free = ctid.identify(ctid.SampledData(H, u, y), ctid.ModelStructure.unfactored(2, 1))
    assert result.estimate.mean_squared_error >= free.estimate.mean_squared_error * (1 - 1e-12)
    with pytest.raises(ValueError, match="'theta9.a1' is not in the model"):
        ctid.identify(ctid.SampledData(H, u, y), ctid.ModelStructure.unfactored(2, 1),
                      constraints=ctid.CoefficientConstraints(
                          coefficients=[ctid.CoefficientSetting(name="theta9.a1", fixed=1.0)]))


def test_a_bound_acts_in_the_iv_fit_as_holding_the_coefficient_there():
    """Decision 0058: b0 = 2 bounded above by 1.6 ends at 1.6, the fit of b0 held at 1.6."""
    u, y = _record(6)
    data = ctid.SampledData(H, u, y)
    structure = ctid.ModelStructure.unfactored(2, 1)
    no_delay = ctid.OutputErrorPolishOptions(estimate_delay=False)

    def fit(setting):
        return ctid.identify(data, structure, polish_options=no_delay,
                             constraints=ctid.CoefficientConstraints(coefficients=[setting]))

    bounded = fit(ctid.CoefficientSetting(name="theta1.b0", upper=1.6))
    held = fit(ctid.CoefficientSetting(name="theta1.b0", fixed=1.6))
    assert bounded.estimate.parameters[2] == 1.6
    np.testing.assert_allclose(bounded.estimate.parameters, held.estimate.parameters,
                               rtol=1e-12)
    def at_bounds(fitted):  # enforced stability may be listed too
        return [n for n in fitted.estimate.verdict.active_constraints if "bound" in n]

    assert at_bounds(bounded) == ["theta1.b0 is at its bound 1.6"]
    assert at_bounds(held) == []
    assert "theta1.b0 is at a bound" in bounded.polish.verdict.active_constraints
