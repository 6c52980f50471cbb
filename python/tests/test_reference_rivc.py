"""ctid's RIVC (srivc with noise_model) against an independent NumPy/SciPy reference
(benchmarks/reference_rivc.py): the ARMA noise model is the least-squares minimiser of the
prediction errors, the innovations are D/C from rest, and on seeded Box-Jenkins records ctid and
the reference land on the same plant and noise model from the same start."""

import pathlib
import sys

import numpy as np
import pytest
from scipy import signal

import ctid

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "benchmarks"))
import reference_rivc  # noqa: E402
import reference_srivc  # noqa: E402

H = 0.05


def _arma_series(ar, ma, n, seed):
    """C/D e from rest after a burn-in of 500 samples, e white and unit variance."""
    e = np.random.default_rng(seed).standard_normal(n + 500)
    return signal.lfilter(ma, ar, e)[500:]


@pytest.mark.parametrize("ar, ma, seed", [([1.0, -0.9], [1.0, 0.5], 11),
                                          ([1.0, -1.2, 0.5], [1.0, 0.4], 12)])
def test_fit_arma_is_the_least_squares_minimiser(ar, ma, seed):
    v = _arma_series(ar, ma, 3000, seed)
    ours = ctid.fit_arma(v, len(ar) - 1, len(ma) - 1)
    d, c, e, _ = reference_rivc.arma_least_squares(v, len(ar) - 1, len(ma) - 1)
    assert ours.converged
    np.testing.assert_allclose(np.asarray(ours.ar), d, rtol=0, atol=1e-8)
    np.testing.assert_allclose(np.asarray(ours.ma), c, rtol=0, atol=1e-8)
    # The minimiser is a sensible estimate of the model that made the series.
    np.testing.assert_allclose(d, ar, atol=0.1)
    np.testing.assert_allclose(c, ma, atol=0.1)
    # The innovation variance is the mean square of the innovations (n - P - Q degrees of
    # freedom).
    dof = len(v) - (len(ar) - 1) - (len(ma) - 1)
    assert ours.innovation_variance == pytest.approx(e @ e / dof, rel=1e-9)


@pytest.mark.parametrize("order", [1, 2, 3])
def test_autoregression_is_ordinary_least_squares(order):
    # With Q = 0 the prediction error e_t = v_t + d_1 v_{t-1} + ... is linear in d: the
    # minimiser is least squares of v_t on minus its own zero-padded past.
    v = _arma_series([1.0, -1.2, 0.5], [1.0, 0.4], 3000, 20 + order)
    design = np.column_stack([-np.concatenate([np.zeros(i), v[:len(v) - i]])
                              for i in range(1, order + 1)])
    expected = np.linalg.lstsq(design, v, rcond=None)[0]
    ours = ctid.fit_arma(v, order, 0)
    np.testing.assert_allclose(np.asarray(ours.ar), np.r_[1.0, expected], rtol=0, atol=1e-10)
    np.testing.assert_array_equal(np.asarray(ours.ma), [1.0])
    d, c, _, _ = reference_rivc.arma_least_squares(v, order, 0)
    np.testing.assert_allclose(d, np.r_[1.0, expected], rtol=0, atol=1e-10)


def test_arma_innovations_are_d_over_c_from_rest():
    v = _arma_series([1.0, -1.2, 0.5], [1.0, 0.4], 1000, 31)
    model = ctid.fit_arma(v, 2, 1)
    expected = signal.lfilter(np.asarray(model.ar), np.asarray(model.ma), v)
    np.testing.assert_allclose(ctid.arma_innovations(model, v), expected, rtol=0,
                               atol=1e-12 * np.max(np.abs(expected)))


def _box_jenkins_record(denominator, numerator, noise_ar, noise_ma, snr, n, hold, seed):
    """A random binary input held `hold` samples, the plant's exact ZOH response, and ARMA
    noise C/D e scaled to the output signal-to-noise ratio `snr` (a ratio of variances)."""
    rng = np.random.default_rng(seed)
    u = np.repeat(np.where(rng.random(n // hold + 1) < 0.5, -1.0, 1.0), hold)[:n]
    x = reference_srivc.filter_bank(u, [numerator], denominator, H, "zoh")[0]
    noise = signal.lfilter(noise_ma, noise_ar, rng.standard_normal(n + 500))[500:]
    noise *= np.std(x) / np.std(noise) / np.sqrt(snr)
    return u, x + noise


CASES = {
    # second-order plant, ARMA(1, 1) noise
    "second_order_arma11": dict(denominator=[1.0, 0.5, 1.0], numerator=[2.0],
                                noise_ar=[1.0, -0.9], noise_ma=[1.0, 0.5], snr=7.0, n=2000,
                                hold=4, seed=41, start=([1.0, 0.6, 1.1], [1.8])),
    # first-order plant with a zero, AR(2) noise
    "first_order_zero_ar2": dict(denominator=[1.0, 0.8], numerator=[1.0, 0.3],
                                 noise_ar=[1.0, -1.2, 0.5], noise_ma=[1.0], snr=5.0, n=2000,
                                 hold=3, seed=42, start=([1.0, 0.7], [1.1, 0.2])),
    # the second-order plant again, ARMA(2, 1) noise on another record
    "second_order_arma21": dict(denominator=[1.0, 0.5, 1.0], numerator=[2.0],
                                noise_ar=[1.0, -1.2, 0.5], noise_ma=[1.0, 0.4], snr=8.0,
                                n=2000, hold=5, seed=43, start=([1.0, 0.45, 0.9], [2.2])),
}


def _ctid_rivc(u, y, case, noise_model):
    denominator, numerator = case["start"]
    n, m = len(denominator) - 1, len(numerator) - 1
    order = ctid.SubmodelOrder(n, m)
    start = ctid.AdditiveModel.from_parameters([order], list(denominator[1:]) + list(numerator))
    return ctid.srivc(ctid.SampledData(H, u, y), order, noise_model=noise_model,
                      initial_model=start, tolerance=1e-13, max_iterations=500,
                      compute_covariance=False)


@pytest.mark.parametrize("name", sorted(CASES))
def test_rivc_reaches_the_reference_stationary_point(name):
    case = CASES[name]
    u, y = _box_jenkins_record(case["denominator"], case["numerator"], case["noise_ar"],
                               case["noise_ma"], case["snr"], case["n"], case["hold"],
                               case["seed"])
    p, q = len(case["noise_ar"]) - 1, len(case["noise_ma"]) - 1
    ours = _ctid_rivc(u, y, case, ctid.NoiseModelOrders(ar=p, ma=q))
    theirs = reference_rivc.rivc(u, y, H, *case["start"], p, q, tolerance=1e-12)
    assert ours.termination == ctid.Termination.converged
    assert theirs["converged"] and theirs["srivc"]["converged"]
    parameters = np.asarray(ours.parameters)
    np.testing.assert_allclose(parameters, theirs["parameters"], rtol=1e-8)
    np.testing.assert_allclose(np.asarray(ours.noise_model.ar), theirs["ar"], rtol=0, atol=1e-7)
    np.testing.assert_allclose(np.asarray(ours.noise_model.ma), theirs["ma"], rtol=0, atol=1e-7)
    # The noise model moves the estimate away from SRIVC's by far more than the agreement
    # asked above, so that agreement is the prefiltered iteration's, not SRIVC's again.
    first = theirs["srivc"]["submodels"][0]
    srivc = np.r_[first["denominator_ascending"][1:], first["numerator_ascending"]]
    assert np.max(np.abs(parameters - srivc) / np.abs(srivc)) > 1e-5
    # ctid's estimate is a fixed point of the reference's own step: one pass from it moves
    # nothing beyond rounding.
    n = len(case["denominator"]) - 1
    a, b, d, c = reference_rivc.rivc_step(u, y, H, parameters[:n], parameters[n:], p, q)
    np.testing.assert_allclose(np.r_[a, b], parameters, rtol=1e-9)
    # Both are near the system that made the data (a loose sanity bound, not the comparison).
    np.testing.assert_allclose(parameters, np.r_[case["denominator"][1:], case["numerator"]],
                               rtol=0.15, atol=0.05)


def test_white_noise_model_is_plain_srivc():
    # With D = C = 1 the prefilter is the identity and RIVC's step is SRIVC's.
    case = CASES["second_order_arma11"]
    u, y = _box_jenkins_record(case["denominator"], case["numerator"], case["noise_ar"],
                               case["noise_ma"], case["snr"], case["n"], case["hold"], 51)
    white = _ctid_rivc(u, y, case, "0,0")
    denominator, numerator = case["start"]
    start = ctid.AdditiveModel.from_parameters([ctid.SubmodelOrder(2, 0)],
                                               list(denominator[1:]) + list(numerator))
    plain = ctid.srivc(ctid.SampledData(H, u, y), ctid.SubmodelOrder(2, 0), initial_model=start,
                       tolerance=1e-13, max_iterations=500, compute_covariance=False)
    assert white.termination == ctid.Termination.converged
    assert plain.termination == ctid.Termination.converged
    np.testing.assert_array_equal(np.asarray(white.noise_model.ar), [1.0])
    np.testing.assert_array_equal(np.asarray(white.noise_model.ma), [1.0])
    np.testing.assert_allclose(np.asarray(white.parameters), np.asarray(plain.parameters),
                               rtol=1e-9)
    # The reference agrees with itself the same way.
    theirs = reference_rivc.rivc(u, y, H, denominator, numerator, 0, 0, tolerance=1e-12)
    srivc = theirs["srivc"]["submodels"][0]
    np.testing.assert_allclose(theirs["parameters"],
                               np.r_[srivc["denominator_ascending"][1:],
                                     srivc["numerator_ascending"]], rtol=1e-9)


def test_noise_model_words_are_the_orders():
    case = CASES["second_order_arma11"]
    u, y = _box_jenkins_record(case["denominator"], case["numerator"], case["noise_ar"],
                               case["noise_ma"], case["snr"], 1000, case["hold"], 52)
    by_orders = _ctid_rivc(u, y, case, ctid.NoiseModelOrders(ar=1, ma=1))
    by_words = _ctid_rivc(u, y, case, "1,1")
    np.testing.assert_array_equal(np.asarray(by_words.parameters),
                                  np.asarray(by_orders.parameters))
    np.testing.assert_array_equal(np.asarray(by_words.noise_model.ma),
                                  np.asarray(by_orders.noise_model.ma))
