"""Output-only modal analysis from Python: ctid.oma on a seeded simulated chain finds its modes,
the oma_result document reads back, and an independent NumPy SSI-cov (direct lag sums, one
least-squares A per order) gives the same poles on the same record."""

import numpy as np
import pytest

import ctid

H = 0.005


def _chain(n=3):
    """Continuous state matrix of a mass-spring chain with Rayleigh damping, its exact discrete
    one, the force-to-state map (ZOH) and the true modes (f [Hz], zeta)."""
    k = np.zeros((n, n))
    for i in range(n):
        k[i, i] = 2.0e4 * (2.0 if i + 1 < n else 1.0)
        if i + 1 < n:
            k[i, i + 1] = k[i + 1, i] = -2.0e4
    m = np.diag(1.0 + 0.25 * np.arange(n))
    minv = np.linalg.inv(m)
    c = 0.5 * m + 1e-4 * k
    ac = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ k, -minv @ c]])
    lam, v = np.linalg.eig(ac)
    ad = (v @ np.diag(np.exp(lam * H)) @ np.linalg.inv(v)).real
    b = np.vstack([np.zeros((n, n)), minv])
    gamma = np.linalg.solve(ac, (ad - np.eye(2 * n)) @ b)
    upper = lam[lam.imag > 0]
    modes = sorted((abs(s) / (2 * np.pi), -s.real / abs(s)) for s in upper)
    return ad, gamma, modes


def _record(seed, samples=30000, n=3):
    ad, gamma, modes = _chain(n)
    rng = np.random.default_rng(seed)
    x = np.zeros(2 * n)
    y = np.empty((samples, n))
    for k in range(-2000, samples):
        if k >= 0:
            y[k] = x[:n]
        x = ad @ x + gamma @ rng.standard_normal(n)
    y += 0.05 * y.std(axis=0) * rng.standard_normal(y.shape)
    return y, modes


def _numpy_poles(y, p, order, max_damping=0.2):
    """SSI-cov written independently: lag sums, Hankel, SVD, A by least squares."""
    y = y - y.mean(axis=0)
    n, l = y.shape
    r = [y[i:].T @ y[:n - i] / n for i in range(1, 2 * p)]
    hankel = np.block([[r[i + j] for j in range(p)] for i in range(p)])
    u, s, _ = np.linalg.svd(hankel)
    o = u[:, :order] * np.sqrt(s[:order])
    a = np.linalg.lstsq(o[:-l], o[l:], rcond=None)[0]
    lam = np.linalg.eigvals(a)
    lam = lam[(lam.imag > 0) & (abs(lam) < 1)]
    s_c = np.log(lam) / H
    zeta = -s_c.real / abs(s_c)
    keep = (zeta > 0) & (zeta < max_damping)
    return np.sort(abs(s_c[keep]) / (2 * np.pi))


def test_oma_finds_the_chain_modes_within_their_standard_errors():
    y, modes = _record(1)
    result = ctid.oma(y, H, max_order=20, block_rows=20)
    assert result.verdict.usable, result.verdict.summary()
    assert len(result.modes) == len(modes)
    for mode, (f, zeta) in zip(result.modes, modes):
        assert abs(mode.frequency_hz - f) < 4 * mode.frequency_hz_std
        assert abs(mode.damping_ratio - zeta) < 4 * mode.damping_ratio_std
        assert len(mode.shape_real) == 3 and max(np.abs(mode.shape_real)) == pytest.approx(1.0)


def test_oma_result_reads_back(tmp_path):
    y, _ = _record(2, samples=10000)
    result = ctid.oma(y, H, max_order=12, channel_names=["a", "b", "c"])
    ctid.write_result(tmp_path / "oma.json", result)
    back = ctid.read_result(tmp_path / "oma.json")
    assert isinstance(back, ctid.OmaResult)
    assert back.channels == ["a", "b", "c"]
    assert ctid.result_to_json(back) == ctid.result_to_json(result)


def test_numpy_ssi_cov_gives_the_same_poles():
    y, _ = _record(3, samples=8000)
    p, order = 12, 6
    result = ctid.oma(y, H, max_order=order, block_rows=p, uncertainty_blocks=0)
    ours = np.sort([q.frequency_hz for q in result.stabilisation if q.order == order])
    reference = _numpy_poles(y, p, order)
    assert ours.shape == reference.shape
    np.testing.assert_allclose(ours, reference, rtol=1e-8)


def test_one_channel_is_refused():
    y, _ = _record(4, samples=2000)
    with pytest.raises(ctid.InvalidArgument, match="needs at least 2"):
        ctid.oma(y[:, :1], H)
