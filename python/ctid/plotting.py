"""Figures for ctid results, drawn with matplotlib.

Importing this module leaves matplotlib's backend as it is (an interactive session keeps its
windows and ``plt.show()``); without a display matplotlib picks a file backend itself, and
``python3 -m ctid.plot`` (what ``ctid --plot`` runs) chooses Agg.

Every function returns the :class:`matplotlib.figure.Figure` and, given ``filename``
(``.png`` or ``.svg``), also saves it there. Frequencies given to these functions are in rad/s
(the library's unit); the figures' frequency axes are in Hz unless ``frequency_unit="rad/s"``
is asked. Magnitudes are in dB, phases in degrees. Lines carry labels ("model", "FRF",
"measured", ...) so callers and tests can find them again with ``line.get_label()``.

Rules every figure keeps (python/tests/test_figure_rules.py checks them):

- A model's phase is unwrapped along its own dense grid (a continuous curve, so unwrapping is
  coherent) and starts in (-180, 180] deg; a measured FRF's phase is put on the model's branch
  when a model is drawn, and is otherwise wrapped to (-180, 180] deg (unwrapping noisy,
  sparse lines would invent turns).
- The default frequency range covers the measured lines and every resonance of the model
  (complex poles with damping ratio below 0.5), so a mode outside the data's band is seen.
- Where the coherence of an FRF is known, the frequencies where it is below 0.5 are shaded
  ("coherence < 0.5") behind the FRF.
- Layout is matplotlib's constrained layout: no label is cut off at the canvas edge.

Confidence bands of a Bode plot come from the parameter covariance P by first-order
propagation (the delta method): the Jacobian J = dG(jw)/dtheta is taken by central finite
differences of the model's frequency response (step 1e-6 |theta_i|, or 1e-9 for a zero
parameter), then var|G| = g' P g with g = Re(conj(G) J) / |G| and var(arg G) = h' P h with
h = Im(J / G), computed by the library (ctid.frequency_response_band, C++
frequency/response_band.h). The band is |G| +- z sigma (z the two-sided normal quantile of
``confidence``), drawn in dB, and arg G +- z sigma in degrees. The residual correlations come
from the library too (ctid.residual_correlations), as validate_model's report does.
"""

from __future__ import annotations

import math
from statistics import NormalDist

import matplotlib.pyplot as plt
import numpy as np

from . import _ctid

__all__ = [
    "bode",
    "channel_fits",
    "frf",
    "frf_matrix",
    "frf_matrix_overlay",
    "mode_shapes",
    "mac_matrix",
    "modes",
    "validation",
    "compare",
    "residual_correlation",
    "noise_spectrum",
    "mse_against_n",
    "mode_tracking",
    "stabilisation",
    "oma_stabilisation",
    "frequency_response_band",
    "correlations",
    "response_curve",
    "step",
    "impulse",
    "save",
]

_FORMATS = (".png", ".svg")


def save(figure, filename):
    """Save ``figure`` to ``filename`` (.png or .svg, chosen by the extension).

    Raises ValueError for any other extension.
    """
    name = str(filename)
    if not name.lower().endswith(_FORMATS):
        raise ValueError(f"save: '{name}' must end in .png or .svg")
    figure.savefig(name, dpi=110)
    return figure


def _figure(*args, **kwargs):
    """plt.subplots with constrained layout (labels, titles and legends kept on the canvas)."""
    kwargs.setdefault("layout", "constrained")
    figure, axes = plt.subplots(*args, **kwargs)
    figure._ctid_created = True
    return figure, axes


def _axes_or_new(ax, count, *args, **kwargs):
    """(figure, axes): the axes the caller gave (``ax``: one Axes, or a sequence of ``count``
    of them for a figure of several panels), drawn into as they are, or a new figure's."""
    if ax is None:
        return _figure(*args, **kwargs)
    given = [ax] if count == 1 else list(ax) if isinstance(ax, (list, tuple, np.ndarray)) else []
    if len(given) != count or not all(hasattr(a, "plot") and hasattr(a, "figure") for a in given):
        what = "a matplotlib Axes" if count == 1 else f"a sequence of {count} matplotlib Axes"
        raise TypeError(f"ax: expected {what}, got {type(ax).__name__}")
    return given[0].figure, given[0] if count == 1 else tuple(given)


def _finish(figure, filename):
    # A figure of the caller's (drawn into through ax=) keeps its layout.
    if getattr(figure, "_ctid_created", False) and figure.get_layout_engine() is None:
        figure.set_layout_engine("constrained")
    if filename is not None:
        save(figure, filename)
    return figure


_FREQUENCY_UNITS = ("Hz", "rad/s")


def _frequency_axis(frequency_unit, where):
    """(factor from rad/s to the axis unit, axis label) for frequency_unit 'Hz' or 'rad/s'."""
    if frequency_unit not in _FREQUENCY_UNITS:
        raise ValueError(f"{where}: frequency_unit is {frequency_unit!r}; it must be 'Hz' or "
                         "'rad/s'")
    factor = 1.0 / (2.0 * np.pi) if frequency_unit == "Hz" else 1.0
    return factor, f"frequency [{frequency_unit}]"


def wrap_phase(degrees):
    """Phase in degrees wrapped to (-180, 180]."""
    return 180.0 - np.mod(180.0 - np.asarray(degrees, dtype=float), 360.0)


def _model_phase(response):
    """The phase [deg] of a model's response on a dense grid, unwrapped along the grid (a
    continuous curve) and starting in (-180, 180]."""
    return np.degrees(np.unwrap(np.angle(np.asarray(response))))


def _on_branch(measured_phase, w, model_w, model_phase):
    """Measured phases [deg] moved by whole turns to lie nearest the model's curve."""
    if len(model_w) < 2:
        return wrap_phase(measured_phase)
    reference = np.interp(np.log(w), np.log(model_w), model_phase)
    return measured_phase + 360.0 * np.round((reference - measured_phase) / 360.0)


def _shade_low_coherence(axes, frequencies, coherence, threshold=0.5):
    """Shades, on every axis, the frequency bands (axis units) where the coherence is below
    ``threshold``; each run of low lines reaches halfway (geometrically) to its neighbours.
    The first span carries the label "coherence < threshold". Returns the number of runs."""
    f = np.asarray(frequencies, dtype=float)
    c = np.asarray(coherence, dtype=float)
    if f.size == 0 or c.size != f.size:
        return 0
    low = ~(c >= threshold)  # NaN (unknown) counts as low
    positive = f > 0
    low &= positive
    if not low.any():
        return 0
    edges = np.empty(f.size + 1)
    inner = np.sqrt(np.maximum(f[:-1], 1e-300) * np.maximum(f[1:], 1e-300))
    edges[1:-1] = inner
    edges[0] = f[0] / (inner[0] / f[0]) if f.size > 1 and f[0] > 0 else f[0]
    edges[-1] = f[-1] * (f[-1] / inner[-1]) if f.size > 1 else f[-1]
    runs = 0
    k = 0
    while k < f.size:
        if not low[k]:
            k += 1
            continue
        start = k
        while k + 1 < f.size and low[k + 1]:
            k += 1
        for n, ax in enumerate(axes):
            ax.axvspan(edges[start], edges[k + 1], color="0.5", alpha=0.15, lw=0, zorder=0,
                       label=f"coherence < {threshold:g}" if runs == 0 and n == 0 else None)
        runs += 1
        k += 1
    return runs


def _resonances(model):
    """Natural frequencies [rad/s] of the model's resonant poles: complex pairs with damping
    ratio below 0.5 (the poles of an AdditiveModel, TransferFunction or MimoAdditiveModel)."""
    if isinstance(model, _ctid.MimoAdditiveModel):
        poles = []
        for sub in model.submodels:
            poles.extend(np.roots(np.asarray(sub.a.coefficients, dtype=float)[::-1]))
        poles = np.asarray(poles, dtype=complex)
    else:
        g = model.to_transfer_function() if isinstance(model, _ctid.AdditiveModel) else model
        poles = np.asarray(g.poles(), dtype=complex)
    radius = np.abs(poles)
    keep = (np.abs(poles.imag) > 0) & (radius > 0)
    damping = -poles.real[keep] / radius[keep]
    return np.unique(radius[keep][damping < 0.5])


def _cover(low, high, model):
    """[low, high] widened to hold every resonance of ``model`` with a factor 1.5 around it."""
    for w in _resonances(model):
        low, high = min(low, w / 1.5), max(high, w * 1.5)
    return low, high


def _as_model(model):
    """(AdditiveModel or TransferFunction, covariance or None)."""
    if isinstance(model, _ctid.EstimationResult):
        cov = np.asarray(model.covariance)
        return model.model, (cov if cov.size else None)
    if isinstance(model, (_ctid.AdditiveModel, _ctid.TransferFunction)):
        return model, None
    raise TypeError(
        "expected an EstimationResult, AdditiveModel or TransferFunction, got "
        + type(model).__name__
    )


def _default_omegas(model, frf=None, count=400):
    """The model's grid [rad/s]: the FRF's lines widened to the model's resonances, or, without
    an FRF, a decade beyond the poles on either side."""
    w = np.asarray(frf.frequencies, dtype=float) if frf is not None else np.zeros(0)
    w = w[w > 0]
    if w.size:
        low, high = _cover(w.min(), w.max(), model)
        return np.logspace(np.log10(low), np.log10(high), count)
    g = model.to_transfer_function() if isinstance(model, _ctid.AdditiveModel) else model
    poles = np.abs(np.asarray(g.poles()))
    poles = poles[poles > 0]
    if poles.size == 0:
        lo, hi = 0.1, 10.0
    else:
        lo, hi = poles.min() / 10.0, poles.max() * 10.0
    return np.logspace(np.log10(lo), np.log10(hi), count)


def frequency_response_band(model, omegas, covariance=None, confidence=0.95):
    """Frequency response of ``model`` with its first-order standard deviations.

    ``model`` is an EstimationResult (its covariance is used unless ``covariance`` is given)
    or an AdditiveModel (then ``covariance`` is that of ``model.parameters()``). Returns
    ``(response, magnitude_sigma, phase_sigma_rad, z)``; the sigmas are None without a
    covariance. See the module docstring for the propagation.
    """
    base, cov = _as_model(model)
    if covariance is not None:
        cov = np.asarray(covariance, dtype=float)
    omegas = np.asarray(omegas, dtype=float)
    z = NormalDist().inv_cdf(0.5 + confidence / 2.0)
    if cov is None or not isinstance(base, _ctid.AdditiveModel):
        return np.asarray(_ctid.frequency_response(base, omegas)), None, None, z
    size = len(base.parameters())
    if cov.shape != (size, size):
        raise ValueError(
            f"frequency_response_band: covariance is {cov.shape[0]}x{cov.shape[1]} but the "
            f"model has {size} parameters"
        )
    response, mag_sigma, phase_sigma = _ctid.frequency_response_band(base, omegas, cov)
    return np.asarray(response), np.asarray(mag_sigma), np.asarray(phase_sigma), z


def _db(x):
    return 20.0 * np.log10(np.maximum(np.abs(x), 1e-300))


def bode(model, frf=None, covariance=None, omegas=None, confidence=0.95, title=None,
         filename=None, sampled=None, frequency_unit="Hz", more=None, ax=None):
    """Bode plot of a fitted model over a nonparametric FRF, with confidence bands.

    ``model``: EstimationResult (its covariance gives the band), AdditiveModel or
    TransferFunction. ``frf``: a ctid.Frf (or any object with ``frequencies`` [rad/s] and
    ``response``, optionally ``coherence``) drawn as markers, its phase put on the model's
    branch; where its coherence is below 0.5 the band is shaded. ``omegas``: the model's grid
    [rad/s] (default: the FRF's range widened to the model's resonances, or a decade around
    the poles). ``sampled``: (h, ctid.Hold) of the data behind the FRF, to draw also the model
    as the samples see it (ctid.sampled_frequency_response: the hold and the sampling
    included), which is what an FRF of sampled data estimates. ``frequency_unit``: "Hz"
    (default) or "rad/s" for the axis. ``more``: further (label, model) pairs drawn as lines
    over the same grid (e.g. the feedback path beside the forward one). Lines: "model", "FRF",
    "model, sampled (zoh|foh)", the labels of ``more``; bands: "<confidence>% band". Returns
    the Figure (saved to ``filename`` if given).
    """
    base, _ = _as_model(model)
    factor, axis_label = _frequency_axis(frequency_unit, "bode")
    if omegas is None:
        omegas = _default_omegas(base, frf)
    omegas = np.asarray(omegas, dtype=float)
    response, mag_sigma, phase_sigma, z = frequency_response_band(
        model, omegas, covariance, confidence)
    figure, (ax_mag, ax_phase) = _axes_or_new(ax, 2, 2, 1, sharex=True, figsize=(7.0, 6.0))
    x = omegas * factor
    phase = _model_phase(response)
    band_label = f"{100 * confidence:g}% band"
    if mag_sigma is not None:
        magnitude = np.abs(response)
        lower = np.maximum(magnitude - z * mag_sigma, magnitude * 1e-6)
        ax_mag.fill_between(x, _db(lower), _db(magnitude + z * mag_sigma), alpha=0.3,
                            color="C0", label=band_label, linewidth=0)
        ax_phase.fill_between(x, phase - np.degrees(z * phase_sigma),
                              phase + np.degrees(z * phase_sigma), alpha=0.3, color="C0",
                              label=band_label, linewidth=0)
    ax_mag.semilogx(x, _db(response), color="C0", label="model")
    ax_phase.semilogx(x, phase, color="C0", label="model")
    shown = [_db(response)]
    for k, (label, other) in enumerate(more or []):
        other_base, _ = _as_model(other)
        g = np.asarray(_ctid.frequency_response(other_base, omegas))
        ax_mag.semilogx(x, _db(g), color=f"C{k + 3}", label=label)
        ax_phase.semilogx(x, _model_phase(g), color=f"C{k + 3}", label=label)
        shown.append(_db(g))
    if sampled is not None:
        h, hold = sampled
        additive = (base if isinstance(base, _ctid.AdditiveModel)
                    else _ctid.AdditiveModel.from_transfer_function(base))
        seen_at = omegas[omegas < math.pi / h]
        seen = np.asarray(_ctid.sampled_frequency_response(additive, seen_at, h, hold))
        name = "zoh" if hold == _ctid.Hold.zero_order_hold else "foh"
        seen_phase = np.degrees(np.unwrap(np.angle(seen)))
        if seen.size:
            seen_phase += 360.0 * np.round((phase[0] - seen_phase[0]) / 360.0)
        ax_mag.semilogx(seen_at * factor, _db(seen), "--", color="C2",
                        label=f"model, sampled ({name})")
        ax_phase.semilogx(seen_at * factor, seen_phase, "--", color="C2",
                          label=f"model, sampled ({name})")
    if frf is not None:
        w = np.asarray(frf.frequencies, dtype=float)
        g = np.asarray(frf.response)
        coherence = np.asarray(getattr(frf, "coherence", []), dtype=float)
        _shade_low_coherence((ax_mag, ax_phase), w * factor, coherence)
        ax_mag.semilogx(w * factor, _db(g), "o", ms=2.5, color="C1", label="FRF")
        # The FRF's phase on the model's branch, so the two can be compared by eye.
        frf_phase = _on_branch(np.degrees(np.angle(g)), w, omegas, phase)
        ax_phase.semilogx(w * factor, frf_phase, "o", ms=2.5, color="C1", label="FRF")
        shown.append(_db(g))
    # The axis follows the model and the FRF, not the band: a band reaching to |G| ~ 0 near an
    # antiresonance would otherwise squash the plot to a few pixels.
    shown = np.concatenate([v[np.isfinite(v)] for v in shown])
    if shown.size:
        ax_mag.set_ylim(shown.min() - 10.0, shown.max() + 10.0)
    ax_mag.set_ylabel("magnitude [dB]")
    ax_phase.set_ylabel("phase [deg]")
    ax_phase.set_xlabel(axis_label)
    for ax in (ax_mag, ax_phase):
        ax.grid(True, which="both", alpha=0.3)
    ax_mag.legend(fontsize=8)
    if title:
        ax_mag.set_title(title)
    return _finish(figure, filename)


def frf(estimate, title=None, filename=None, frequency_unit="Hz", coherence_threshold=0.5):
    """A nonparametric FRF on its own: magnitude (dB), phase (deg, wrapped to (-180, 180]: with
    no model to follow, unwrapping noisy lines would invent turns) and, when the estimate has
    one, the squared coherence, the lines below ``coherence_threshold`` shaded in every panel.

    ``estimate``: a ctid.Frf or any object with ``frequencies`` [rad/s], complex ``response``
    and optionally ``coherence``. ``frequency_unit``: "Hz" (default) or "rad/s". Lines: "FRF"
    in each panel, "coherence". Returns the Figure.
    """
    factor, axis_label = _frequency_axis(frequency_unit, "frf")
    w = np.asarray(estimate.frequencies, dtype=float)
    g = np.asarray(estimate.response)
    coherence = np.asarray(getattr(estimate, "coherence", []), dtype=float)
    coherent = coherence.size == w.size and w.size > 0
    figure, axes = _figure(3 if coherent else 2, 1, sharex=True,
                           figsize=(7.0, 7.0 if coherent else 5.5))
    x = w * factor
    if coherent:
        _shade_low_coherence(axes, x, coherence, coherence_threshold)
    axes[0].semilogx(x, _db(g), ".-", ms=3, lw=0.8, label="FRF")
    axes[0].set_ylabel("magnitude [dB]")
    axes[1].semilogx(x, wrap_phase(np.degrees(np.angle(g))), ".", ms=3, label="FRF")
    axes[1].set_ylabel("phase [deg]")
    axes[1].set_ylim(-190.0, 190.0)
    axes[1].set_yticks([-180, -90, 0, 90, 180])
    if coherent:
        axes[2].semilogx(x, coherence, ".-", ms=3, lw=0.8, label="coherence")
        axes[2].set_ylabel("coherence")
        axes[2].set_ylim(0.0, 1.05)
        if (coherence < coherence_threshold).any():
            axes[0].legend(fontsize=8)
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[-1].set_xlabel(axis_label)
    if title:
        axes[0].set_title(title)
    return _finish(figure, filename)


def _mimo_frf_arrays(estimate, where):
    """(input names, output names, frequencies [rad/s], response (lines, n_y, n_u), coherence
    (lines, n_y)) of a ctid.MimoFrf or of the "mimo_frf" document `ctid frf -o X.json` writes."""
    if isinstance(estimate, dict):
        if estimate.get("type") != "mimo_frf":
            raise ValueError(f"{where}: expected a mimo_frf document, got type "
                             f"{estimate.get('type')!r}")
        pairs = np.array(estimate["response"], dtype=float)  # (lines, n_y, n_u, 2); null -> nan
        response = pairs[..., 0] + 1j * pairs[..., 1]
        return (list(estimate["inputs"]), list(estimate["outputs"]),
                np.asarray(estimate["frequencies"], dtype=float), response,
                np.asarray(estimate["coherence"], dtype=float))
    return (list(estimate.input_names), list(estimate.output_names),
            np.asarray(estimate.frequencies, dtype=float), np.asarray(estimate.response),
            np.asarray(estimate.coherence, dtype=float))


def frf_matrix(estimate, channels=None, max_outputs=4, title=None, filename=None,
               frequency_unit="Hz"):
    """Chosen channels of an FRF matrix over frequency in Hz: |H_ji| (dB) of each, and below
    the multiple coherence of each chosen output with all inputs.

    ``estimate``: a ctid.MimoFrf or the "mimo_frf" document of ``ctid frf -o X.json`` (a dict).
    ``channels``: (output name, input name) pairs; default every input of the first
    ``max_outputs`` outputs. ``frequency_unit``: "Hz" (default) or "rad/s". Lines:
    "<output>/<input>" and "coherence <output>". Returns the Figure.
    """
    factor, axis_label = _frequency_axis(frequency_unit, "frf_matrix")
    inputs, outputs, w, response, coherence = _mimo_frf_arrays(estimate, "frf_matrix")
    hz = w * factor
    if channels is None:
        channels = [(y, u) for y in outputs[:max_outputs] for u in inputs]
    figure, axes = _figure(2, 1, sharex=True, figsize=(8.0, 6.5),
                           gridspec_kw={"height_ratios": [2, 1]})
    shown = []
    for output, input_name in channels:
        if output not in outputs or input_name not in inputs:
            raise ValueError(f"frf_matrix: no channel {output}/{input_name}; outputs "
                             f"{', '.join(outputs)}, inputs {', '.join(inputs)}")
        j, i = outputs.index(output), inputs.index(input_name)
        axes[0].semilogx(hz, _db(response[:, j, i]), lw=0.8, label=f"{output}/{input_name}")
        if output not in shown:
            shown.append(output)
            axes[1].semilogx(hz, coherence[:, j], lw=0.8, label=f"coherence {output}")
    axes[0].set_ylabel("|H| [dB]")
    axes[1].set_ylabel("multiple coherence")
    axes[1].set_ylim(0.0, 1.05)
    axes[1].set_xlabel(axis_label)
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize="small", ncol=2)
    if title:
        axes[0].set_title(title)
    return _finish(figure, filename)


def _channel_index(name_or_index, names, kind, where):
    """Position of a channel given by name or by 0-based index."""
    if isinstance(name_or_index, (int, np.integer)) and not isinstance(name_or_index, bool):
        if not 0 <= name_or_index < len(names):
            raise ValueError(
                f"{where}: {kind} index {name_or_index} is outside 0..{len(names) - 1}")
        return int(name_or_index)
    if name_or_index not in names:
        raise ValueError(f"{where}: no {kind} {name_or_index!r}; {kind}s are {', '.join(names)}")
    return names.index(name_or_index)


def frf_matrix_overlay(model, frf, channels=None, title=None, filename=None, omegas=None,
                       max_channels=4, frequency_unit="Hz"):
    """Chosen channels of a measured FRF matrix with a MIMO model's frequency response over
    them: for each channel |H_ji| in dB above its phase in degrees, over frequency in Hz.

    ``model``: a ctid.MimoAdditiveModel or a ctid.MimoEstimationResult (its model); channel
    (j, i) is ``model.channel(j, i)``, the direct term included. ``frf``: a ctid.MimoFrf (e.g.
    ``ctid.welch_frf(mimo_data)``) or the "mimo_frf" document of ``ctid frf -o X.json``, with
    as many inputs and outputs as the model. ``channels``: (output, input) pairs, each a name
    of the FRF's channels or a 0-based index; default the ``max_channels`` channels with the
    largest peak |H_ji| in the FRF, largest first. ``omegas``: the model's grid [rad/s]
    (default 400 points over the FRF's lines, widened to the model's resonances).
    ``frequency_unit``: "Hz" (default) or "rad/s". Where the output's multiple coherence is
    below 0.5 the channel's axes are shaded. The axes come in pairs (magnitude, phase), one
    pair per channel in the order of ``channels``, the magnitude axis titled
    "<output>/<input>"; each holds the lines "model" and "FRF" (the FRF's phase put on the
    model's branch). Returns the Figure.
    """
    if isinstance(model, _ctid.MimoEstimationResult):
        if model.model is None:
            raise ValueError("frf_matrix_overlay: the result holds no model")
        model = model.model
    if not isinstance(model, _ctid.MimoAdditiveModel):
        raise TypeError("frf_matrix_overlay: expected a MimoAdditiveModel or "
                        "MimoEstimationResult, got " + type(model).__name__)
    factor, axis_label = _frequency_axis(frequency_unit, "frf_matrix_overlay")
    inputs, outputs, w, response, coherence = _mimo_frf_arrays(frf, "frf_matrix_overlay")
    if response.shape[1:] != (model.outputs, model.inputs):
        raise ValueError(
            f"frf_matrix_overlay: the FRF is {response.shape[1]} outputs x {response.shape[2]} "
            f"inputs but the model {model.outputs} x {model.inputs}")
    if channels is None:
        with np.errstate(invalid="ignore"):
            peaks = np.nanmax(np.abs(response), axis=0) if w.size else np.zeros(
                response.shape[1:])
        peaks = np.where(np.isfinite(peaks), peaks, -np.inf)
        order = np.argsort(-peaks, axis=None, kind="stable")[:max_channels]
        pairs = [tuple(int(v) for v in np.unravel_index(k, peaks.shape)) for k in order]
    else:
        pairs = [(_channel_index(y, outputs, "output", "frf_matrix_overlay"),
                  _channel_index(u, inputs, "input", "frf_matrix_overlay"))
                 for y, u in channels]
    if not pairs:
        raise ValueError("frf_matrix_overlay: no channel to draw")
    if omegas is None:
        positive = w[w > 0]
        if positive.size == 0:
            raise ValueError("frf_matrix_overlay: the FRF has no line above 0 rad/s; give omegas")
        low, high = _cover(positive.min(), positive.max(), model)
        omegas = np.logspace(np.log10(low), np.log10(high), 400)
    omegas = np.asarray(omegas, dtype=float)
    columns = 1 if len(pairs) == 1 else 2
    rows = math.ceil(len(pairs) / columns)
    # Each channel's two axes share a cell of the outer grid, so magnitude and phase sit close
    # together and the space goes between channels (constrained layout; tight_layout cannot
    # lay out nested grids).
    figure = plt.figure(figsize=(6.0 * columns, 4.2 * rows + (0.4 if title else 0.0)),
                        layout="constrained")
    outer = figure.add_gridspec(rows, columns)
    for c, (j, i) in enumerate(pairs):
        row, column = divmod(c, columns)
        cell = outer[row, column].subgridspec(2, 1, height_ratios=[2, 1], hspace=0.05)
        ax_mag = figure.add_subplot(cell[0])
        ax_phase = figure.add_subplot(cell[1], sharex=ax_mag)
        g = np.asarray(_ctid.frequency_response(model.channel(j, i), omegas))
        phase = _model_phase(g)
        measured = response[:, j, i]
        measured_phase = _on_branch(np.degrees(np.angle(measured)), w, omegas, phase)
        if coherence.shape[:1] == w.shape and coherence.ndim == 2:
            _shade_low_coherence((ax_mag, ax_phase), w * factor, coherence[:, j])
        ax_mag.semilogx(w * factor, _db(measured), "o", ms=2.0, color="C1", label="FRF")
        ax_mag.semilogx(omegas * factor, _db(g), color="C0", lw=1.2, label="model")
        ax_phase.semilogx(w * factor, measured_phase, "o", ms=2.0, color="C1", label="FRF")
        ax_phase.semilogx(omegas * factor, phase, color="C0", lw=1.2, label="model")
        ax_mag.set_title(f"{outputs[j]}/{inputs[i]}", fontsize=9)
        ax_mag.set_ylabel("|H| [dB]")
        ax_phase.set_ylabel("phase [deg]")
        ax_phase.set_xlabel(axis_label)
        ax_mag.tick_params(labelbottom=False)
        for ax in (ax_mag, ax_phase):
            ax.grid(True, which="both", alpha=0.3)
        if c == 0:
            ax_mag.legend(fontsize=7)
    if title:
        figure.suptitle(title)
    if filename is not None:
        save(figure, filename)
    return figure


def _mimo_modes(result_or_modes, where):
    """The modes of a MimoEstimationResult, or the modes given (ctid.MimoMode, or any objects
    with its fields)."""
    modes = list(getattr(result_or_modes, "modes", result_or_modes))
    for m in modes:
        if not (hasattr(m, "shape") and hasattr(m, "natural_frequency")):
            raise TypeError(f"{where}: expected a MimoEstimationResult or MimoMode objects, got "
                            + type(m).__name__)
    return modes


def _plus_minus(value, error, digits=5):
    text = f"{value:.{digits}g}"
    if error is not None and math.isfinite(error):
        text += f" ± {error:.2g}"
    return text


def _mode_label(mode):
    return f"{mode.submodel + 1}: {mode.natural_frequency / (2.0 * np.pi):.4g} Hz"


def mode_shapes(result_or_modes, output_names=None, geometry=None, title=None, filename=None):
    """Each mode's shape over the outputs (sensors), one panel per mode.

    ``result_or_modes``: a ctid.MimoEstimationResult or a list of ctid.MimoMode (or objects
    with its fields: submodel, natural_frequency, damping_ratio, their *_se, shape,
    shape_se_real, rank_one_share). A shape is
    scaled to unit length with its largest entry real and positive (mimo_srivc.h); drawn are
    its real part, "Re(shape)", with error bars of one standard error (``shape_se_real``,
    where finite), and its magnitude signed by the phase (+|psi_j| when |arg psi_j| <= 90 deg,
    else -|psi_j|), "|shape|, signed": for a real (classically damped) mode the two coincide.
    ``output_names``: one per output (default 1, 2, ...) for the x ticks. ``geometry``: a 1-D
    position per output used as the x axis instead of the index (the points joined in the
    order of position). Each panel is titled with the mode's f_n [Hz] and zeta, each with its
    standard error, and its rank-one share. One axis per mode, in the modes' order. Returns the
    Figure.
    """
    modes = _mimo_modes(result_or_modes, "mode_shapes")
    if not modes:
        raise ValueError("mode_shapes: no modes to draw (the model has no second-order submodel)")
    outputs = len(modes[0].shape)
    names = ([str(j + 1) for j in range(outputs)] if output_names is None
             else [str(n) for n in output_names])
    if len(names) != outputs:
        raise ValueError(f"mode_shapes: {len(names)} output names for {outputs} outputs")
    if geometry is None:
        x = np.arange(1.0, outputs + 1.0)
    else:
        x = np.asarray(geometry, dtype=float).ravel()
        if x.size != outputs or not np.all(np.isfinite(x)):
            raise ValueError(f"mode_shapes: geometry needs {outputs} finite positions, one per "
                             f"output; got {x.size}")
    order = np.argsort(x, kind="stable")
    columns = 1 if len(modes) == 1 else 2
    rows = math.ceil(len(modes) / columns)
    figure, axes = _figure(rows, columns, figsize=(6.0 * columns, 3.0 * rows + 0.5),
                                squeeze=False)
    for ax in list(axes.flat)[len(modes):]:
        ax.remove()
    for ax, mode in zip(axes.flat, modes):
        if len(mode.shape) != outputs:
            raise ValueError("mode_shapes: the modes' shapes differ in length")
        shape = np.asarray(mode.shape)[order]
        signed = np.abs(shape) * np.where(np.cos(np.angle(shape)) >= 0.0, 1.0, -1.0)
        se = np.asarray(mode.shape_se_real, dtype=float)
        se = se[order] if se.size == outputs else np.full(outputs, np.nan)
        ax.axhline(0.0, color="0.6", lw=0.6)
        ax.plot(x[order], shape.real, "o-", ms=4, lw=1.2, color="C0", label="Re(shape)")
        finite = np.isfinite(se)
        if finite.any():
            ax.errorbar(x[order][finite], shape.real[finite], yerr=se[finite], fmt="none",
                        ecolor="C0", capsize=3, lw=0.8, label="± 1 se")
        ax.plot(x[order], signed, "s", ms=6, mfc="none", color="C3", label="|shape|, signed")
        hz = 2.0 * np.pi
        ax.set_title(
            f"mode {mode.submodel + 1}: f_n = "
            f"{_plus_minus(mode.natural_frequency / hz, mode.natural_frequency_se / hz)} Hz, "
            f"ζ = {_plus_minus(mode.damping_ratio, mode.damping_ratio_se, 4)}\n"
            + (f"MPC {mode.mpc:.3g}" if hasattr(mode, "mpc")
               else f"rank-one share {mode.rank_one_share:.3g}"), fontsize=9)
        if geometry is None:
            ax.set_xticks(x)
            ax.set_xticklabels(names, rotation=90 if outputs > 8 else 0,
                               fontsize=7 if outputs > 8 else 9)
            ax.set_xlabel("output")
        else:
            ax.set_xlabel("position")
        ax.set_ylabel("shape")
        ax.grid(True, alpha=0.3)
    figure.axes[0].legend(fontsize=7)
    if title:
        figure.suptitle(title)
    return _finish(figure, filename)


def mac_matrix(modes_a, modes_b=None, labels=None, column_labels=None, title=None,
               filename=None, ax=None):
    """The modal assurance criterion MAC(a, b) = |a^H b|^2 / ((a^H a)(b^H b)) as an annotated
    heat map (ctid.modal_assurance), between the modes of one estimate (``modes_b`` None: a
    well-separated set has a MAC near the identity) or between two estimates of the same
    outputs (e.g. fits of two halves of a record: a mode found in both has a MAC near 1).

    ``modes_a``, ``modes_b``: ctid.MimoEstimationResult or lists of ctid.MimoMode (rows and
    columns; shapes of equal length). ``labels``, ``column_labels``: tick labels (default
    "<submodel>: <f_n> Hz"; the columns take ``labels`` when ``modes_b`` is None). The image's
    array is the MAC matrix and every cell carries its value to two decimals. Returns the
    Figure.
    """
    rows = _mimo_modes(modes_a, "mac_matrix")
    cols = rows if modes_b is None else _mimo_modes(modes_b, "mac_matrix")
    if not rows or not cols:
        raise ValueError("mac_matrix: no modes to compare")
    mac = np.array([[_ctid.modal_assurance(np.asarray(a.shape, dtype=complex),
                                           np.asarray(b.shape, dtype=complex)) for b in cols]
                    for a in rows], dtype=float)
    row_labels = [_mode_label(m) for m in rows] if labels is None else [str(v) for v in labels]
    if column_labels is None:
        column_labels = (row_labels if modes_b is None and labels is not None
                         else [_mode_label(m) for m in cols])
    column_labels = [str(v) for v in column_labels]
    if len(row_labels) != len(rows) or len(column_labels) != len(cols):
        raise ValueError(f"mac_matrix: {len(row_labels)} x {len(column_labels)} labels for "
                         f"{len(rows)} x {len(cols)} modes")
    figure, ax = _axes_or_new(ax, 1, figsize=(max(4.5, 2.4 + 0.8 * len(cols)),
                                       max(3.5, 1.6 + 0.55 * len(rows))))
    image = ax.imshow(mac, vmin=0.0, vmax=1.0, cmap="Blues", aspect="auto")
    for r in range(mac.shape[0]):
        for c in range(mac.shape[1]):
            ax.text(c, r, f"{mac[r, c]:.2f}", ha="center", va="center", fontsize=8,
                    color="white" if mac[r, c] > 0.6 else "black")
    ax.set_xticks(range(len(cols)))
    ax.set_xticklabels(column_labels, rotation=45, ha="right", fontsize=8)
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(row_labels, fontsize=8)
    ax.set_ylabel("mode" if modes_b is None else "modes of the first estimate")
    ax.set_xlabel("mode" if modes_b is None else "modes of the second estimate")
    figure.colorbar(image, ax=ax, label="MAC")
    if title:
        ax.set_title(title)
    return _finish(figure, filename)


def channel_fits(names, fits, title=None, filename=None, ax=None):
    """Fit [%] per channel (x: the channels in order) for several models or bounds side by
    side: ``fits`` maps a label to one value per channel (NaN: not available). Returns the
    Figure."""
    labels = list(fits)
    count = len(names)
    width = 0.8 / max(len(labels), 1)
    figure, ax = _axes_or_new(ax, 1, figsize=(max(7.0, 0.3 * count + 2.0), 4.0))
    x = np.arange(count)
    for index, label in enumerate(labels):
        values = np.asarray(fits[label], dtype=float)
        if values.shape != (count,):
            raise ValueError(f"channel_fits: '{label}' has {values.size} values for {count} "
                             "channels")
        ax.bar(x + (index - (len(labels) - 1) / 2.0) * width, values, width, label=label)
    ax.set_xticks(x)
    ax.set_xticklabels(names, rotation=90, fontsize="small")
    ax.set_ylabel("fit [%]")
    ax.set_ylim(min(0.0, np.nanmin([np.nanmin(np.asarray(v, dtype=float)) for v in
                                     fits.values()])), 100.0)
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(loc="lower right", fontsize="small")
    if title:
        ax.set_title(title)
    return _finish(figure, filename)


def stabilisation(scan, title=None, filename=None, frequency_unit="Hz", ax=None):
    """Stabilisation diagram of a structure scan: every pole pair of every fit at its natural
    frequency [Hz] (x) and its fit's order (y). Markers: "stable" (frequency and damping within
    the scan's tolerances of the previous order's), "stable frequency", "new", "unstable pole";
    the recommended fit's row is marked.

    ``scan``: a ctid.StructureScanResult or the JSON document `ctid structure -o` writes.
    ``frequency_unit``: "Hz" (default) or "rad/s". Returns the Figure.
    """
    factor, axis_label = _frequency_axis(frequency_unit, "stabilisation")
    def get(obj, name):
        return obj[name] if isinstance(obj, dict) else getattr(obj, name)

    points = get(scan, "stabilisation")
    styles = [("stable", "o", "tab:green"), ("stable frequency", "d", "tab:blue"),
              ("new", ".", "tab:gray"), ("unstable pole", "x", "tab:red")]
    groups = {name: ([], []) for name, _, _ in styles}
    for p in points:
        if not get(p, "stable_pole"):
            name = "unstable pole"
        elif get(p, "stable_damping"):
            name = "stable"
        elif get(p, "stable_frequency"):
            name = "stable frequency"
        else:
            name = "new"
        groups[name][0].append(get(p, "frequency") * factor)
        groups[name][1].append(get(p, "order"))
    figure, ax = _axes_or_new(ax, 1, figsize=(7.0, 4.5))
    for name, marker, colour in styles:
        x, y = groups[name]
        if x:
            ax.semilogx(x, y, marker, color=colour, ms=6, ls="none", label=name)
    recommended = get(scan, "recommended")
    fits = get(scan, "fits")
    if recommended is not None and 0 <= recommended < len(fits):
        orders = [get(p, "order") for p in points if get(p, "fit") == recommended]
        if orders:
            ax.axhline(orders[0], color="k", lw=0.8, ls="--", label="recommended")
    ax.set_xlabel(f"natural {axis_label}")
    ax.set_ylabel("model order (poles)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize="small")
    if title:
        ax.set_title(title)
    return _finish(figure, filename)


class _OmaModeView:
    """An output-only mode (ctid.OmaMode, Hz) with the fields mode_shapes and mac_matrix read
    (rad/s, the complex shape, its standard errors, MPC in place of the rank-one share)."""

    def __init__(self, index, mode):
        hz = 2.0 * np.pi
        self.submodel = index
        self.natural_frequency = hz * mode.frequency_hz
        std = mode.frequency_hz_std
        self.natural_frequency_se = hz * std if std is not None else float("nan")
        self.damping_ratio = mode.damping_ratio
        self.damping_ratio_se = (mode.damping_ratio_std if mode.damping_ratio_std is not None
                                 else float("nan"))
        self.shape = np.asarray(mode.shape_real, dtype=float) + 1j * np.asarray(
            mode.shape_imag, dtype=float)
        self.shape_se_real = np.asarray(
            [float("nan") if v is None else v for v in mode.shape_real_std], dtype=float)
        self.mpc = mode.mpc


def _oma_modes(result, where):
    modes = [_OmaModeView(i, m) for i, m in enumerate(getattr(result, "modes", []))]
    if not modes:
        raise ValueError(f"{where}: the analysis found no mode to draw")
    return modes


def oma_mode_shapes(result, geometry=None, title=None, filename=None):
    """The mode shapes of an output-only analysis (``ctid.oma``, ``ctid oma -o``), one panel per
    mode. Without a sensor geometry, as :func:`mode_shapes` draws them: the real part with one
    standard error and the magnitude signed by the phase, over the channels (named by
    ``result.channels``) or over ``geometry`` given as one position per channel. With
    ``geometry`` a :class:`ctid.geometry.Geometry` (or the path of its sensors CSV file), each
    shape deforms the 2-D or 3-D wireframe of the sensors (decision 0063). Shapes are
    normalised as every output-only shape (largest entry 1, decision 0030); each panel's title
    carries f_n, ζ and the MPC. Returns the Figure."""
    from . import geometry as sensors

    if isinstance(geometry, (str, bytes)) or hasattr(geometry, "__fspath__"):
        geometry = sensors.read_geometry(geometry)
    if not isinstance(geometry, sensors.Geometry):
        return mode_shapes(_oma_modes(result, "oma_mode_shapes"),
                           output_names=list(result.channels), geometry=geometry, title=title,
                           filename=filename)
    modes = _oma_modes(result, "oma_mode_shapes")
    columns = 1 if len(modes) == 1 else 2
    rows = math.ceil(len(modes) / columns)
    figure = plt.figure(figsize=(5.0 * columns, 4.0 * rows + 0.5), layout="constrained")
    figure._ctid_created = True
    hz = 2.0 * np.pi
    sensors.draw_shapes(
        result, geometry, modes,
        lambda m: (f"mode {m.submodel + 1}: f_n = "
                   f"{_plus_minus(m.natural_frequency / hz, m.natural_frequency_se / hz)} Hz, "
                   f"ζ = {_plus_minus(m.damping_ratio, m.damping_ratio_se, 4)}\nMPC {m.mpc:.3g}"),
        figure)
    if title:
        figure.suptitle(title)
    return _finish(figure, filename)


def oma_mac(result, other=None, title=None, filename=None, ax=None):
    """The auto-MAC of an output-only analysis's modes (``other`` None: well-separated modes
    give a MAC near the identity), or the MAC between its modes and those of ``other`` (another
    analysis of the same channels, e.g. a later record). Annotated heat map as
    :func:`mac_matrix`. Returns the Figure."""
    rows = _oma_modes(result, "oma_mac")
    cols = None if other is None else _oma_modes(other, "oma_mac")
    if other is not None and list(other.channels) != list(result.channels):
        raise ValueError("oma_mac: the two analyses have different channels")
    return mac_matrix(rows, cols, title=title, filename=filename, ax=ax)


def oma_stabilisation(result, title=None, filename=None, frequency_unit="Hz", ax=None):
    """Stabilisation diagram of an output-only analysis (``ctid.oma``, ``ctid oma -o``): every
    pole tried at its natural frequency (x) and model order (y), marked by its stability class
    against the previous order ("stable": frequency, damping and shape; "frequency and
    shape", "frequency and damping", "frequency", "new"); each chosen mode is a vertical line
    labelled with its frequency and the number of orders that support it. Behind them, on a
    second axis, the first singular value of the output spectral matrix in dB (the result's
    ``first_singular_value``, when it has one).

    ``result``: a ctid.OmaResult (``ctid.read_result`` reads the document). Returns the Figure.
    """
    factor, axis_label = _frequency_axis(frequency_unit, "oma_stabilisation")
    factor *= 2.0 * math.pi  # the poles' frequencies are in Hz
    styles = [("stable", "o", "tab:green"), ("frequency_shape", "s", "tab:olive"),
              ("frequency_damping", "d", "tab:blue"), ("frequency", "^", "tab:cyan"),
              ("new", ".", "tab:gray")]
    labels = {"stable": "stable", "frequency_shape": "frequency and shape",
              "frequency_damping": "frequency and damping", "frequency": "frequency",
              "new": "new"}
    groups = {name: ([], []) for name, _, _ in styles}
    for pole in result.stabilisation:
        name = str(pole.stability).split(".")[-1]
        name = "new" if name == "new_pole" else name
        groups.setdefault(name, ([], []))
        groups[name][0].append(pole.frequency_hz * factor)
        groups[name][1].append(pole.order)
    figure, ax = _axes_or_new(ax, 1, figsize=(7.0, 4.5))
    s1 = list(result.first_singular_value)
    if s1:
        behind = ax.twinx()
        positive = min((v for v in s1 if v > 0.0), default=1.0)
        behind.plot([f * factor for f in result.spectrum_hz],
                    [10.0 * math.log10(max(v, positive)) for v in s1], color="0.65", lw=0.8)
        behind.set_ylabel("first singular value [dB]")
        ax.set_zorder(behind.get_zorder() + 1)  # the poles over the curve
        ax.patch.set_visible(False)
    for name, marker, colour in styles:
        x, y = groups[name]
        if x:
            ax.plot(x, y, marker, color=colour, ms=5, ls="none", label=labels[name])
    for mode in result.modes:
        ax.axvline(mode.frequency_hz * factor, color="k", lw=0.8, ls="--")
        ax.annotate(f"{mode.frequency_hz:.4g} Hz ({mode.supporting_orders})",
                    (mode.frequency_hz * factor, 1.0), xycoords=("data", "axes fraction"),
                    rotation=90, va="top", ha="right", fontsize="x-small")
    ax.set_xlabel(f"natural {axis_label}")
    # pLSCF's orders are polynomial orders (decision 0066); SSI's are states.
    plscf = getattr(getattr(result, "method", None), "name", None) == "plscf"
    ax.set_ylabel("polynomial order" if plscf else "model order")
    ax.grid(True, alpha=0.3)
    if any(groups[name][0] for name, _, _ in styles):
        ax.legend(loc="lower right", fontsize="small")
    if title:
        ax.set_title(title)
    return _finish(figure, filename)


def modes(model, omegas=None, frf=None, title=None, filename=None, frequency_unit="Hz",
          ax=None):
    """Magnitude of each submodel of an additive model, their sum, and optionally the FRF
    (shaded where its coherence, if known, is below 0.5).

    ``model``: EstimationResult or AdditiveModel. ``omegas`` [rad/s]: the grid (default as
    in bode). ``frequency_unit``: "Hz" (default) or "rad/s", for the axis and the labels.
    Lines: "submodel i" (with f_n or w_n and zeta for a second-order mode), "sum", "FRF".
    Returns the Figure.
    """
    factor, axis_label = _frequency_axis(frequency_unit, "modes")
    base, _ = _as_model(model)
    if not isinstance(base, _ctid.AdditiveModel):
        raise TypeError("modes: needs an additive model")
    if omegas is None:
        omegas = _default_omegas(base, frf)
    omegas = np.asarray(omegas, dtype=float)
    columns = np.asarray(_ctid.submodel_frequency_responses(base, omegas))
    figure, ax = _axes_or_new(ax, 1, figsize=(7.0, 4.5))
    x = omegas * factor
    for i in range(columns.shape[1]):
        label = f"submodel {i + 1}"
        modal = base.modal_parameters(i)
        if modal is not None:
            name = "f_n" if frequency_unit == "Hz" else "w_n"
            label += (f" ({name} = {modal.natural_frequency * factor:.4g} {frequency_unit}, "
                      f"zeta = {modal.damping_ratio:.3g})")
        ax.semilogx(x, _db(columns[:, i]), "--", lw=1, label=label)
    ax.semilogx(x, _db(_ctid.frequency_response(base, omegas)), "k", lw=1.5, label="sum")
    if frf is not None:
        w = np.asarray(frf.frequencies, dtype=float)
        _shade_low_coherence((ax,), w * factor,
                             np.asarray(getattr(frf, "coherence", []), dtype=float))
        ax.semilogx(w * factor, _db(frf.response), "o", ms=2.5, color="0.4", label="FRF")
    ax.set_xlabel(axis_label)
    ax.set_ylabel("magnitude [dB]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    if title:
        ax.set_title(title)
    return _finish(figure, filename)


def validation(data, simulated, title=None, filename=None, ax=None):
    """Measured against simulated output over time, with the fit % in the title.

    ``data``: ctid.SampledData. ``simulated``: the model's output samples, or a model
    (EstimationResult / AdditiveModel / TransferFunction) simulated on ``data.input`` with
    its exact ZOH response. Lines: "measured", "simulated". Returns the Figure.
    """
    if not isinstance(simulated, np.ndarray) and not isinstance(simulated, (list, tuple)):
        base, _ = _as_model(simulated)
        if isinstance(base, _ctid.AdditiveModel):
            simulated = _ctid.model_output(base, data.input, data.sample_time)
        else:
            simulated = _ctid.simulate(base, data.input, data.sample_time)
    simulated = np.asarray(simulated, dtype=float)
    measured = np.asarray(data.output)
    fit = _ctid.fit_percent(measured, simulated)
    figure, ax = _axes_or_new(ax, 1, figsize=(8.0, 4.0))
    t = np.asarray(data.time)
    ax.plot(t, measured, color="0.5", lw=1, label="measured")
    ax.plot(t, simulated, color="C0", lw=1, label="simulated")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("output")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    heading = f"fit = {fit:.2f} %"
    ax.set_title(f"{title}: {heading}" if title else heading)
    return _finish(figure, filename)


def compare(data, models, labels=None, options=None, title=None, filename=None, ax=None):
    """Several models over one measured output, like MATLAB's ``compare``.

    ``data``: ctid.SampledData. ``models``: a list of AdditiveModel / EstimationResult (each
    simulated by ctid.validation_output with ``options``, a ctid.ValidationOptions: initial
    state and scored window) or of simulated output arrays. ``labels``: one per model
    (default "model 1", ...). The legend gives each model's fit % on the window; the window is
    shaded when it is not the whole record. Returns the Figure.
    """
    options = options if options is not None else _ctid.ValidationOptions()
    labels = list(labels) if labels is not None else [f"model {i + 1}" for i in range(len(models))]
    if len(labels) != len(models):
        raise ValueError(f"compare: {len(labels)} labels for {len(models)} models")
    measured = np.asarray(data.output)
    t = np.asarray(data.time)
    start = options.window_start if options.window_start is not None else t[0]
    end = options.window_end if options.window_end is not None else t[-1]
    inside = (t >= start - 1e-9) & (t <= end + 1e-9)
    if inside.sum() < 2:
        raise ValueError(f"compare: the window [{start}, {end}] s holds fewer than 2 samples")
    figure, ax = _axes_or_new(ax, 1, figsize=(8.0, 4.0))
    ax.plot(t, measured, color="0.5", lw=1, label="measured")
    for i, (model, label) in enumerate(zip(models, labels)):
        if isinstance(model, (np.ndarray, list, tuple)):
            output = np.asarray(model, dtype=float)
            fit = _ctid.fit_percent(measured[inside], output[inside])
        else:
            base, _ = _as_model(model)
            output = np.asarray(_ctid.validation_output(base, data, options))
            fit = _ctid.validate_model(base, data, options).fit_percent
        ax.plot(t, output, color=f"C{i}", lw=1, label=f"{label}: fit {fit:.2f} %")
    first, last = t[inside][0], t[inside][-1]
    if first > t[0] or last < t[-1]:
        ax.axvspan(first, last, color="C0", alpha=0.06, lw=0, label="scored window")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("output")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    state = "estimated initial state" if options.initial_state == _ctid.InitialState.estimate \
        else "from rest"
    ax.set_title(f"{title}: {state}" if title else state)
    return _finish(figure, filename)


def correlations(residual, input, max_lag=25):
    """Normalised residual autocorrelation (lags 0..max_lag) and residual-input
    cross-correlation (lags -max_lag..max_lag), both after removing the means.

    r_e(k) = sum_t e_t e_{t+k} / sum e^2 and r_eu(k) = sum_t e_{t+k} u_t /
    sqrt(sum e^2 sum u^2). Returns (lags_auto, r_e, lags_cross, r_eu).
    """
    e = np.asarray(residual, dtype=float)
    u = np.asarray(input, dtype=float)
    if e.size != u.size:
        raise ValueError(f"correlations: residual has {e.size} samples but input {u.size}")
    if not 1 <= max_lag < e.size:
        raise ValueError(f"correlations: max_lag = {max_lag} must lie in [1, {e.size - 1}]")
    r_e, r_eu = _ctid.residual_correlations(e, u, int(max_lag))
    return (np.arange(max_lag + 1), np.asarray(r_e), np.arange(-max_lag, max_lag + 1),
            np.asarray(r_eu))


def residual_correlation(residual, input=None, max_lag=25, confidence=0.99, title=None,
                         filename=None, ax=None):
    """Residual autocorrelation and residual-input cross-correlation with confidence bounds.

    ``residual`` and ``input``: sample arrays (the correlations of :func:`correlations`), or
    ``residual`` a ctid.ValidationReport (``ctid validate -o``; ``input`` None), whose
    correlations (r_ee at lags 1..max_lag, r_eu at -max_lag..max_lag, the same sign
    convention) and 99 % bound are drawn as they are. The bounds +-z/sqrt(N) (z = 2.58 for
    99 %) are those of a white residual uncorrelated with the input. r_eu(k) pairs e(t + k)
    with u(t), so a peak at k > 0 means the input leads the residual (the model misses some of
    the input's effect), at k < 0 that the residual leads the input (feedback). Lines:
    "autocorrelation", "cross-correlation", and the bounds labelled "99% bound". Returns the
    Figure.
    """
    if isinstance(residual, _ctid.ValidationReport):
        report = residual
        if report.max_lag < 1:
            raise ValueError("residual_correlation: the report has no correlation lags")
        lags_auto = np.arange(1, report.max_lag + 1)
        r_e = np.asarray(report.residual_autocorrelation, dtype=float)
        lags_cross = np.arange(-report.max_lag, report.max_lag + 1)
        r_eu = np.asarray(report.cross_correlation, dtype=float)
        bound = report.whiteness_bound
        confidence = 0.99
    else:
        if input is None:
            raise TypeError("residual_correlation: give the input beside the residual samples")
        lags_auto, r_e, lags_cross, r_eu = correlations(residual, input, max_lag)
        bound = NormalDist().inv_cdf(0.5 + confidence / 2.0) / math.sqrt(len(residual))
    figure, (ax_auto, ax_cross) = _axes_or_new(ax, 2, 2, 1, figsize=(7.0, 5.5))
    label = f"{100 * confidence:g}% bound"
    ax_auto.plot(lags_auto, r_e, "o-", ms=3, lw=1, label="autocorrelation")
    ax_cross.plot(lags_cross, r_eu, "o-", ms=3, lw=1, color="C2", label="cross-correlation")
    for ax, lags in ((ax_auto, lags_auto), (ax_cross, lags_cross)):
        ax.plot([lags[0], lags[-1]], [bound, bound], "r--", lw=1, label=label)
        ax.plot([lags[0], lags[-1]], [-bound, -bound], "r--", lw=1)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    ax_auto.set_xlabel("lag [samples]")
    ax_auto.set_ylabel("residual autocorrelation")
    ax_cross.set_xlabel("lag k [samples]: r(k) pairs e(t + k) with u(t); k > 0: input leads "
                        "residual")
    ax_cross.set_ylabel("residual-input correlation")
    if title:
        ax_auto.set_title(title)
    return _finish(figure, filename)


def _averaged_periodogram(x, h, segment=256):
    """(frequencies [Hz], one-sided power spectral density [unit^2/Hz]) of x by Hann-windowed
    segments overlapping by half (Welch's method), normalised so that white noise of variance
    s^2 reads 2 h s^2, the convention of ArmaModel.spectrum."""
    x = np.asarray(x, dtype=float) - np.mean(x)
    n = min(segment, x.size)
    window = np.hanning(n)
    spectra = [np.abs(np.fft.rfft(window * x[s:s + n])) ** 2
               for s in range(0, x.size - n + 1, max(n // 2, 1))]
    density = np.mean(spectra, axis=0) * h / np.sum(window ** 2)
    density[1:] *= 2.0
    if n % 2 == 0:
        density[-1] /= 2.0  # the Nyquist line has no mirror
    return np.fft.rfftfreq(n, h), density


def noise_spectrum(result, data=None, title=None, filename=None, ax=None):
    """The noise spectrum of a RIVC fit (``noise_model`` given, decision 0056): the ARMA
    model's one-sided power spectral density 2 h sigma_e^2 |C/D|^2 against frequency [Hz],
    line "noise model", on a log scale. With ``data`` (the SampledData it was fitted to, or
    another record) the averaged periodogram of the output error y - G u is drawn beside it,
    line "output error", so the fitted colour can be compared with the measured one.
    ``result``: an EstimationResult with a noise model (or an ArmaModel whose spectrum is set;
    ``data`` then needs a ``result`` with a model). Returns the Figure."""
    noise = result if isinstance(result, _ctid.ArmaModel) else getattr(result, "noise_model", None)
    if noise is None:
        raise ValueError("noise_spectrum: the result has no noise model (fit with noise_model, "
                         "ctid fit --noise-model)")
    if len(noise.spectrum) == 0:
        raise ValueError("noise_spectrum: the noise model has no spectrum (ctid.arma_spectrum)")
    figure, axes = _axes_or_new(ax, 1, figsize=(7.0, 4.0))
    if data is not None:
        if isinstance(result, _ctid.ArmaModel):
            raise TypeError("noise_spectrum: give the EstimationResult to draw the output error")
        simulated = _ctid.model_output(result.model, data.input, data.sample_time,
                                       data.input_hold)
        f, density = _averaged_periodogram(np.asarray(data.output) - simulated, data.sample_time)
        axes.semilogy(f[1:], density[1:], color="0.6", lw=1, label="output error")
    axes.semilogy(noise.spectrum_frequencies, noise.spectrum, color="C0", lw=1.5,
                  label="noise model")
    axes.set_xlabel("frequency [Hz]")
    axes.set_ylabel("power spectral density [unit²/Hz]")
    axes.grid(True, which="both", alpha=0.3)
    axes.legend(fontsize=8)
    p, q = len(noise.ar) - 1, len(noise.ma) - 1
    axes.set_title(title or f"noise model ARMA({p}, {q})")
    return _finish(figure, filename)


def _mse_rows(source):
    """Rows as dicts estimator, N, parameter, mse, predicted_mse."""
    if isinstance(source, (_ctid.StudyResult, _ctid.StudySummary)):
        rows = []
        for row in source.mse:
            rows.append({
                "estimator": row.estimator.name,
                "N": row.samples,
                "parameter": source.parameter_names[row.parameter],
                "mse": row.mean_squared_error,
                "predicted_mse": row.predicted_mean_squared_error,
            })
        return rows
    return [
        {
            "estimator": str(r["estimator"]),
            "N": float(r["N"]),
            "parameter": str(r["parameter"]),
            "mse": float(r["mse"]),
            "predicted_mse": float(r.get("predicted_mse", "nan")),
        }
        for r in source
    ]


def mse_against_n(study, title=None, filename=None):
    """MSE against N (log-log) for a Monte Carlo study, one panel per parameter, one solid
    line per estimator ("<estimator>") and the asymptotic-covariance prediction dashed
    ("<estimator> (predicted)").

    ``study``: a ctid.StudyResult or ctid.StudySummary (``ctid study``'s summary.json), or
    rows (dicts) with the columns of the CLI's mse.csv (estimator, N, parameter, mse,
    predicted_mse). Returns the Figure.
    """
    rows = _mse_rows(study)
    if not rows:
        raise ValueError("mse_against_n: no rows to plot")
    parameters = list(dict.fromkeys(r["parameter"] for r in rows))
    estimators = list(dict.fromkeys(r["estimator"] for r in rows))
    cols = min(len(parameters), 2 if len(parameters) <= 4 else 3)
    nrows = math.ceil(len(parameters) / cols)
    figure, axes = _figure(nrows, cols, figsize=(4.2 * cols, 3.2 * nrows), squeeze=False)
    for ax, parameter in zip(axes.flat, parameters):
        for k, estimator in enumerate(estimators):
            sel = sorted((r for r in rows
                          if r["parameter"] == parameter and r["estimator"] == estimator),
                         key=lambda r: r["N"])
            if not sel:
                continue
            n = [r["N"] for r in sel]
            ax.loglog(n, [r["mse"] for r in sel], "o-", ms=3, lw=1, color=f"C{k}",
                      label=estimator)
            predicted = [r["predicted_mse"] for r in sel]
            if any(math.isfinite(v) and v > 0 for v in predicted):
                ax.loglog(n, predicted, "--", lw=1, color=f"C{k}",
                          label=f"{estimator} (predicted)")
        ax.set_title(parameter)
        ax.set_xlabel("N")
        ax.set_ylabel("MSE")
        ax.grid(True, which="both", alpha=0.3)
    for ax in list(axes.flat)[len(parameters):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    if title:
        figure.suptitle(title)
    return _finish(figure, filename)


# --- Mode tracking (issue 17) -------------------------------------------------------------------

def _tracking_arrays(result):
    """(centre times [s], usable flags, tracks as dicts of float arrays in rad/s) of a
    ctid.TrackingResult or the mode_tracking_result document `ctid track -o` writes."""
    def get(obj, name):
        return obj[name] if isinstance(obj, dict) else getattr(obj, name)

    def floats(values):
        return np.array([np.nan if v is None else v for v in values], dtype=float)

    windows = get(result, "windows")
    times = np.array([get(w, "centre_time") for w in windows], dtype=float)
    usable = np.array([bool(get(get(w, "verdict"), "usable")) for w in windows])
    tracks = []
    for track in get(result, "tracks"):
        tracks.append({name: floats(get(track, name)) for name in (
            "natural_frequency", "natural_frequency_se", "damping_ratio", "damping_ratio_se")})
    return times, usable, tracks


def mode_tracking(result, standard_errors=1.0, title=None, filename=None, frequency_unit="Hz",
                  ax=None):
    """Tracked modes against time: natural frequency (top) and damping ratio (bottom) of every
    track at each window's centre, with error bars of ``standard_errors`` standard errors
    (default one). Windows without a usable model are shaded ("no usable model").

    ``result``: a ctid.TrackingResult (ctid.track_modes) or the mode_tracking_result document
    `ctid track -o` writes (a dict). ``frequency_unit``: "Hz" (default) or "rad/s". Lines are
    labelled "track k". Returns the Figure.
    """
    factor, _ = _frequency_axis(frequency_unit, "mode_tracking")
    times, usable, tracks = _tracking_arrays(result)
    if len(times) == 0:
        raise ValueError("mode_tracking: the result has no windows")
    figure, (top, bottom) = _axes_or_new(ax, 2, 2, 1, figsize=(7.5, 5.5), sharex=True)
    for k, track in enumerate(tracks):
        shown = np.isfinite(track["natural_frequency"])
        if not shown.any():
            continue
        colour = f"C{k % 10}"
        se = np.nan_to_num(track["natural_frequency_se"], nan=0.0) * standard_errors
        top.errorbar(times[shown], track["natural_frequency"][shown] * factor,
                     yerr=se[shown] * factor, fmt="o-", ms=3, lw=1, capsize=2, color=colour,
                     label=f"track {k + 1}")
        se = np.nan_to_num(track["damping_ratio_se"], nan=0.0) * standard_errors
        bottom.errorbar(times[shown], track["damping_ratio"][shown], yerr=se[shown], fmt="o-",
                        ms=3, lw=1, capsize=2, color=colour, label=f"track {k + 1}")
    if (~usable).any():
        half = 0.5 * (np.median(np.diff(times)) if len(times) > 1 else 1.0)
        labelled = False
        for t in times[~usable]:
            for ax in (top, bottom):
                ax.axvspan(t - half, t + half, color="tab:red", alpha=0.12, lw=0,
                           label=None if labelled or ax is bottom else "no usable model")
            labelled = True
    band = "" if standard_errors == 1.0 else f"{standard_errors:g} "
    top.set_ylabel(f"natural frequency [{frequency_unit}]")
    bottom.set_ylabel("damping ratio")
    bottom.set_xlabel("time at the window's centre [s]")
    top.set_title(f"error bars: ± {band}standard error", fontsize="small")
    for ax in (top, bottom):
        ax.grid(True, alpha=0.3)
    if tracks:
        top.legend(loc="best", fontsize="small")
    if title:
        figure.suptitle(title)
    return _finish(figure, filename)


def response_curve(time, output, lower=None, upper=None, kind="step", final_value=None,
                   confidence=None, ax=None, title=None, filename=None):
    """Draw a time response y(t) ("<kind> response") with its band between ``lower`` and
    ``upper`` ("<confidence>% band", or "band" when ``confidence`` is None) and, given
    ``final_value``, a dashed "final value" line. Draws into ``ax`` when given (its figure is
    returned), otherwise into a new figure. Returns the Figure (saved to ``filename`` if given).
    """
    if kind not in ("step", "impulse"):
        raise ValueError(f"response_curve: kind is {kind!r}; it must be 'step' or 'impulse'")
    t = np.asarray(time, dtype=float)
    y = np.asarray(output, dtype=float)
    if t.shape != y.shape or t.size < 2:
        raise ValueError("response_curve: time and output need the same length, at least 2")
    figure, ax = _axes_or_new(ax, 1, figsize=(7.0, 4.0))
    if lower is not None and upper is not None and np.size(lower) == t.size:
        band = "band" if confidence is None else f"{100 * confidence:g}% band"
        ax.fill_between(t, np.asarray(lower, dtype=float), np.asarray(upper, dtype=float),
                        alpha=0.3, color="C0", label=band, linewidth=0)
    ax.plot(t, y, color="C0", label=f"{kind} response")
    if final_value is not None and np.isfinite(final_value):
        ax.axhline(final_value, color="0.4", linestyle="--", linewidth=1.0, label="final value")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("output")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    return _finish(figure, filename)


def _time_response(function, model, ax, title, filename, options):
    response = model if isinstance(model, _ctid.TimeResponse) else function(model, **options)
    kind = "step" if response.kind == _ctid.ResponseKind.step else "impulse"
    has_band = np.size(response.standard_deviation) > 0
    confidence = 2.0 * NormalDist().cdf(response.z) - 1.0 if has_band else None
    final = response.characteristics.dc_gain.value if kind == "step" else None
    return response_curve(response.time, response.output,
                          response.lower if has_band else None,
                          response.upper if has_band else None, kind=kind, final_value=final,
                          confidence=confidence, ax=ax, title=title, filename=filename)


def step(model, ax=None, title=None, filename=None, **options):
    """Step response of ``model`` (an EstimationResult, AdditiveModel, TransferFunction, or a
    TimeResponse already computed) with its delta-method band and final value: ctid.step_response
    with ``options`` (covariance=, final_time=, points=, confidence=, ...), drawn by
    response_curve into ``ax`` or a new figure. Returns the Figure."""
    return _time_response(_ctid.step_response, model, ax, title, filename, options)


def impulse(model, ax=None, title=None, filename=None, **options):
    """Impulse response of ``model`` with its band, as :func:`step`. Returns the Figure."""
    return _time_response(_ctid.impulse_response, model, ax, title, filename, options)
