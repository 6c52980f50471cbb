"""Output-only modal analysis from Python: ctid.oma on a seeded simulated chain finds its modes,
the oma_result document reads back, and an independent NumPy SSI-cov (direct lag sums, one
least-squares A per order) and SSI-data (QR of the data Hankel matrix's transpose) give the
same poles on the same record."""

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


def _frequencies_from_factor(u, s, order, l, max_damping):
    """What both independent SSIs share after their SVD: O = U_n S_n^(1/2), A by least squares
    on O's shifted rows, the continuous poles' natural frequencies [Hz], sorted, of the ones
    with a damping ratio in (0, max_damping)."""
    o = u[:, :order] * np.sqrt(s[:order])
    a = np.linalg.lstsq(o[:-l], o[l:], rcond=None)[0]
    lam = np.linalg.eigvals(a)
    lam = lam[(lam.imag > 0) & (abs(lam) < 1)]
    s_c = np.log(lam) / H
    zeta = -s_c.real / abs(s_c)
    keep = (zeta > 0) & (zeta < max_damping)
    return np.sort(abs(s_c[keep]) / (2 * np.pi))


def _numpy_poles(y, p, order, max_damping=0.2):
    """SSI-cov written independently: lag sums, Hankel, SVD, A by least squares."""
    y = y - y.mean(axis=0)
    n, l = y.shape
    r = [y[i:].T @ y[:n - i] / n for i in range(1, 2 * p)]
    hankel = np.block([[r[i + j] for j in range(p)] for i in range(p)])
    u, s, _ = np.linalg.svd(hankel)
    return _frequencies_from_factor(u, s, order, l, max_damping)


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


def _scipy_first_singular_value(y, length):
    """s1(f) of the output spectral matrix from scipy.signal.csd (Hann, half overlap, density,
    each segment's mean removed): G_ij = csd(y_i, y_j), the first singular value per line."""
    signal = pytest.importorskip("scipy.signal")
    channels = y.shape[1]
    f = None
    g = None
    for i in range(channels):
        for j in range(channels):
            f, pij = signal.csd(y[:, i], y[:, j], fs=1.0 / H, nperseg=length, detrend="constant")
            if g is None:
                g = np.empty((len(f), channels, channels), dtype=complex)
            g[:, i, j] = pij
    return f, np.array([np.linalg.svd(gk, compute_uv=False)[0] for gk in g])


def test_fdd_peaks_match_scipy_csd_spectral_matrix():
    """fdd's frequencies are the peaks of the first singular value of scipy.signal.csd's
    spectral matrix, interpolated by a parabola through log s1 at the peak and its neighbours:
    the same numbers to 1e-9 Hz (the spectral matrix's conventions match scipy's)."""
    y, modes = _record(21)
    length = 2048
    result = ctid.oma(y, H, method=ctid.OmaMethod.fdd, segment_length=length)
    assert result.verdict.usable, result.verdict.summary()
    assert len(result.modes) == len(modes)
    f, s1 = _scipy_first_singular_value(y, length)
    df = f[1] - f[0]
    for mode, (truth, _) in zip(result.modes, modes):
        window = np.flatnonzero(np.abs(f - truth) < 5 * df)
        k = window[np.argmax(s1[window])]
        a, b, c = np.log(s1[k - 1 : k + 2])
        expected = f[k] + 0.5 * (a - c) / (a - 2 * b + c) * df
        assert mode.frequency_hz == pytest.approx(expected, abs=1e-9)
        assert np.isnan(mode.damping_ratio)


def test_efdd_gives_damping_near_the_truth():
    """efdd on a 30000-sample record: frequencies within 1 %, damping ratios within a factor 2
    (each bell spans a few lines; the C++ Monte Carlo bounds the spread)."""
    y, modes = _record(22)
    result = ctid.oma(y, H, method=ctid.OmaMethod.efdd)
    assert result.method == ctid.OmaMethod.efdd
    assert len(result.modes) == len(modes)
    for mode, (f, zeta) in zip(result.modes, modes):
        assert mode.frequency_hz == pytest.approx(f, rel=0.01)
        assert 0.5 * zeta < mode.damping_ratio < 2.0 * zeta


def test_every_result_carries_scipys_first_singular_value():
    """The first singular value every method reports is scipy.signal.csd's spectral matrix's,
    line by line, to 1e-9 relative (ssi-cov and efdd alike)."""
    y, _ = _record(23)
    length = 1024
    f, s1 = _scipy_first_singular_value(y, length)
    for method in (ctid.OmaMethod.ssi_cov, ctid.OmaMethod.efdd):
        result = ctid.oma(y, H, method=method, segment_length=length, max_order=12,
                          uncertainty_blocks=0)
        np.testing.assert_allclose(result.spectrum_hz, f, rtol=1e-12)
        np.testing.assert_allclose(result.first_singular_value, s1, rtol=1e-9,
                                   atol=1e-12 * s1.max())


def test_the_stabilisation_diagram_draws_the_first_singular_value_behind_the_poles():
    """oma_stabilisation: a second axis holds the first singular value in dB at its lines,
    under the axis of the poles."""
    pytest.importorskip("matplotlib")
    from ctid import plotting
    y, _ = _record(24)
    result = ctid.oma(y, H, max_order=12, uncertainty_blocks=0)
    figure = plotting.oma_stabilisation(result)
    poles_axis, behind = figure.axes
    (curve,) = behind.get_lines()
    np.testing.assert_allclose(curve.get_xdata(), result.spectrum_hz)
    np.testing.assert_allclose(curve.get_ydata(), 10 * np.log10(result.first_singular_value))
    assert poles_axis.get_zorder() > behind.get_zorder()
    assert "singular value" in behind.get_ylabel()
    assert poles_axis.get_ylabel() == "model order"
    # pLSCF's orders are polynomial orders, and the axis says so.
    plscf = ctid.oma(y, H, method=ctid.OmaMethod.plscf, max_order=12, uncertainty_blocks=0)
    assert plotting.oma_stabilisation(plscf).axes[0].get_ylabel() == "polynomial order"


def _numpy_ssi_data_poles(y, p, order, max_damping=0.2):
    """SSI-data written independently: the data Hankel matrix (past over future, 1/sqrt(j)),
    np.linalg.qr of its transpose, the SVD of the L21 block, A by least squares."""
    y = y - y.mean(axis=0)
    n, l = y.shape
    j = n - 2 * p + 1
    past = np.vstack([y[i : i + j].T for i in range(p)])
    future = np.vstack([y[p + i : p + i + j].T for i in range(p)])
    hankel = np.vstack([past, future]) / np.sqrt(j)
    lower = np.linalg.qr(hankel.T, mode="r").T
    l21 = lower[p * l :, : p * l]
    u, s, _ = np.linalg.svd(l21)
    return _frequencies_from_factor(u, s, order, l, max_damping)


def test_numpy_ssi_data_gives_the_same_poles():
    y, _ = _record(5, samples=8000)
    p, order = 12, 6
    result = ctid.oma(
        y, H, method=ctid.OmaMethod.ssi_data, max_order=order, block_rows=p, uncertainty_blocks=0
    )
    assert result.method == ctid.OmaMethod.ssi_data
    ours = np.sort([q.frequency_hz for q in result.stabilisation if q.order == order])
    reference = _numpy_ssi_data_poles(y, p, order)
    assert ours.shape == reference.shape and len(ours) == 3
    np.testing.assert_allclose(ours, reference, rtol=1e-8)
    # and they are the chain's modes, near SSI-cov's on the same record
    np.testing.assert_allclose(ours, _numpy_poles(y, p, order), rtol=0.02)


def test_a_hyphenated_method_is_an_attribute_and_keeps_its_name_in_json():
    """ctid.OmaMethod.ssi_data is the command line's "ssi-data": the name JSON holds."""
    assert ctid.OmaMethod.ssi_data.name == "ssi-data"
    options = ctid.OmaOptions(method=ctid.OmaMethod.ssi_data)
    document = ctid.options_to_json(options)
    assert document["method"] == "ssi-data"
    assert ctid.options_from_json("OmaOptions", document).method == ctid.OmaMethod.ssi_data


def test_perturbation_standard_errors_are_finite_and_positive():
    """uncertainty=perturbation (the default for ssi-cov) and segments: the same modes, finite
    positive standard errors of frequency, damping and every shape entry but the largest."""
    y, modes = _record(4, samples=20000)
    kinds = (ctid.OmaUncertainty.perturbation, ctid.OmaUncertainty.segments)
    results = [ctid.oma(y, H, max_order=20, block_rows=20, uncertainty=kind) for kind in kinds]
    assert ctid.OmaOptions().uncertainty == ctid.OmaUncertainty.perturbation
    assert "first-order perturbation standard errors" in results[0].message
    perturbation, segments = results
    assert len(perturbation.modes) == len(modes)
    for mode, other in zip(perturbation.modes, segments.modes):
        assert mode.frequency_hz == other.frequency_hz
        assert mode.damping_ratio == other.damping_ratio
        assert np.isfinite(mode.frequency_hz_std) and mode.frequency_hz_std > 0
        assert np.isfinite(mode.damping_ratio_std) and mode.damping_ratio_std > 0
        largest = int(np.argmax(np.hypot(mode.shape_real, mode.shape_imag)))
        for j, (re, im) in enumerate(zip(mode.shape_real_std, mode.shape_imag_std)):
            assert np.isfinite(re) and np.isfinite(im)
            assert (re == 0 and im == 0) if j == largest else (re > 0 and im > 0)


def _numpy_poser(setups, references):
    """PoSER in NumPy (decision 0059), from each setup's own modes: the modes of setup 1 found
    in every setup (nearest frequency within 2 %), inverse-variance weighted means of f (the
    variance scaled by nu / (nu - 2) for standard errors from 10 blocks), each shape
    scaled onto setup 1's on the references, normalised at its largest entry."""
    merged = []
    for anchor in setups[0].modes:
        chosen = [anchor]
        for other in setups[1:]:
            near = [m for m in other.modes
                    if abs(m.frequency_hz / anchor.frequency_hz - 1.0) <= 0.02]
            if not near:
                break
            chosen.append(min(near, key=lambda m: abs(m.frequency_hz - anchor.frequency_hz)))
        if len(chosen) < len(setups):
            continue
        f = np.array([m.frequency_hz for m in chosen])
        wf = 1.0 / np.array([m.frequency_hz_std for m in chosen]) ** 2
        shapes = [np.array(m.shape_real) + 1j * np.array(m.shape_imag) for m in chosen]
        refs = [[list(s.channels).index(r) for r in references] for s in setups]
        first = shapes[0][refs[0]]
        scaled = []
        for shape, ref in zip(shapes, refs):
            alpha = np.vdot(shape[ref], first) / np.vdot(shape[ref], shape[ref])
            scaled.append(alpha * shape)
        glob = [np.mean([s[ref][k] for s, ref in zip(scaled, refs)])
                for k in range(len(references))]
        for s, setup, ref in zip(scaled, setups, refs):
            glob += [s[j] for j in range(len(s)) if j not in ref]
        glob = np.array(glob)
        nu = 10 - 1  # the standard errors' degrees of freedom (10 blocks)
        merged.append((np.sum(wf * f) / np.sum(wf), np.sqrt(nu / (nu - 2) / np.sum(wf)),
                       glob / glob[np.argmax(np.abs(glob))]))
    return merged


def test_oma_setups_merge_as_an_independent_numpy_poser():
    """Three setups of a 4-mass chain, x2 and x4 the references (the third setup has no roving
    sensor): ctid's merge equals a NumPy PoSER of the setups' own modes."""
    dofs = [[0, 1, 3], [1, 2, 3], [1, 3]]
    outputs, names = [], []
    for s, own in enumerate(dofs):
        y, _ = _record(40 + s, samples=20000, n=4)
        outputs.append(y[:, own])
        names.append([f"x{d + 1}" for d in own])
    modes = _chain(4)[2]
    picking = ctid.OmaOptions(max_order=16, modes_near_hz=[f for f, _ in modes])
    result = ctid.oma_setups(outputs, H, names, reference_names=["x2", "x4"], oma=picking)
    assert result.merged.verdict.usable, result.merged.message
    assert list(result.merged.channels) == ["x2", "x4", "x1", "x3"]
    expected = _numpy_poser(result.setups, ["x2", "x4"])
    assert len(result.merged.modes) == len(expected) == len(modes)
    for mode, (f, f_std, shape) in zip(result.merged.modes, expected):
        assert mode.frequency_hz == pytest.approx(f, rel=1e-12)
        assert mode.frequency_hz_std == pytest.approx(f_std, rel=1e-12)
        got = np.array(mode.shape_real) + 1j * np.array(mode.shape_imag)
        np.testing.assert_allclose(got, shape, atol=1e-12)
    with pytest.raises(ValueError, match="reference channel 'x3' is missing from setup 1"):
        ctid.oma_setups(outputs, H, names, reference_names=["x3"])


def test_track_output_only_modes_windows_are_the_analysis_of_their_stretch():
    """ctid.track_output_only_modes (decision 0060): window k's modes are ctid.oma of its
    samples, in rad/s; the chain's three modes are followed through every window."""
    y, modes = _record(50, samples=30000)
    options = ctid.OmaOptions(max_order=16, block_rows=20)
    result = ctid.track_output_only_modes(y, H, window=50.0, step=25.0, oma=options)
    assert len(result.windows) == 5
    for window in result.windows:
        stretch = y[window.first_sample:window.first_sample + result.window_samples]
        direct = ctid.oma(stretch, H, options)
        assert [m.natural_frequency for m in window.modes] == \
            [2 * np.pi * m.frequency_hz for m in direct.modes]
    assert len(result.tracks) == len(modes)
    for track, (f, _) in zip(result.tracks, modes):
        assert track.windows_matched >= 4  # a window may miss a mode
        assert track.mean_natural_frequency / (2 * np.pi) == pytest.approx(f, rel=0.01)


def test_mode_shape_and_mac_figures_of_an_analysis(tmp_path):
    """ctid.plotting.oma_mode_shapes draws one panel per mode over the named channels, and
    oma_mac's image is the auto-MAC of the shapes (1 on the diagonal); python3 -m ctid.plot
    draws both from the document."""
    import subprocess
    import sys

    from ctid import plotting

    y, _ = _record(3)
    result = ctid.oma(y, H, max_order=16, channel_names=["a", "b", "c"])
    assert len(result.modes) >= 2
    figure = plotting.oma_mode_shapes(result, filename=str(tmp_path / "shapes.png"))
    assert len(figure.axes) == len(result.modes)
    assert [t.get_text() for t in figure.axes[0].get_xticklabels()] == ["a", "b", "c"]
    figure = plotting.oma_mac(result)
    image = figure.axes[0].images[0].get_array()
    shapes = [np.array(m.shape_real) + 1j * np.array(m.shape_imag) for m in result.modes]
    expected = [[abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real)
                 for b in shapes] for a in shapes]
    np.testing.assert_allclose(image, expected, atol=1e-12)
    document = tmp_path / "oma.json"
    other = ctid.oma(y[:, :2], H, max_order=16)
    with pytest.raises(ValueError, match="different channels"):
        plotting.oma_mac(result, other)
    ctid.write_result(str(document), result)
    for kind in ("oma_shapes", "oma_mac"):
        out = tmp_path / f"{kind}.png"
        subprocess.run([sys.executable, "-m", "ctid.plot", kind, str(document), str(out)],
                       check=True)
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_fit_many_output_only_runs_oma_on_every_record(tmp_path):
    """ctid.batch.fit_many(output_only=True) (decision 0061): each record runs ctid oma with the
    spec's flags; a summary row's modes are ctid.oma's of the same samples, a record without a
    resonance has no usable model, and a fit flag in the spec is refused."""
    import ctid.batch

    records = []
    for seed in (61, 62):
        y, _ = _record(seed, samples=12000)
        file = tmp_path / f"r{seed}.csv"
        np.savetxt(file, y, delimiter=",", header="a,b,c", comments="", fmt="%.17g")
        records.append((file, y))
    noise = np.random.default_rng(63).standard_normal((4000, 3))
    np.savetxt(tmp_path / "noise.csv", noise, delimiter=",", header="a,b,c", comments="",
               fmt="%.17g")
    spec = {"sample-time": H, "max-order": 16, "block-rows": 20}
    rows = ctid.batch.fit_many(str(tmp_path / "*.csv"), spec, out_dir=tmp_path / "out", jobs=2,
                               output_only=True)
    by_name = {row["name"]: row for row in rows}
    assert by_name["noise"]["status"] == "no_usable_model"
    for file, y in records:
        row = by_name[file.stem]
        assert row["status"] == "ok" and row["estimator"] == "ssi-cov"
        direct = ctid.oma(y, H, max_order=16, block_rows=20)
        assert [m["frequency_hz"] for m in row["modes"]] == \
            pytest.approx([m.frequency_hz for m in direct.modes], rel=1e-12)
        assert [m["damping_se"] for m in row["modes"]] == \
            pytest.approx([m.damping_ratio_std for m in direct.modes], rel=1e-9)
    with pytest.raises(ValueError, match="field 'modes' is not a ctid oma flag"):
        ctid.batch.fit_many(str(tmp_path / "r*.csv"), {"modes": 2}, out_dir=tmp_path / "no",
                            output_only=True)


def _numpy_preger_frequencies(outputs, names, references, p, order, max_damping=0.2):
    """PreGER written independently (decision 0062): each setup's SSI-cov Hankel matrix against
    the references, O_s = U_n S_n^(1/2) at `order`, its reference rows fitted onto setup 1's by
    least squares, the global observability matrix interleaved block row by block row (the
    references, then each setup's other channels), A by least squares on its shifted rows."""
    observabilities, refs = [], []
    for y, own in zip(outputs, names):
        ref = [own.index(r) for r in references]
        y = y - y.mean(axis=0)
        n = len(y)
        r = [y[i:].T @ y[:n - i, ref] / n for i in range(1, 2 * p)]
        hankel = np.block([[r[i + j] for j in range(p)] for i in range(p)])
        u, s, _ = np.linalg.svd(hankel)
        observabilities.append(u[:, :order] * np.sqrt(s[:order]))
        refs.append(ref)
    blocks = []
    first = None
    for o, own, ref in zip(observabilities, names, refs):
        rows = o.reshape(p, len(own), order)
        on_refs = rows[:, ref, :].reshape(p * len(ref), order)
        if first is None:
            first = on_refs
            moved = rows
            blocks.append(rows[:, ref, :])
        else:
            moved = (o @ np.linalg.lstsq(on_refs, first, rcond=None)[0]).reshape(p, len(own), order)
        blocks.append(moved[:, [j for j in range(len(own)) if j not in ref], :])
    glob = np.concatenate(blocks, axis=1)
    channels = glob.shape[1]
    glob = glob.reshape(p * channels, order)
    a = np.linalg.lstsq(glob[:-channels], glob[channels:], rcond=None)[0]
    lam = np.linalg.eigvals(a)
    lam = lam[(lam.imag > 0) & (abs(lam) < 1)]
    s_c = np.log(lam) / H
    zeta = -s_c.real / abs(s_c)
    return np.sort(abs(s_c[(zeta > 0) & (zeta < max_damping)]) / (2 * np.pi))


def test_oma_setups_preger_gives_the_poles_of_an_independent_numpy_preger():
    """Three setups of a 4-mass chain merged by PreGER: at every order the global diagram's
    poles are those of a NumPy PreGER of the same records, and the chain's modes are found."""
    dofs = [[0, 1, 3], [1, 2, 3], [1, 3]]
    outputs, names = [], []
    for s, own in enumerate(dofs):
        y, _ = _record(70 + s, samples=20000, n=4)
        outputs.append(y[:, own])
        names.append([f"x{d + 1}" for d in own])
    modes = _chain(4)[2]
    options = ctid.OmaOptions(max_order=20, block_rows=20)
    result = ctid.oma_setups(outputs, H, names, reference_names=["x2", "x4"], oma=options,
                             merge=ctid.OmaMerge.preger)
    assert result.merged.verdict.usable, result.merged.message
    assert list(result.merged.channels) == ["x2", "x4", "x1", "x3"]
    for order in (8, 14, 20):
        ours = np.sort([q.frequency_hz for q in result.merged.stabilisation if q.order == order])
        reference = _numpy_preger_frequencies(outputs, names, ["x2", "x4"], 20, order)
        np.testing.assert_allclose(ours, reference, rtol=1e-8)
    assert len(result.merged.modes) == len(modes)
    for mode, (f, _) in zip(result.merged.modes, modes):
        assert abs(mode.frequency_hz - f) < 4 * mode.frequency_hz_std


def _numpy_plscf_frequencies(y, refs, lags, order, max_damping=0.2):
    """pLSCF written independently, as PolyMAX's papers state it: direct lag sums, the
    exponential window (w_M = 0.01) and the M-point grid's lines 0..M/2 (decision 0066's
    definitions), the reduced normal equations M = 2 sum_o (T_o - S_o^T R^-1 S_o) with the
    last coefficient the identity, the block companion matrix, s = ln(z)/h + beta."""
    y = y - y.mean(axis=0)
    n, l = y.shape
    r = len(refs)
    corr = [y[k:].T @ y[:n - k, refs] / n for k in range(1, lags + 1)]
    beta = np.log(100.0) / (lags * H)
    z = np.exp(2j * np.pi * np.arange(lags // 2 + 1) / lags)
    spectra = [sum(np.exp(-beta * k * H) * z_j ** (-k) * corr[k - 1] for k in range(1, lags + 1))
               for z_j in z]
    x = np.stack([z ** k for k in range(order + 1)], axis=1)
    rr = (x.conj().T @ x).real
    m = np.zeros(((order + 1) * r, (order + 1) * r))
    for o in range(l):
        yo = -np.concatenate([x[:, [k]] * np.array([s[o] for s in spectra])
                              for k in range(order + 1)], axis=1)
        so = (x.conj().T @ yo).real
        to = (yo.conj().T @ yo).real
        m += 2.0 * (to - so.T @ np.linalg.solve(rr, so))
    lo = order * r
    alpha = -np.linalg.solve(m[:lo, :lo], m[:lo, lo:])
    companion = np.zeros((lo, lo))
    for k in range(order):
        companion[:r, k * r:(k + 1) * r] = -alpha[(order - 1 - k) * r:(order - k) * r]
    companion[r:, :lo - r] = np.eye(lo - r)
    mu = np.linalg.eigvals(companion)
    mu = mu[(mu.imag > 0) & (abs(mu) < 1)]
    s_c = np.log(mu) / H + beta
    zeta = -s_c.real / abs(s_c)
    keep = (zeta > 0) & (zeta < max_damping)
    return np.sort(abs(s_c[keep]) / (2 * np.pi))


def test_numpy_plscf_gives_the_same_poles():
    """The library's QR of the projected equations and the papers' reduced normal equations are
    one least-squares problem: the same poles, to far below their standard errors."""
    y, modes = _record(7, samples=20000)
    refs, lags, order = [0, 2], 256, 6  # 256: the least lags (decision 0066)
    expected = _numpy_plscf_frequencies(y, refs, lags, order)
    result = ctid.oma(y, H, method=ctid.OmaMethod.plscf, max_order=2 * order,
                      reference_channels=refs, block_rows=20, uncertainty_blocks=0)
    assert result.method == ctid.OmaMethod.plscf
    assert "polynomial orders 1..12" in result.message and "256 lags" in result.message
    top = [p.frequency_hz for p in result.stabilisation if p.order == order]
    assert len(top) == len(expected)
    np.testing.assert_allclose(np.sort(top), expected, rtol=1e-8)
    for f, _ in modes:
        assert min(abs(m.frequency_hz - f) / f for m in result.modes) < 0.01
