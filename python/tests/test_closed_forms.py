"""Binding outputs against independent NumPy/SciPy computations."""

import numpy as np
import pytest
import scipy.linalg
import scipy.signal

import ctid

H = 0.05


def test_zoh_discretisation_matches_scipy():
    a = np.array([[0.0, 1.0], [-4.0, -0.8]])
    b = np.array([[0.0], [1.0]])
    zoh = ctid.discretize_zoh(a, b, H)
    phi, gamma, *_ = scipy.signal.cont2discrete((a, b, np.eye(2), np.zeros((2, 1))), H,
                                                method="zoh")
    np.testing.assert_allclose(zoh.phi, phi, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(zoh.gamma, gamma, rtol=1e-12, atol=1e-15)


def test_simulation_matches_scipy_dlsim():
    g = ctid.TransferFunction([4.0], [4.0, 0.8, 1.0])
    u = ctid.white_noise(400, 1.0, 5)
    y = ctid.simulate(g, u, H)
    # The same model as a state space (SciPy's transfer functions are descending).
    a, b, c, d = scipy.signal.tf2ss([4.0], [1.0, 0.8, 4.0])
    phi, gamma, c, d, _ = scipy.signal.cont2discrete((a, b, c, d), H, method="zoh")
    _, y_ref, _ = scipy.signal.dlsim((phi, gamma, c, d, H), u)
    np.testing.assert_allclose(y, y_ref.ravel(), atol=1e-12)


def test_welch_frf_matches_scipy_csd_and_coherence():
    g = ctid.TransferFunction([4.0], [4.0, 3.0, 1.0])
    u = ctid.white_noise(4096, 1.0, 8)
    y = ctid.simulate(g, u, H) + ctid.white_noise(4096, 0.1, 9)
    frf = ctid.welch_frf(ctid.SampledData(H, u, y), segment_length=256, overlap=0.5)
    kwargs = dict(fs=1 / H, window="hann", nperseg=256, noverlap=128, detrend=False)
    f, puu = scipy.signal.welch(u, **kwargs)
    _, puy = scipy.signal.csd(u, y, **kwargs)
    _, coherence = scipy.signal.coherence(u, y, **kwargs)
    np.testing.assert_allclose(frf.frequencies, 2 * np.pi * f[1:], rtol=1e-14)
    np.testing.assert_allclose(frf.response, (puy / puu)[1:], rtol=1e-10)
    np.testing.assert_allclose(frf.coherence, coherence[1:], rtol=1e-10)


def test_periodic_frf_matches_numpy_fft(experiment):
    data = experiment["data"]
    frf = ctid.periodic_frf(data, period_length=256, transient_periods=1)
    u = np.asarray(data.input).reshape(4, 256)[1:]
    y = np.asarray(data.output).reshape(4, 256)[1:]
    lines = np.array(frf.lines)
    ratio = np.fft.fft(y, axis=1)[:, lines] / np.fft.fft(u, axis=1)[:, lines]
    np.testing.assert_array_equal(lines, experiment["u"].lines)
    np.testing.assert_allclose(frf.response, ratio.mean(axis=0), rtol=1e-10)
    np.testing.assert_allclose(frf.variance, ratio.var(axis=0, ddof=1) / 3,
                               rtol=1e-8)


def test_srivc_recovers_noise_free_model():
    g = ctid.TransferFunction([4.0], [4.0, 0.8, 1.0])
    u = ctid.prbs(2047, register_length=11)
    data = ctid.SampledData(H, u, ctid.simulate(g, u, H))
    result = ctid.srivc(data, ctid.SubmodelOrder(2, 0))
    assert result.converged()
    # Anti-monic: 1 + 0.2 s + 0.25 s^2, gain 1.
    np.testing.assert_allclose(result.parameters, [0.2, 0.25, 1.0], rtol=1e-9)


def test_peaks_from_a_measured_frf():
    model = ctid.AdditiveModel([
        ctid.Submodel(ctid.Polynomial([1.0, 2 * 0.02 / 2.0, 1 / 4.0]), ctid.Polynomial([1.0])),
        ctid.Submodel(ctid.Polynomial([1.0, 2 * 0.03 / 12.0, 1 / 144.0]),
                      ctid.Polynomial([0.3]))])
    w = ctid.log_frequency_grid(0.5, 50.0, 3000)
    peaks = ctid.resonance_peaks(w, ctid.frequency_response(model, w), max_peaks=2)
    assert [round(p.frequency, 1) for p in peaks] == [2.0, 12.0]
    assert peaks[0].damping_ratio == pytest.approx(0.02, rel=0.1)


def test_validation_correlations_match_numpy():
    model = ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial([1.0, 0.5]), ctid.Polynomial([2.0]))])
    wrong = ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial([1.0, 0.5]), ctid.Polynomial([1.5]))])
    u = ctid.white_noise(1000, 1.0, 3)
    y = ctid.model_output(model, u, H) + ctid.white_noise(1000, 0.1, 4)
    report = ctid.validate_model(wrong, ctid.SampledData(H, u, y), max_lag=7)
    e = y - ctid.model_output(wrong, u, H)
    e, v = e - e.mean(), u - u.mean()
    full = np.correlate(e, v, mode="full") / np.sqrt(e @ e * (v @ v))  # lag k at index N-1+k
    mid = len(u) - 1
    np.testing.assert_allclose(report.cross_correlation, full[mid - 7:mid + 8], atol=1e-12)
    auto = np.correlate(e, e, mode="full")[mid + 1:mid + 8] / (e @ e)
    np.testing.assert_allclose(report.residual_autocorrelation, auto, atol=1e-12)
    assert report.max_lag == 7
    assert not report.residual_uncorrelated_with_input


def test_paper_systems_have_the_papers_poles_gains_and_pid(paper_systems):
    poles = np.concatenate([s.to_transfer_function().poles()
                            for s in paper_systems["open_loop"].submodels])
    expected = [complex(-0.25, 1.39), complex(-0.15, 3.16), complex(-0.17, 5.77),
                complex(-0.5, 9.99)]
    expected = np.concatenate([expected, np.conj(expected)])
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(expected), rtol=1e-12)
    gains = [s.b.coefficients[0] for s in paper_systems["open_loop"].submodels]
    np.testing.assert_array_equal(gains, [3.0, 0.4, 0.2, 0.05])
    np.testing.assert_array_equal(paper_systems["closed_loop"].parameters(),
                                  [0.25, 0.25, 3.0, 0.01, 0.025, 1.0])
    for z in (complex(0.3, 0.8), complex(-2.0, 0.1)):
        pid = 0.0115 + 0.00725 * z / (z - 1) + 0.00454 * (z - 1) / z
        assert abs(paper_systems["pid"](z) - pid) < 1e-15
        assert abs(paper_systems["noise_filter"](z) - (z + 0.5) / (z - 0.85)) < 1e-14
    assert paper_systems["sample_time"] == 0.05
