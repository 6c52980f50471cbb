"""Figures of the shared-pole MIMO fit (issue 13): mode shapes, the MAC matrix and the model
over a measured FRF matrix, each checked against the numbers it should draw (read back from
the Figure), and the `python3 -m ctid.plot` kinds the CLI's --plot calls."""

import json
import math
import os
import subprocess
import sys
import types

import matplotlib.pyplot as plt
import numpy as np
import pytest

import ctid
from ctid import plot, plotting

from test_mimo_fit import two_modes
from test_plots import check_png, line

H = 0.05
INPUTS = ["f1", "f2"]
OUTPUTS = ["a1", "a2", "a3"]


def noisy_record(model, n=2000, noise=0.05, seed=3):
    u = np.column_stack([ctid.white_noise(n, 1.0, 5 + k) for k in range(model.inputs)])
    y = np.zeros((n, model.outputs))
    for j in range(model.outputs):
        for k in range(model.inputs):
            y[:, j] += ctid.simulate(model.channel(j, k), u[:, k], H)
    y += noise * np.random.default_rng(seed).standard_normal(y.shape)
    return ctid.MimoData(H, u, y).with_names(INPUTS, OUTPUTS)


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def data():
    return noisy_record(two_modes())


@pytest.fixture(scope="module")
def fit(data):
    r = ctid.mimo_srivc(data, [ctid.SubmodelOrder(2, 0)] * 2, max_iterations=50)
    assert r.converged(), r.message
    return r


def errorbar_halves(ax):
    """Half-lengths of the vertical error bars of the axis' one errorbar container."""
    containers = [c for c in ax.containers if c.get_label() == "± 1 se"]
    assert len(containers) == 1
    segments = containers[0].lines[2][0].get_segments()
    return np.array([(s[1][1] - s[0][1]) / 2.0 for s in segments]), np.array(
        [s[0][0] for s in segments])


def test_mode_shapes_draw_every_shape_with_its_errors(tmp_path, fit):
    path = tmp_path / "shapes.png"
    figure = plotting.mode_shapes(fit, output_names=OUTPUTS, filename=path)
    check_png(path)
    assert len(figure.axes) == len(fit.modes) == 2
    for ax, mode in zip(figure.axes, fit.modes):
        np.testing.assert_array_equal(line(ax, "Re(shape)").get_ydata(), np.real(mode.shape))
        np.testing.assert_array_equal(line(ax, "|shape|, signed").get_ydata(),
                                      np.abs(mode.shape) * np.sign(np.real(mode.shape)))
        halves, _ = errorbar_halves(ax)
        assert np.all(mode.shape_se_real > 0)
        np.testing.assert_allclose(halves, mode.shape_se_real, rtol=1e-12)
        f_hz = mode.natural_frequency / (2 * math.pi)
        assert f"f_n = {f_hz:.5g} ± {mode.natural_frequency_se / (2 * math.pi):.2g} Hz" in \
            ax.get_title()
        assert f"ζ = {mode.damping_ratio:.4g} ± {mode.damping_ratio_se:.2g}" in ax.get_title()
        assert [t.get_text() for t in ax.get_xticklabels()] == OUTPUTS


def fake_mode(shape, se_real, submodel=0, w=3.0):
    return types.SimpleNamespace(
        submodel=submodel, natural_frequency=w, natural_frequency_se=float("nan"),
        damping_ratio=0.02, damping_ratio_se=float("nan"), shape=np.asarray(shape),
        shape_se_real=np.asarray(se_real, dtype=float), rank_one_share=0.9)


def test_mode_shapes_geometry_sign_by_phase_and_missing_errors():
    # A complex shape: the signed magnitude takes the sign of the real part's direction, not of
    # the real part's size; NaN errors draw no bar; the geometry orders the points.
    shape = [0.1 + 0.9j, 1.0, -0.6 + 0.2j, 0.05 - 0.7j]
    mode = fake_mode(shape, [0.01, np.nan, 0.03, 0.04])
    geometry = [2.0, 0.0, 3.0, 1.0]
    figure = plotting.mode_shapes([mode], geometry=geometry)
    assert len(figure.axes) == 1
    ax = figure.axes[0]
    order = [1, 3, 0, 2]
    np.testing.assert_array_equal(line(ax, "Re(shape)").get_xdata(), [0.0, 1.0, 2.0, 3.0])
    np.testing.assert_array_equal(line(ax, "Re(shape)").get_ydata(),
                                  np.real(np.asarray(shape)[order]))
    magnitude = np.abs(np.asarray(shape))
    np.testing.assert_allclose(line(ax, "|shape|, signed").get_ydata(),
                               [magnitude[1], magnitude[3], magnitude[0], -magnitude[2]])
    halves, x = errorbar_halves(ax)
    np.testing.assert_allclose(x, [1.0, 2.0, 3.0])  # outputs 3, 0, 2 at their positions
    np.testing.assert_allclose(halves, [0.04, 0.01, 0.03])
    assert "f_n = 0.47746 Hz" in ax.get_title()  # no standard error to print
    assert ax.get_xlabel() == "position"
    with pytest.raises(ValueError, match="geometry needs 4 finite positions"):
        plotting.mode_shapes([mode], geometry=[0.0, 1.0])
    with pytest.raises(ValueError, match="3 output names for 4 outputs"):
        plotting.mode_shapes([mode], output_names=["a", "b", "c"])
    with pytest.raises(ValueError, match="no modes"):
        plotting.mode_shapes([])


def test_mac_matrix_draws_modal_assurance(tmp_path, fit, data):
    path = tmp_path / "mac.png"
    figure = plotting.mac_matrix(fit, filename=path)
    check_png(path)
    ax = figure.axes[0]
    expected = np.asarray(ctid.modal_assurance(fit.modes, fit.modes))
    np.testing.assert_allclose(ax.images[0].get_array(), expected, rtol=1e-12, atol=1e-15)
    texts = sorted((t.get_position(), t.get_text()) for t in ax.texts)
    assert [text for _, text in texts] == [f"{expected[c, r]:.2f}" for r in range(2)
                                           for c in range(2)]
    # Two halves of the record: each mode found again (MAC near 1), the others apart.
    half = data.size() // 2
    first = ctid.mimo_srivc(data.segment(0, half), [ctid.SubmodelOrder(2, 0)] * 2)
    second = ctid.mimo_srivc(data.segment(half, half), [ctid.SubmodelOrder(2, 0)] * 2)
    figure = plotting.mac_matrix(first, second.modes, labels=["A1", "A2"],
                                 column_labels=["B1", "B2"])
    ax = figure.axes[0]
    mac = np.asarray(ax.images[0].get_array())
    np.testing.assert_allclose(mac, ctid.modal_assurance(first.modes, second.modes), rtol=1e-12)
    assert mac[0, 0] > 0.99 and mac[1, 1] > 0.99 and mac[0, 1] < 0.1
    assert [t.get_text() for t in ax.get_yticklabels()] == ["A1", "A2"]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["B1", "B2"]
    with pytest.raises(ValueError, match="labels"):
        plotting.mac_matrix(fit, labels=["only one"])


def channel_response(submodels, direct, j, i, omegas):
    """H_ji(jw) = sum_k R_k[j, i](jw) / A_k(jw) + D[j, i], from the coefficients (ascending)."""
    s = 1j * np.asarray(omegas)
    total = np.full(s.shape, direct[j][i], dtype=complex)
    for a, numerators in submodels:
        total += (np.polynomial.polynomial.polyval(s, numerators[j][i])
                  / np.polynomial.polynomial.polyval(s, a))
    return total


def test_frf_matrix_overlay_draws_each_channel_of_the_model(tmp_path, data):
    # A model with a direct term and first-order numerators, so every part of the channel
    # counts; its response is computed here from the coefficients, not by ctid.
    w = (1.4, 4.0)
    numerators = [[[[0.3, 0.1], [-0.2, 0.05]], [[0.5, 0.02], [0.1, 0.2]],
                   [[-0.1, 0.3], [0.4, -0.1]]],
                  [[[0.2, 0.04], [0.1, 0.1]], [[-0.3, 0.05], [0.6, -0.03]],
                   [[0.2, 0.2], [0.1, 0.3]]]]
    denominators = [[1.0, 0.1 / v, 1.0 / v ** 2] for v in w]
    direct = [[0.01, 0.0], [0.0, -0.02], [0.03, 0.01]]
    model = ctid.MimoAdditiveModel(2, 3, [
        ctid.MimoSubmodel(ctid.Polynomial(a), [ctid.Polynomial(b) for row in r for b in row])
        for a, r in zip(denominators, numerators)], np.array(direct))
    frf = ctid.welch_frf(data)
    path = tmp_path / "overlay.png"
    channels = [("a3", "f1"), (1, 1)]
    figure = plotting.frf_matrix_overlay(model, frf, channels=channels, filename=path)
    check_png(path)
    assert len(figure.axes) == 4
    measured = np.asarray(frf.response)
    for c, (j, i) in enumerate([(2, 0), (1, 1)]):
        ax_mag, ax_phase = figure.axes[2 * c], figure.axes[2 * c + 1]
        assert ax_mag.get_title() == f"{OUTPUTS[j]}/{INPUTS[i]}"
        drawn = line(ax_mag, "model")
        omegas = drawn.get_xdata() * 2 * np.pi
        expected = channel_response(list(zip(denominators, numerators)), direct, j, i, omegas)
        np.testing.assert_allclose(drawn.get_ydata(), 20 * np.log10(np.abs(expected)),
                                   rtol=1e-9)
        np.testing.assert_allclose(np.deg2rad(line(ax_phase, "model").get_ydata()),
                                   np.unwrap(np.angle(expected)), atol=1e-9)
        np.testing.assert_allclose(line(ax_mag, "FRF").get_ydata(),
                                   20 * np.log10(np.abs(measured[:, j, i])))
        np.testing.assert_allclose(line(ax_mag, "FRF").get_xdata(),
                                   np.asarray(frf.frequencies) / (2 * np.pi))
        frf_phase = np.deg2rad(line(ax_phase, "FRF").get_ydata())
        np.testing.assert_allclose(np.exp(1j * frf_phase), np.exp(1j * np.angle(
            measured[:, j, i])), atol=1e-9)  # the FRF's own phase, moved by whole turns only
    with pytest.raises(ValueError, match="no output 'a9'"):
        plotting.frf_matrix_overlay(model, frf, channels=[("a9", "f1")])
    with pytest.raises(ValueError, match="the FRF is 3 outputs x 2 inputs but the model 1 x 1"):
        plotting.frf_matrix_overlay(ctid.MimoAdditiveModel(1, 1, [ctid.MimoSubmodel(
            ctid.Polynomial([1.0, 1.0]), [ctid.Polynomial([1.0])])]), frf)


def test_frf_matrix_overlay_defaults_to_the_largest_channels(fit, data):
    frf = ctid.welch_frf(data)
    figure = plotting.frf_matrix_overlay(fit, frf)
    peaks = np.max(np.abs(np.asarray(frf.response)), axis=0)
    largest = np.argsort(-peaks, axis=None)[:4]
    expected = [f"{OUTPUTS[k // 2]}/{INPUTS[k % 2]}" for k in largest]
    assert [ax.get_title() for ax in figure.axes[::2]] == expected
    assert len(figure.axes) == 8


def mimo_frf_document(frf):
    """The mimo_frf document `ctid frf -o X.json` writes, from a MimoFrf."""
    return json.loads(ctid.result_to_json(frf))


def write_fit(path, result, outputs=OUTPUTS):
    ctid.write_result(str(path), result)
    with open(path) as stream:
        document = json.load(stream)
    document["data"] = {"file": "d.csv", "inputs": INPUTS, "outputs": outputs}
    with open(path, "w") as stream:
        json.dump(document, stream)


def test_plot_entry_point_draws_the_mimo_kinds(tmp_path, fit, data):
    result = tmp_path / "r.json"
    write_fit(result, fit)
    frf = tmp_path / "frf.json"
    with open(frf, "w") as stream:
        json.dump(mimo_frf_document(ctid.welch_frf(data)), stream)
    figure = plot.run("mode_shapes", str(result), str(tmp_path / "shapes.png"))
    assert len(figure.axes) == 2
    assert [t.get_text() for t in figure.axes[0].get_xticklabels()] == OUTPUTS
    figure = plot.run("mac", str(result), str(tmp_path / "mac.png"), against=str(result))
    np.testing.assert_allclose(figure.axes[0].images[0].get_array(),
                               ctid.modal_assurance(fit.modes, fit.modes), rtol=1e-12)
    figure = plot.run("frf_matrix_overlay", str(result), str(tmp_path / "overlay.png"),
                      frf=str(frf))
    assert len(figure.axes) == 8
    # A bare mimo_additive_model document is drawn the same.
    model_file = tmp_path / "m.json"
    with open(result) as stream:
        model_document = json.load(stream)["model"]
    with open(model_file, "w") as stream:
        json.dump(model_document, stream)
    again = plot.run("frf_matrix_overlay", str(model_file), str(tmp_path / "overlay2.png"),
                     frf=str(frf))
    np.testing.assert_allclose(line(again.axes[0], "model").get_ydata(),
                               line(figure.axes[0], "model").get_ydata(), rtol=1e-12)
    for name in ("shapes.png", "mac.png", "overlay.png", "overlay2.png"):
        check_png(tmp_path / name)
    other = tmp_path / "other.json"
    write_fit(other, fit, outputs=["b1", "b2", "b3"])
    with pytest.raises(plot.InputError, match="are not those of"):
        plot.run("mac", str(result), str(tmp_path / "x.png"), against=str(other))


def test_plot_entry_point_refuses_bad_mimo_input(tmp_path, fit):
    result = tmp_path / "r.json"
    write_fit(result, fit)
    env = dict(os.environ, MPLBACKEND="Agg")

    def run(*args):
        return subprocess.run([sys.executable, "-m", "ctid.plot", *args], capture_output=True,
                              text=True, env=env)

    done = run("frf_matrix_overlay", str(result), str(tmp_path / "o.png"))
    assert done.returncode == 2
    assert done.stderr.startswith("ctid.plot: frf_matrix_overlay needs --frf FRF.json")
    done = run("mode_shapes", str(result), str(tmp_path / "o.png"), "--frf", str(result))
    assert done.returncode == 2
    assert "--frf goes with bode, modes and frf_matrix_overlay" in done.stderr
    siso = tmp_path / "siso.json"
    with open(siso, "w") as stream:
        json.dump({"type": "additive_model", "submodels": []}, stream)
    done = run("mac", str(siso), str(tmp_path / "o.png"))
    assert done.returncode == 2
    assert ("not a mimo_estimation_result or frf_matrix_fit_result document (type "
            "'additive_model')") in done.stderr
    done = run("mode_shapes", str(result), str(tmp_path / "shapes.png"))
    assert done.returncode == 0, done.stderr
    check_png(tmp_path / "shapes.png")


def test_channel_fits_draws_one_bar_per_channel_and_series(tmp_path):
    names = ["a1", "a2", "a3"]
    fits = {"two inputs": [90.0, 80.5, 70.25], "one input": [10.0, float("nan"), -5.0]}
    path = tmp_path / "fits.png"
    figure = plotting.channel_fits(names, fits, title="t", filename=str(path))
    check_png(path)
    ax = figure.axes[0]
    heights = [p.get_height() for p in ax.patches]
    assert heights[:3] == fits["two inputs"]
    assert heights[3] == 10.0 and math.isnan(heights[4]) and heights[5] == -5.0
    assert [t.get_text() for t in ax.get_xticklabels()] == names
    assert ax.get_ylim()[0] <= -5.0
    plt.close(figure)
    with pytest.raises(ValueError, match="'one input' has 2 values for 3 channels"):
        plotting.channel_fits(names, {"one input": [1.0, 2.0]})
