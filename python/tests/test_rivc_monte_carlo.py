"""Seeded Monte Carlo of RIVC (refined IV with an ARMA noise model, decision 0056) on
Box-Jenkins records: with strongly coloured noise its mean squared error is near the
Cramer-Rao bound and well below SRIVC's, its standard errors match the spread, and with white
noise it does what SRIVC does. The bound is computed here, independently of ctid's estimator:
sigma_e^2 (Psi_f' Psi_f)^-1 with Psi the output's exact ZOH sensitivity to the parameters
(scipy's discretisation) filtered by D/C, at the true plant and noise model."""

import numpy as np
import pytest
from scipy import signal

import ctid

H = 0.05
SAMPLES = 2000
RUNS = 200
A = np.array([1.0, 0.5, 1.0])  # 1 + 0.5 p + p^2 (ascending)
B = np.array([2.0])
TRUE = np.array([0.5, 1.0, 2.0])  # [a_1, a_2, b_0]
MODEL = ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial(list(A)), ctid.Polynomial(list(B)))])
ORDER = ctid.SubmodelOrder(2, 0)


def _input(rng):
    # A random binary signal held for 5 samples.
    return np.repeat(np.sign(rng.standard_normal(SAMPLES // 5 + 1)), 5)[:SAMPLES]


def _zoh(numerator_ascending, denominator_ascending, u):
    b, a, _ = signal.cont2discrete(
        (np.asarray(numerator_ascending)[::-1], np.asarray(denominator_ascending)[::-1]), H,
        method="zoh")
    return signal.lfilter(np.ravel(b), a, u)


def _cramer_rao(u, d, c, sigma_e):
    """sigma_e^2 (Psi_f' Psi_f)^-1 at the true parameters: dx/da_k = -p^k B / A^2 u,
    dx/db_0 = 1/A u, each filtered by D/C."""
    a2 = np.polymul(A[::-1], A[::-1])[::-1]  # A^2, ascending
    columns = [-_zoh(np.r_[np.zeros(k), B], a2, u) for k in (1, 2)]
    columns.append(_zoh([1.0], A, u))
    psi = np.column_stack([signal.lfilter(d, c, col) for col in columns])
    return sigma_e ** 2 * np.linalg.inv(psi.T @ psi)


def _campaign(d, c, orders, seed0):
    srivc, rivc, se, bound = [], [], [], []
    for seed in range(seed0, seed0 + RUNS):
        rng = np.random.default_rng(seed)
        u = _input(rng)
        x = ctid.simulate(MODEL, u, H)
        sigma_e = 1.0
        v = signal.lfilter(c, d, rng.standard_normal(SAMPLES))
        sigma_e = np.std(x) / np.std(v) / 3.0  # output SNR (std) of about 3
        y = x + sigma_e * v
        data = ctid.SampledData(H, u, y)
        plain = ctid.srivc(data, ORDER)
        refined = ctid.srivc(data, ORDER, noise_model=orders)
        assert refined.converged(), refined.message
        srivc.append(plain.parameters)
        rivc.append(refined.parameters)
        se.append(refined.standard_errors)
        bound.append(np.diag(_cramer_rao(u, d, c, sigma_e)))
    return (np.array(srivc), np.array(rivc), np.array(se), np.array(bound))


def test_rivc_is_efficient_under_strongly_coloured_noise():
    # Noise D v = e with D = 1 - 0.99 q^-1: drifting, low-frequency noise.
    d, c = [1.0, -0.99], [1.0]
    srivc, rivc, se, bound = _campaign(d, c, ctid.NoiseModelOrders(ar=1, ma=0), 1000)
    mse_rivc = ((rivc - TRUE) ** 2).mean(axis=0)
    mse_srivc = ((srivc - TRUE) ** 2).mean(axis=0)
    crb = bound.mean(axis=0)
    # Within 25 % of the bound, parameter by parameter.
    assert np.all(mse_rivc <= 1.25 * crb), (mse_rivc, crb)
    assert np.all(mse_rivc >= 0.75 * crb), (mse_rivc, crb)
    # At least 30 % below SRIVC's in total (each relative to its parameter's size).
    relative = lambda mse: np.sum(mse / TRUE ** 2)  # noqa: E731
    assert relative(mse_rivc) <= 0.7 * relative(mse_srivc), (mse_rivc, mse_srivc)
    # Reported standard errors within +-20 % of the spread.
    ratio = se.mean(axis=0) / rivc.std(axis=0)
    assert np.all(np.abs(ratio - 1.0) <= 0.2), ratio


def test_rivc_with_an_arma_noise_model_has_calibrated_errors():
    d, c = [1.0, -0.98], [1.0, 0.5]
    srivc, rivc, se, bound = _campaign(d, c, ctid.NoiseModelOrders(ar=1, ma=1), 3000)
    mse_rivc = ((rivc - TRUE) ** 2).mean(axis=0)
    assert np.all(mse_rivc <= 1.25 * bound.mean(axis=0)), (mse_rivc, bound.mean(axis=0))
    ratio = se.mean(axis=0) / rivc.std(axis=0)
    assert np.all(np.abs(ratio - 1.0) <= 0.2), ratio
    mse_srivc = ((srivc - TRUE) ** 2).mean(axis=0)
    assert np.sum(mse_rivc / TRUE ** 2) < np.sum(mse_srivc / TRUE ** 2)


def test_rivc_matches_srivc_under_white_noise():
    # The noise model chosen by the criterion on white noise; the two estimators then agree in
    # accuracy (the same records, so their errors are strongly correlated).
    srivc, rivc, _, bound = _campaign([1.0], [1.0], ctid.NoiseModelOrders(automatic=True), 5000)
    mse_rivc = ((rivc - TRUE) ** 2).mean(axis=0)
    mse_srivc = ((srivc - TRUE) ** 2).mean(axis=0)
    assert np.all(np.abs(mse_rivc / mse_srivc - 1.0) <= 0.1), (mse_rivc, mse_srivc)
    assert np.all(mse_rivc <= 1.25 * bound.mean(axis=0))


@pytest.mark.parametrize("word, ar, ma, automatic", [("2,1", 2, 1, False), ("auto", 1, 0, True)])
def test_noise_model_words(word, ar, ma, automatic):
    orders = ctid.NoiseModelOrders(word)
    assert (orders.ar, orders.ma, orders.automatic) == (ar, ma, automatic)


@pytest.mark.parametrize("word", ["2", "a,b", "2,1,0", "21,0", "-1,0", ""])
def test_bad_noise_model_words_are_refused_by_name(word):
    with pytest.raises(ValueError, match="is not P,Q"):
        ctid.NoiseModelOrders(word)


def test_undermodelling_is_named_on_the_dryer():
    # The shipped hair dryer (DaISy, data/daisy_dryer_ljung), samples 1-500 without their means.
    import pathlib
    root = pathlib.Path(__file__).resolve().parents[2]
    data = ctid.read_csv(str(root / "data/daisy_dryer_ljung/dryer.csv"), time="t_s_assumed_0.08",
                         input="u_heater_voltage", output="y_outlet_temperature")
    data = data.preprocess(end_row=500, detrend=ctid.Detrend.mean).data

    def fit(poles, zeros, delay):
        return ctid.srivc(data, ctid.SubmodelOrder(poles, zeros), input_delay_samples=delay,
                          noise_model="2,2")

    too_simple = fit(2, 0, 3)
    assert not too_simple.verdict.usable
    assert any("the plant structure is likely too simple" in r for r in too_simple.verdict.reasons)
    assert too_simple.fit_percent < too_simple.start_fit_percent - 1.0
    adequate = fit(2, 1, 2)
    assert adequate.verdict.usable, adequate.verdict.summary()
    assert abs(adequate.fit_percent - adequate.start_fit_percent) < 1.0
