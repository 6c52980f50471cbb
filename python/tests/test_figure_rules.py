"""Rules every figure of ctid.plotting keeps (issue 15, "what the engineer sees"), checked
on each kind of figure read back from its matplotlib artists:

- the drawn model curves equal the model's response at the plotted frequencies, computed here
  in closed form from the model's coefficients (not through ctid.frequency_response);
- frequency axes say Hz, and rad/s when asked, and the x data are in that unit;
- a model's phase is continuous; a measured FRF alone is wrapped to (-180, 180];
- the default range holds every resonance of the model, even outside the FRF's lines;
- measured data are drawn on every model-vs-data figure, and low coherence is shaded;
- the residual plot's lag label says what the cross-correlation's sign means;
- no text artist reaches outside the canvas."""

import math
import types

import matplotlib.pyplot as plt
import numpy as np
import pytest

import ctid
from ctid import plotting

from test_mimo_fit import two_modes
from test_plots import line

H = 0.05


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


# --- closed forms ------------------------------------------------------------------------------

def polyval_ascending(coefficients, s):
    return np.polyval(np.asarray(coefficients, dtype=float)[::-1], s)


def transfer_function_response(g, w):
    s = 1j * np.asarray(w, dtype=float)
    return (polyval_ascending(g.numerator.coefficients, s)
            / polyval_ascending(g.denominator.coefficients, s) * np.exp(-s * g.input_delay))


def additive_response(model, w):
    """Sum over the submodels of B_i(s) / (s^l_i A_i(s)), times the delay."""
    s = 1j * np.asarray(w, dtype=float)
    total = np.zeros(s.shape, dtype=complex)
    for k in range(len(model)):
        sub = model[k]
        total += (polyval_ascending(sub.b.coefficients, s)
                  / (s ** sub.integrators * polyval_ascending(sub.a.coefficients, s)))
    return total * np.exp(-s * model.input_delay)


def mimo_response(model, w, output, input):
    s = 1j * np.asarray(w, dtype=float)
    total = np.full(s.shape, model.direct[output, input] if model.has_direct_term else 0.0,
                    dtype=complex)
    for sub in model.submodels:
        total += (polyval_ascending(sub.b[output * model.inputs + input].coefficients, s)
                  / polyval_ascending(sub.a.coefficients, s))
    return total


def db(g):
    return 20 * np.log10(np.abs(g))


def same_phase(drawn_degrees, response):
    """The drawn phase equals arg G up to whole turns (and is continuous along the curve)."""
    turns = (np.asarray(drawn_degrees) - np.degrees(np.angle(response))) / 360.0
    np.testing.assert_allclose(turns, np.round(turns), atol=1e-9)


# --- rules -------------------------------------------------------------------------------------

def texts_inside_canvas(figure):
    """Every text artist drawn lies inside the figure's canvas: titles, axis labels, legends,
    annotations by their window extent; tick labels through their axis' tight box (matplotlib
    keeps labels of ticks outside the view limits as undrawn artists)."""
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    box = figure.bbox

    def inside(extent, what):
        assert (extent.x0 >= box.x0 - 0.5 and extent.y0 >= box.y0 - 0.5
                and extent.x1 <= box.x1 + 0.5 and extent.y1 <= box.y1 + 0.5), (
            f"{what} at {extent} leaves the canvas {box}")

    ticks = set()
    for ax in figure.axes:
        for axis in (ax.xaxis, ax.yaxis):
            for minor in (False, True):
                ticks.update(id(t) for t in axis.get_ticklabels(minor=minor, which=None))
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                ticks.update((id(tick.label1), id(tick.label2)))
            extent = axis.get_tightbbox(renderer)
            if extent is not None and ax.axison and ax.get_visible():
                inside(extent, f"the {axis.axis_name} axis of {ax.get_title()!r}")
    checked = 0
    for text in figure.findobj(match=lambda a: isinstance(a, plt.Text)):
        if id(text) in ticks or not text.get_visible() or not text.get_text().strip():
            continue
        inside(text.get_window_extent(renderer), f"text {text.get_text()!r}")
        checked += 1
    assert checked > 0


def frequency_label(ax, unit):
    assert ax.get_xlabel().endswith(f"[{unit}]"), ax.get_xlabel()


def to_rad_per_s(x, unit):
    return np.asarray(x) * (2 * np.pi if unit == "Hz" else 1.0)


@pytest.fixture(scope="module")
def record():
    g = ctid.TransferFunction([4.0], [4.0, 0.8, 1.0])
    u = ctid.multisine(period_length=256, sample_time=H, max_frequency=4.0, periods=8, seed=7)
    y = ctid.simulate(g, u.signal, H) + ctid.white_noise(len(u.signal), 0.05, 3)
    return ctid.SampledData(H, u.signal, y)


@pytest.fixture(scope="module")
def estimate(record):
    r = ctid.srivc(record, ctid.SubmodelOrder(2, 0), max_iterations=30)
    assert r.converged()
    return r


@pytest.fixture(scope="module")
def welch(record):
    return ctid.welch_frf(record, segment_length=256)


@pytest.mark.parametrize("unit", ["Hz", "rad/s"])
def test_bode_draws_the_model_in_closed_form_over_the_data(estimate, welch, unit):
    kwargs = {} if unit == "Hz" else {"frequency_unit": "rad/s"}
    figure = plotting.bode(estimate, frf=welch, **kwargs)
    ax_mag, ax_phase = figure.axes
    frequency_label(ax_phase, unit)
    model = line(ax_mag, "model")
    w = to_rad_per_s(model.get_xdata(), unit)
    expected = additive_response(estimate.model, w)
    np.testing.assert_allclose(model.get_ydata(), db(expected), rtol=1e-9, atol=1e-9)
    phase = line(ax_phase, "model").get_ydata()
    same_phase(phase, expected)
    assert np.all(np.abs(np.diff(phase)) < 90), "the model's phase jumps"
    assert -180 < phase[0] <= 180
    measured = line(ax_mag, "FRF")
    np.testing.assert_allclose(to_rad_per_s(measured.get_xdata(), unit), welch.frequencies,
                               rtol=1e-14)
    np.testing.assert_allclose(measured.get_ydata(), db(welch.response), rtol=1e-12)
    same_phase(line(ax_phase, "FRF").get_ydata(), welch.response)
    texts_inside_canvas(figure)


def test_bode_of_a_transfer_function_and_more_models():
    g = ctid.TransferFunction([2.0, 1.0], [3.0, 2.0, 3.0, 1.0])
    h = ctid.TransferFunction([1.0], [1.0, 0.5], 0.2)
    figure = plotting.bode(g, more=[("feedback H", h)], title="F and H")
    ax_mag, ax_phase = figure.axes
    w = to_rad_per_s(line(ax_mag, "model").get_xdata(), "Hz")
    np.testing.assert_allclose(line(ax_mag, "model").get_ydata(),
                               db(transfer_function_response(g, w)), rtol=1e-9)
    np.testing.assert_allclose(line(ax_mag, "feedback H").get_ydata(),
                               db(transfer_function_response(h, w)), rtol=1e-9)
    same_phase(line(ax_phase, "feedback H").get_ydata(), transfer_function_response(h, w))
    frequency_label(ax_phase, "Hz")
    texts_inside_canvas(figure)


def test_a_resonance_outside_the_data_stays_on_the_axis(welch):
    # A mode at 40 rad/s, far above the FRF's 4 Hz band edge... and one at 0.05 rad/s below.
    model = ctid.AdditiveModel([
        ctid.Submodel(ctid.Polynomial([1.0, 0.01 / 0.05, 1 / 0.05 ** 2]), ctid.Polynomial([1.0])),
        ctid.Submodel(ctid.Polynomial([1.0, 0.02 / 40, 1 / 40.0 ** 2]), ctid.Polynomial([0.1]))])
    band = welch.frequencies[(welch.frequencies > 0.5) & (welch.frequencies < 20)]
    frf = types.SimpleNamespace(frequencies=band, response=np.ones(band.size, dtype=complex))
    for draw in (plotting.bode, plotting.modes):
        figure = draw(model, frf=frf)
        x = to_rad_per_s(line(figure.axes[0], "FRF").get_xdata(), "Hz")
        curve = line(figure.axes[0], "model" if draw is plotting.bode else "sum")
        w = to_rad_per_s(curve.get_xdata(), "Hz")
        assert w.min() < 0.05 / 1.2 and w.max() > 40 * 1.2
        assert w.min() <= x.min() and w.max() >= x.max()
        # The peak is drawn: the curve's largest value is at the resonance.
        peak = w[np.argmax(curve.get_ydata())]
        assert peak == pytest.approx(0.05, rel=0.05) or peak == pytest.approx(40, rel=0.05)
        lo, hi = figure.axes[0].get_xlim()
        assert lo <= 0.05 / (2 * np.pi) and hi >= 40 / (2 * np.pi)


def test_frf_alone_wraps_its_phase_and_shades_low_coherence(welch):
    coherence = np.asarray(welch.coherence).copy()
    low = slice(10, 14)
    coherence[low] = 0.1
    frf = types.SimpleNamespace(frequencies=welch.frequencies, response=welch.response,
                                coherence=coherence)
    for unit in ("Hz", "rad/s"):
        figure = plotting.frf(frf, frequency_unit=unit)
        magnitude, phase, coherent = figure.axes
        frequency_label(coherent, unit)
        drawn = line(phase, "FRF").get_ydata()
        assert np.all((drawn > -180) & (drawn <= 180))
        same_phase(drawn, welch.response)
        np.testing.assert_allclose(to_rad_per_s(line(magnitude, "FRF").get_xdata(), unit),
                                   welch.frequencies, rtol=1e-14)
        shaded = [p for p in magnitude.patches if p.get_label() == "coherence < 0.5"]
        assert len(shaded) == 1
        x0, x1 = shaded[0].get_xy()[:, 0].min(), shaded[0].get_xy()[:, 0].max()
        inside = to_rad_per_s([x0, x1], unit)
        assert inside[0] < welch.frequencies[10] and inside[1] > welch.frequencies[13]
        assert inside[0] > welch.frequencies[9] and inside[1] < welch.frequencies[14]
        texts_inside_canvas(figure)


def test_bode_and_modes_shade_low_coherence_of_the_frf(estimate, welch):
    coherence = np.asarray(welch.coherence).copy()
    coherence[40:] = 0.2
    frf = types.SimpleNamespace(frequencies=welch.frequencies, response=welch.response,
                                coherence=coherence)
    for figure in (plotting.bode(estimate, frf=frf), plotting.modes(estimate, frf=frf)):
        assert [p for p in figure.axes[0].patches if p.get_label() == "coherence < 0.5"]
        line(figure.axes[0], "FRF")
    # A fully coherent FRF shades nothing.
    clean = types.SimpleNamespace(frequencies=welch.frequencies, response=welch.response,
                                  coherence=np.ones(welch.frequencies.size))
    figure = plotting.bode(estimate, frf=clean)
    assert not [p for p in figure.axes[0].patches if p.get_label() == "coherence < 0.5"]


def test_modes_draws_every_submodel_in_closed_form(estimate, welch):
    figure = plotting.modes(estimate, frf=welch, title="modes")
    ax = figure.axes[0]
    frequency_label(ax, "Hz")
    total = line(ax, "sum")
    w = to_rad_per_s(total.get_xdata(), "Hz")
    np.testing.assert_allclose(total.get_ydata(), db(additive_response(estimate.model, w)),
                               rtol=1e-9)
    np.testing.assert_allclose(line(ax, "FRF").get_ydata(), db(welch.response), rtol=1e-12)
    texts_inside_canvas(figure)


@pytest.fixture(scope="module")
def mimo():
    model = two_modes()
    n = 4096
    u = np.column_stack([ctid.white_noise(n, 1.0, 5 + k) for k in range(model.inputs)])
    y = np.zeros((n, model.outputs))
    for j in range(model.outputs):
        for k in range(model.inputs):
            y[:, j] += ctid.simulate(model.channel(j, k), u[:, k], H)
    y += 0.01 * np.random.default_rng(4).standard_normal(y.shape)
    data = ctid.MimoData(H, u, y)
    return model, ctid.welch_frf(data, segment_length=512), data


@pytest.mark.parametrize("unit", ["Hz", "rad/s"])
def test_frf_matrix_overlay_draws_each_channel_in_closed_form_over_the_data(mimo, unit):
    model, frf, _ = mimo
    channels = [(0, 0), (1, 1), (2, 0)]
    figure = plotting.frf_matrix_overlay(model, frf, channels=channels, title="overlay",
                                         frequency_unit=unit)
    axes = figure.axes
    assert len(axes) == 2 * len(channels)
    for c, (j, i) in enumerate(channels):
        ax_mag, ax_phase = axes[2 * c], axes[2 * c + 1]
        frequency_label(ax_phase, unit)
        drawn = line(ax_mag, "model")
        w = to_rad_per_s(drawn.get_xdata(), unit)
        expected = mimo_response(model, w, j, i)
        np.testing.assert_allclose(drawn.get_ydata(), db(expected), rtol=1e-9)
        same_phase(line(ax_phase, "model").get_ydata(), expected)
        measured = line(ax_mag, "FRF")
        np.testing.assert_allclose(to_rad_per_s(measured.get_xdata(), unit), frf.frequencies,
                                   rtol=1e-14)
        np.testing.assert_allclose(measured.get_ydata(), db(frf.response[:, j, i]), rtol=1e-12)
    texts_inside_canvas(figure)


def test_frf_matrix_draws_the_measured_channels(mimo):
    _, frf, _ = mimo
    figure = plotting.frf_matrix(frf, title="FRF matrix")
    magnitude, coherence = figure.axes
    frequency_label(coherence, "Hz")
    drawn = line(magnitude, f"{frf.output_names[1]}/{frf.input_names[0]}")
    np.testing.assert_allclose(to_rad_per_s(drawn.get_xdata(), "Hz"), frf.frequencies,
                               rtol=1e-14)
    np.testing.assert_allclose(drawn.get_ydata(), db(frf.response[:, 1, 0]), rtol=1e-12)
    frequency_label(plotting.frf_matrix(frf, frequency_unit="rad/s").axes[1], "rad/s")
    texts_inside_canvas(figure)


def test_stabilisation_axis_in_hz_or_rad_per_s(record):
    scan = ctid.scan_structures(record, [ctid.ModelStructure.modes(k) for k in (1, 2)])
    for unit in ("Hz", "rad/s"):
        figure = plotting.stabilisation(scan, title="scan", frequency_unit=unit)
        ax = figure.axes[0]
        frequency_label(ax, unit)
        drawn = np.concatenate([l.get_xdata() for l in ax.get_lines()
                                if l.get_label() in ("stable", "stable frequency", "new")])
        assert np.any(np.isclose(to_rad_per_s(drawn, unit), 2.0, rtol=0.05))
        texts_inside_canvas(figure)


def test_time_figures_draw_the_measured_output(record, estimate):
    for figure in (plotting.validation(record, estimate, title="validation"),
                   plotting.compare(record, [estimate], labels=["srivc"], title="compare")):
        ax = figure.axes[0]
        np.testing.assert_array_equal(line(ax, "measured").get_ydata(), record.output)
        assert ax.get_xlabel() == "time [s]"
        texts_inside_canvas(figure)


def test_the_lag_label_says_what_a_positive_lag_means():
    # The residual is the input three samples late: the input leads the residual, and the
    # cross-correlation peaks at k = +3, where the label says "input leads residual".
    u = np.random.default_rng(8).standard_normal(3000)
    e = np.concatenate([np.zeros(3), u[:-3]])
    lags, r_eu = plotting.correlations(e, u, max_lag=10)[2:]
    assert lags[np.argmax(np.abs(r_eu))] == 3
    figure = plotting.residual_correlation(e, u, max_lag=10, title="residuals")
    cross = figure.axes[1]
    drawn = line(cross, "cross-correlation")
    assert drawn.get_xdata()[np.argmax(drawn.get_ydata())] == 3
    assert "k > 0: input leads residual" in cross.get_xlabel()
    texts_inside_canvas(figure)


def test_the_report_draws_the_same_correlations(record, estimate):
    report = ctid.validate_model(estimate.model, record, max_lag=12)
    figure = plotting.residual_correlation(report)
    auto, cross = figure.axes
    np.testing.assert_array_equal(line(auto, "autocorrelation").get_xdata(), np.arange(1, 13))
    np.testing.assert_array_equal(line(auto, "autocorrelation").get_ydata(),
                                  report.residual_autocorrelation)
    np.testing.assert_array_equal(line(cross, "cross-correlation").get_xdata(),
                                  np.arange(-12, 13))
    np.testing.assert_array_equal(line(cross, "cross-correlation").get_ydata(),
                                  report.cross_correlation)
    # Same sign convention as plotting.correlations on the residual itself.
    residual = record.output - ctid.model_output(estimate.model, record.input, H)
    ours = plotting.correlations(residual, record.input, max_lag=12)[3]
    np.testing.assert_allclose(report.cross_correlation, ours, atol=1e-9)
    texts_inside_canvas(figure)


def test_the_remaining_figures_keep_their_text_on_the_canvas(mimo):
    model, _, data = mimo
    modes = ctid.mimo_srivc(data, [ctid.SubmodelOrder(2, 0)] * 2, max_iterations=30).modes
    names = [f"accelerometer {k + 1}" for k in range(model.outputs)]
    figures = [
        plotting.mode_shapes(modes, output_names=names, title="shapes"),
        plotting.mac_matrix(modes, title="MAC"),
        plotting.channel_fits(names, {"model": [90.0, 80.0, 70.0], "bound": [95, 85, 75]},
                              title="fits"),
        plotting.mse_against_n([
            {"estimator": "srivc", "N": n, "parameter": p, "mse": 1.0 / n,
             "predicted_mse": 0.9 / n} for n in (100, 1000) for p in ("a1", "a2", "b0")],
            title="MSE"),
    ]
    for figure in figures:
        texts_inside_canvas(figure)


@pytest.mark.parametrize("unit", ["Hz", "rad/s"])
def test_mode_tracking_draws_each_track_in_the_unit_on_the_canvas(record, unit):
    options = ctid.TrackingOptions(window=256 * H)
    options.identification.refined_iv.initial_conditions = ctid.InitialConditions.estimate
    result = ctid.track_modes(record, ctid.ModelStructure.modes(1), options)
    assert len(result.windows) == 8 and len(result.tracks) == 1
    figure = plotting.mode_tracking(result, title="tracking of a long title " * 3,
                                    frequency_unit=unit)
    top, bottom = figure.axes[:2]
    assert top.get_ylabel() == f"natural frequency [{unit}]"
    line = top.get_lines()[0]
    np.testing.assert_allclose(line.get_xdata(), [w.centre_time for w in result.windows])
    np.testing.assert_allclose(to_rad_per_s(line.get_ydata(), unit),
                               result.tracks[0].natural_frequency, rtol=1e-12)
    np.testing.assert_allclose(bottom.get_lines()[0].get_ydata(), result.tracks[0].damping_ratio)
    texts_inside_canvas(figure)


def test_mode_tracking_shades_windows_without_a_usable_model():
    nan = float("nan")
    document = {
        "windows": [{"centre_time": t, "verdict": {"usable": ok}}
                    for t, ok in ((5.0, True), (15.0, False), (25.0, True))],
        "tracks": [{"natural_frequency": [6.0, nan, 6.1],
                    "natural_frequency_se": [0.1, nan, None],
                    "damping_ratio": [0.02, nan, 0.021],
                    "damping_ratio_se": [0.001, nan, 0.001]}],
    }
    figure = plotting.mode_tracking(document)
    top = figure.axes[0]
    np.testing.assert_allclose(top.get_lines()[0].get_ydata(), np.array([6.0, 6.1]) / (2 * np.pi))
    labels = [p.get_label() for p in top.patches]
    assert labels.count("no usable model") == 1
    texts_inside_canvas(figure)


def test_unknown_frequency_unit_is_refused(estimate):
    with pytest.raises(ValueError, match="frequency_unit is 'Hertz'"):
        plotting.bode(estimate, frequency_unit="Hertz")


def test_wrap_phase_range():
    wrapped = plotting.wrap_phase([-540.0, -180.0, 0.0, 180.0, 181.0, 720.0 + 179.0])
    np.testing.assert_allclose(wrapped, [180.0, 180.0, 0.0, 180.0, -179.0, 179.0])
    assert math.isclose(plotting.wrap_phase(-179.5), -179.5)
