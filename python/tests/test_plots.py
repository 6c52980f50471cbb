"""Figures: each file exists and is a valid PNG (or SVG) of sensible size, and the data
drawn equal the model's (read back from the Figure's axes)."""

import json
import os
import struct
import subprocess
import sys

import numpy as np
import pytest

import ctid
from ctid import plotting


def png_size(path):
    with open(path, "rb") as stream:
        head = stream.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    assert head[12:16] == b"IHDR"
    width, height = struct.unpack(">II", head[16:24])
    return width, height


def check_png(path):
    assert os.path.getsize(path) > 5000, "suspiciously small PNG"
    width, height = png_size(path)
    assert 400 <= width <= 3000 and 300 <= height <= 3000, (width, height)


def line(ax, label):
    found = [l for l in ax.get_lines() if l.get_label() == label]
    assert found, f"no line labelled {label!r}; have {[l.get_label() for l in ax.get_lines()]}"
    return found[0]


def test_bode_draws_the_model_frf_and_band(tmp_path, experiment, fitted):
    frf = ctid.periodic_frf(experiment["data"], period_length=256)
    path = tmp_path / "bode.png"
    figure = plotting.bode(fitted, frf=frf, filename=path)
    check_png(path)
    ax_mag, ax_phase = figure.axes
    model = line(ax_mag, "model")
    w = model.get_xdata() * 2 * np.pi  # the axis is in Hz
    expected = np.asarray(ctid.frequency_response(fitted.model, w))
    np.testing.assert_allclose(model.get_ydata(), 20 * np.log10(np.abs(expected)), rtol=1e-12)
    np.testing.assert_allclose(np.deg2rad(line(ax_phase, "model").get_ydata()),
                               np.unwrap(np.angle(expected)), atol=1e-12)
    measured = line(ax_mag, "FRF")
    np.testing.assert_allclose(measured.get_xdata(), frf.frequencies / (2 * np.pi))
    np.testing.assert_allclose(measured.get_ydata(), 20 * np.log10(np.abs(frf.response)))
    # The band is there and brackets the model.
    bands = [c for c in ax_mag.collections if c.get_label() == "95% band"]
    assert len(bands) == 1
    vertices = bands[0].get_paths()[0].vertices
    assert vertices[:, 1].min() <= model.get_ydata().min() + 1e-9
    # The magnitude axis spans the model and the FRF with a 10 dB margin, whatever the band.
    curves = np.concatenate([model.get_ydata(), measured.get_ydata()])
    np.testing.assert_allclose(ax_mag.get_ylim(), (curves.min() - 10, curves.max() + 10))


def test_bode_draws_the_model_as_the_samples_see_it(tmp_path, experiment, fitted):
    # sampled=(h, hold): a dashed curve of ctid.sampled_frequency_response below Nyquist,
    # the ZOH one lagging the continuous-time model by about half a sample.
    h = experiment["data"].sample_time
    figure = plotting.bode(fitted, sampled=(h, ctid.Hold.zero_order_hold),
                           filename=tmp_path / "bode.png")
    ax_mag, ax_phase = figure.axes
    seen = line(ax_mag, "model, sampled (zoh)")
    w = seen.get_xdata() * 2 * np.pi
    assert w.max() < np.pi / h
    expected = np.asarray(ctid.sampled_frequency_response(fitted.model, w, h,
                                                          ctid.Hold.zero_order_hold))
    np.testing.assert_allclose(seen.get_ydata(), 20 * np.log10(np.abs(expected)), rtol=1e-12)
    low = w < 0.1 * np.pi / h
    lag = (line(ax_phase, "model").get_ydata()[: w.size][low]
           - line(ax_phase, "model, sampled (zoh)").get_ydata()[low])
    np.testing.assert_allclose(np.deg2rad(lag), w[low] * h / 2, rtol=0.05, atol=1e-3)


def test_confidence_band_matches_sampling(fitted):
    # The delta-method sigma of |G| against the spread of |G| over parameter draws.
    w = np.array([1.0, 2.0, 4.0])
    response, sigma, _, z = plotting.frequency_response_band(fitted, w)
    assert z == pytest.approx(1.959964, rel=1e-6)
    draws = np.random.default_rng(1).multivariate_normal(fitted.parameters, fitted.covariance,
                                                         size=4000)
    magnitudes = np.array([np.abs(ctid.frequency_response(fitted.model.with_parameters(d), w))
                           for d in draws])
    np.testing.assert_allclose(sigma, magnitudes.std(axis=0), rtol=0.1)


def test_modes_draws_each_submodel(tmp_path):
    model = ctid.AdditiveModel([
        ctid.Submodel(ctid.Polynomial([1.0, 0.02, 0.25]), ctid.Polynomial([1.0])),
        ctid.Submodel(ctid.Polynomial([1.0, 0.005, 1 / 144.0]), ctid.Polynomial([0.3]))])
    path = tmp_path / "modes.png"
    figure = plotting.modes(model, filename=path, frequency_unit="rad/s")
    check_png(path)
    ax = figure.axes[0]
    labels = [l.get_label() for l in ax.get_lines()]
    assert labels[0].startswith("submodel 1 (w_n = 2 rad/s")
    assert labels[1].startswith("submodel 2 (w_n = 12 rad/s")
    hz = plotting.modes(model).axes[0]
    assert [l.get_label() for l in hz.get_lines()][0].startswith(
        f"submodel 1 (f_n = {2 / (2 * np.pi):.4g} Hz")
    np.testing.assert_allclose(line(hz, "sum").get_xdata() * 2 * np.pi,
                               line(ax, "sum").get_xdata(), rtol=1e-14)
    total = line(ax, "sum")
    columns = ctid.submodel_frequency_responses(model, total.get_xdata())
    np.testing.assert_allclose(ax.get_lines()[1].get_ydata(),
                               20 * np.log10(np.abs(columns[:, 1])), rtol=1e-12)
    np.testing.assert_allclose(total.get_ydata(),
                               20 * np.log10(np.abs(columns.sum(axis=1))), rtol=1e-12)


def test_validation_shows_measured_simulated_and_fit(tmp_path, experiment, fitted):
    path = tmp_path / "validation.svg"
    figure = plotting.validation(experiment["data"], fitted, filename=path)
    assert path.read_text().lstrip().startswith(("<?xml", "<svg"))
    ax = figure.axes[0]
    simulated = ctid.model_output(fitted.model, experiment["data"].input, 0.05)
    np.testing.assert_array_equal(line(ax, "simulated").get_ydata(), simulated)
    np.testing.assert_array_equal(line(ax, "measured").get_ydata(), experiment["data"].output)
    fit = ctid.fit_percent(experiment["data"].output, simulated)
    assert ax.get_title() == f"fit = {fit:.2f} %"


def test_residual_correlation_against_numpy(tmp_path):
    rng = np.random.default_rng(3)
    e, u = rng.standard_normal(2000), rng.standard_normal(2000)
    path = tmp_path / "residuals.png"
    figure = plotting.residual_correlation(e, u, max_lag=10, filename=path)
    check_png(path)
    auto, cross = figure.axes
    ec, uc = e - e.mean(), u - u.mean()
    full = np.correlate(ec, ec, "full")[len(e) - 1:len(e) + 10] / (ec @ ec)
    np.testing.assert_allclose(line(auto, "autocorrelation").get_ydata(), full, atol=1e-12)
    cross_full = np.correlate(ec, uc, "full")[len(e) - 11:len(e) + 10]
    np.testing.assert_allclose(line(cross, "cross-correlation").get_ydata(),
                               cross_full / np.sqrt((ec @ ec) * (uc @ uc)), atol=1e-12)
    np.testing.assert_allclose(line(auto, "99% bound").get_ydata(), 2.5758293 / np.sqrt(2000),
                               rtol=1e-6)


def test_mse_against_n_from_rows(tmp_path):
    n = np.array([1000, 3000, 10000])
    rows = [{"estimator": e, "N": str(k), "parameter": "b10", "mse": str(c / k),
             "predicted_mse": str(0.9 * c / k)} for e, c in (("srivc", 2.0), ("additive", 1.0))
            for k in n]
    path = tmp_path / "mse.png"
    figure = plotting.mse_against_n(rows, filename=path)
    check_png(path)
    ax = figure.axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    np.testing.assert_allclose(line(ax, "additive").get_ydata(), 1.0 / n)
    np.testing.assert_allclose(line(ax, "srivc (predicted)").get_ydata(), 1.8 / n)


def test_save_rejects_other_formats(fitted):
    figure = plotting.bode(fitted)
    with pytest.raises(ValueError, match="must end in .png or .svg"):
        plotting.save(figure, "figure.jpg")


def run_plot(*args):
    return subprocess.run([sys.executable, "-m", "ctid.plot", *map(str, args)],
                          capture_output=True, text=True, env=os.environ.copy())


def test_command_line_entry_point(tmp_path, experiment, fitted):
    frf = ctid.periodic_frf(experiment["data"], period_length=256)
    model = fitted.model[0]
    document = {
        "model": {"type": "additive_model", "input_delay": 0.0,
                  "submodels": [{"denominator_ascending": list(model.a.coefficients),
                                 "numerator_ascending": list(model.b.coefficients),
                                 "integrators": 0}]},
        "covariance": np.asarray(fitted.covariance).tolist(),
        "frf": {"frequencies": list(frf.frequencies), "real": list(frf.response.real),
                "imag": list(frf.response.imag)},
    }
    (tmp_path / "fit.json").write_text(json.dumps(document))
    for kind in ("bode", "modes"):
        result = run_plot(kind, tmp_path / "fit.json", tmp_path / f"{kind}.png")
        assert result.returncode == 0, result.stderr
        check_png(tmp_path / f"{kind}.png")

    data = experiment["data"]
    simulated = ctid.model_output(fitted.model, data.input, data.sample_time)
    rows = ["t,u,y,y_model"] + [f"{t!r},{u!r},{y!r},{s!r}" for t, u, y, s in
                                zip(data.time, data.input, data.output, simulated)]
    (tmp_path / "data.csv").write_text("\n".join(rows) + "\n")
    for kind in ("validation", "residuals"):
        result = run_plot(kind, tmp_path / "data.csv", tmp_path / f"{kind}.png")
        assert result.returncode == 0, result.stderr
        check_png(tmp_path / f"{kind}.png")

    (tmp_path / "mse.csv").write_text(
        "estimator,N,size_index,parameter,true_value,mse,bias,predicted_mse,valid_runs,"
        "converged_runs\nsrivc,1000,0,b10,1,0.001,0,0.0009,10,10\n"
        "srivc,10000,1,b10,1,0.0001,0,0.00009,10,10\n")
    result = run_plot("mse", tmp_path / "mse.csv", tmp_path / "mse.svg")
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "mse.svg").stat().st_size > 1000

    rows = ["frequency,real,imag,coherence"] + [
        f"{w!r},{g.real!r},{g.imag!r},0.9" for w, g in zip(frf.frequencies, frf.response)]
    (tmp_path / "frf.csv").write_text("\n".join(rows) + "\n")
    result = run_plot("frf", tmp_path / "frf.csv", tmp_path / "frf.png")
    assert result.returncode == 0, result.stderr
    check_png(tmp_path / "frf.png")
    (tmp_path / "frf.csv").write_text("frequency,real\n1,2\n")
    result = run_plot("frf", tmp_path / "frf.csv", tmp_path / "frf.png")
    assert result.returncode == 2 and "needs a column named imag" in result.stderr


def test_frf_figure_draws_magnitude_phase_and_coherence(experiment):
    data = experiment["data"]
    welch = ctid.welch_frf(data, segment_length=128)
    figure = plotting.frf(welch, title="t")
    axes = figure.axes
    assert len(axes) == 3
    (magnitude,) = [l for l in axes[0].get_lines() if l.get_label() == "FRF"]
    np.testing.assert_allclose(magnitude.get_ydata(), 20 * np.log10(np.abs(welch.response)))
    (coherence,) = [l for l in axes[2].get_lines() if l.get_label() == "coherence"]
    np.testing.assert_allclose(coherence.get_ydata(), welch.coherence)
    # A periodic FRF has a coherence over its periods too; an estimate without one has two
    # panels.
    periodic = ctid.periodic_frf(data, period_length=256)
    assert len(plotting.frf(periodic).axes) == 3

    class Bare:
        frequencies = periodic.frequencies
        response = periodic.response

    assert len(plotting.frf(Bare()).axes) == 2


def test_command_line_bad_input_exits_2(tmp_path):
    result = run_plot("nyquist", tmp_path / "x.json", tmp_path / "x.png")
    assert result.returncode == 2
    assert result.stderr.strip() == ("ctid.plot: unknown kind 'nyquist'; expected one of "
                                     "bode, modes, frf, frf_matrix, validation, compare, "
                                     "residuals, mse, stabilisation, mode_shapes, mac, "
                                     "frf_matrix_overlay, tracking, oma_stabilisation, "
                                     "oma_shapes, oma_mac, step, impulse")
    (tmp_path / "bad.json").write_text('{"type": "state_space"}')
    result = run_plot("bode", tmp_path / "bad.json", tmp_path / "x.png")
    assert result.returncode == 2 and '"type" is "state_space"' in result.stderr
    (tmp_path / "tf.json").write_text(
        '{"type": "transfer_function", "numerator_ascending": [1], '
        '"denominator_ascending": [0, 0]}')
    result = run_plot("bode", tmp_path / "tf.json", tmp_path / "x.png")
    assert result.returncode == 2 and result.stderr.startswith("ctid.plot: ")


def test_importing_plotting_keeps_the_callers_backend():
    # Issue 35: `import ctid.plotting` switched matplotlib to Agg, so a later plt.show()
    # showed nothing. A fresh interpreter chooses "svg", then imports the module.
    import subprocess
    import sys
    code = ("import matplotlib; matplotlib.use('svg'); import ctid.plotting; "
            "print(matplotlib.get_backend())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "svg"


def test_figures_draw_into_the_callers_axes(experiment, fitted):
    """ax=: the figure is the caller's, its axes hold what the function drew (the same lines as
    a figure of the function's own), its layout and the backend are left as they were, and an
    ax of the wrong kind is one TypeError."""
    import matplotlib
    import matplotlib.pyplot as plt

    backend = matplotlib.get_backend()
    model = fitted.model
    e = np.random.default_rng(1).standard_normal(300)
    cases = [
        ("modes", lambda ax: plotting.modes(model, ax=ax), 1),
        ("validation", lambda ax: plotting.validation(experiment["data"], fitted, ax=ax), 1),
        ("compare", lambda ax: plotting.compare(experiment["data"], [fitted], ax=ax), 1),
        ("channel_fits", lambda ax: plotting.channel_fits(["y1", "y2"], {"fit": [90.0, 80.0]},
                                                          ax=ax), 1),
        ("bode", lambda ax: plotting.bode(fitted, ax=ax), 2),
        ("residual_correlation", lambda ax: plotting.residual_correlation(e, e, ax=ax), 2),
    ]
    for name, draw, count in cases:
        own = draw(None)
        figure, axes = plt.subplots(1, count)
        given = axes if count > 1 else [axes]
        assert figure.get_layout_engine() is None
        drawn = draw(axes if count > 1 else axes)
        assert drawn is figure, name
        assert figure.get_layout_engine() is None, name
        for mine, theirs in zip(given, own.axes):
            count_of = lambda a: (len(a.lines), len(a.patches), len(a.collections))
            assert count_of(mine) == count_of(theirs) and sum(count_of(mine)) > 0, name
            for a, b in zip(mine.lines, theirs.lines):
                np.testing.assert_array_equal(a.get_ydata(), b.get_ydata())
        plt.close(figure)
        plt.close(own)
        wrong = "an axes" if count == 1 else plt.subplots(1, 1)[1]
        with pytest.raises(TypeError, match=r"ax: expected (a matplotlib Axes|a sequence of 2)"):
            draw(wrong)
    assert matplotlib.get_backend() == backend


def test_noise_spectrum_draws_the_model_and_the_measured_output_error(tmp_path):
    # 2 / (1 + 0.5 p + p^2) with AR(1) noise (pole 0.9), RIVC with the true orders.
    g = ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial([1.0, 0.5, 1.0]),
                                          ctid.Polynomial([2.0]))])
    h = 0.05
    u = ctid.white_noise(8000, 1.0, seed=4)
    filt = ctid.DiscreteTransferFunction(ctid.Polynomial([0.0, 1.0]),
                                         ctid.Polynomial([-0.9, 1.0]), h)
    data = ctid.SampledData(h, u, ctid.simulate(g, u, h) + ctid.colored_noise(filt, 8000, 0.01,
                                                                              seed=5))
    result = ctid.srivc(data, ctid.SubmodelOrder(2, 0), noise_model="1,0")
    path = tmp_path / "noise.png"
    figure = plotting.noise_spectrum(result, data, filename=path)
    check_png(path)
    ax = figure.axes[0]
    model = line(ax, "noise model")
    np.testing.assert_array_equal(model.get_xdata(), result.noise_model.spectrum_frequencies)
    np.testing.assert_array_equal(model.get_ydata(), result.noise_model.spectrum)
    # The closed form of the true noise: 2 h 0.01 / |1 - 0.9 e^{-i w h}|^2.
    f = np.asarray(result.noise_model.spectrum_frequencies)
    truth = 2 * h * 0.01 / np.abs(1 - 0.9 * np.exp(-2j * np.pi * f * h)) ** 2
    assert np.all(np.abs(np.log(model.get_ydata() / truth)) < 0.15)
    # The measured output error's periodogram, averaged over its lines, agrees with the model.
    measured = line(ax, "output error")
    at = np.interp(measured.get_xdata(), f, model.get_ydata())
    assert abs(np.mean(np.log(measured.get_ydata() / at))) < 0.2
    assert ax.get_xlabel() == "frequency [Hz]"
    with pytest.raises(ValueError, match="has no noise model"):
        plotting.noise_spectrum(ctid.srivc(data, ctid.SubmodelOrder(2, 0)))
