"""Figures for ctid results, drawn with matplotlib (Agg backend, no display needed).

Every function returns the :class:`matplotlib.figure.Figure` and, given ``filename``
(``.png`` or ``.svg``), also saves it there. Frequencies are in rad/s, magnitudes in dB,
phases in degrees. Lines carry labels ("model", "FRF", "measured", ...) so callers and tests
can find them again with ``line.get_label()``.

Confidence bands of a Bode plot come from the parameter covariance P by first-order
propagation (the delta method): the Jacobian J = dG(jw)/dtheta is taken by central finite
differences of the model's frequency response (step 1e-6 |theta_i|, or 1e-9 for a zero
parameter), then var|G| = g' P g with g = Re(conj(G) J) / |G| and var(arg G) = h' P h with
h = Im(J / G). The band is |G| +- z sigma (z the two-sided normal quantile of
``confidence``), drawn in dB, and arg G +- z sigma in degrees.
"""

from __future__ import annotations

import math
from statistics import NormalDist

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from . import _ctid  # noqa: E402

__all__ = [
    "bode",
    "frf",
    "modes",
    "validation",
    "compare",
    "residual_correlation",
    "mse_against_n",
    "frequency_response_band",
    "correlations",
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


def _finish(figure, filename):
    figure.tight_layout()
    if filename is not None:
        save(figure, filename)
    return figure


def _as_model(model):
    """(AdditiveModel or TransferFunction, parameters or None, covariance or None)."""
    if isinstance(model, _ctid.EstimationResult):
        cov = np.asarray(model.covariance)
        return model.model, np.asarray(model.parameters), (cov if cov.size else None)
    if isinstance(model, (_ctid.AdditiveModel, _ctid.TransferFunction)):
        return model, None, None
    raise TypeError(
        "expected an EstimationResult, AdditiveModel or TransferFunction, got "
        + type(model).__name__
    )


def _default_omegas(model, frf=None, count=400):
    if frf is not None and len(frf.frequencies):
        w = np.asarray(frf.frequencies)
        return np.logspace(np.log10(w.min()), np.log10(w.max()), count)
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
    base, theta, cov = _as_model(model)
    if covariance is not None:
        cov = np.asarray(covariance, dtype=float)
    omegas = np.asarray(omegas, dtype=float)
    response = np.asarray(_ctid.frequency_response(base, omegas))
    z = NormalDist().inv_cdf(0.5 + confidence / 2.0)
    if cov is None or not isinstance(base, _ctid.AdditiveModel):
        return response, None, None, z
    theta = np.asarray(base.parameters(), dtype=float) if theta is None else theta
    if cov.shape != (theta.size, theta.size):
        raise ValueError(
            f"frequency_response_band: covariance is {cov.shape[0]}x{cov.shape[1]} but the "
            f"model has {theta.size} parameters"
        )
    jacobian = np.empty((omegas.size, theta.size), dtype=complex)
    for i in range(theta.size):
        step = 1e-6 * abs(theta[i]) if theta[i] != 0.0 else 1e-9
        up, down = theta.copy(), theta.copy()
        up[i] += step
        down[i] -= step
        jacobian[:, i] = (
            np.asarray(_ctid.frequency_response(base.with_parameters(up), omegas))
            - np.asarray(_ctid.frequency_response(base.with_parameters(down), omegas))
        ) / (2.0 * step)
    magnitude = np.abs(response)
    g_mag = np.real(np.conj(response)[:, None] * jacobian) / magnitude[:, None]
    g_phase = np.imag(jacobian / response[:, None])
    mag_sigma = np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", g_mag, cov, g_mag), 0.0))
    phase_sigma = np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", g_phase, cov, g_phase), 0.0))
    return response, mag_sigma, phase_sigma, z


def _db(x):
    return 20.0 * np.log10(np.maximum(np.abs(x), 1e-300))


def bode(model, frf=None, covariance=None, omegas=None, confidence=0.95, title=None,
         filename=None, sampled=None):
    """Bode plot of a fitted model over a nonparametric FRF, with confidence bands.

    ``model``: EstimationResult (its covariance gives the band), AdditiveModel or
    TransferFunction. ``frf``: a ctid.Frf (or any object with ``frequencies`` and
    ``response``) drawn as markers. ``omegas``: the model's grid [rad/s]
    (default: the FRF's range, or a decade around the poles). ``sampled``: (h, ctid.Hold) of
    the data behind the FRF, to draw also the model as the samples see it
    (ctid.sampled_frequency_response: the hold and the sampling included), which is what an
    FRF of sampled data estimates. Lines: "model", "FRF", "model, sampled (zoh|foh)"; bands:
    "<confidence>% band". Returns the Figure (saved to ``filename`` if given).
    """
    base, _, _ = _as_model(model)
    if omegas is None:
        omegas = _default_omegas(base, frf)
    omegas = np.asarray(omegas, dtype=float)
    response, mag_sigma, phase_sigma, z = frequency_response_band(
        model, omegas, covariance, confidence)
    figure, (ax_mag, ax_phase) = plt.subplots(2, 1, sharex=True, figsize=(7.0, 6.0))
    phase = np.degrees(np.unwrap(np.angle(response)))
    band_label = f"{100 * confidence:g}% band"
    if mag_sigma is not None:
        magnitude = np.abs(response)
        lower = np.maximum(magnitude - z * mag_sigma, magnitude * 1e-6)
        ax_mag.fill_between(omegas, _db(lower), _db(magnitude + z * mag_sigma), alpha=0.3,
                            color="C0", label=band_label, linewidth=0)
        ax_phase.fill_between(omegas, phase - np.degrees(z * phase_sigma),
                              phase + np.degrees(z * phase_sigma), alpha=0.3, color="C0",
                              label=band_label, linewidth=0)
    ax_mag.semilogx(omegas, _db(response), color="C0", label="model")
    ax_phase.semilogx(omegas, phase, color="C0", label="model")
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
        ax_mag.semilogx(seen_at, _db(seen), "--", color="C2", label=f"model, sampled ({name})")
        ax_phase.semilogx(seen_at, seen_phase, "--", color="C2",
                          label=f"model, sampled ({name})")
    if frf is not None:
        w = np.asarray(frf.frequencies)
        g = np.asarray(frf.response)
        ax_mag.semilogx(w, _db(g), "o", ms=2.5, color="C1", label="FRF")
        frf_phase = np.degrees(np.angle(g))
        # Put the FRF's phase on the model's branch so the two can be compared by eye.
        model_at_w = np.interp(np.log(w), np.log(omegas), phase)
        frf_phase += 360.0 * np.round((model_at_w - frf_phase) / 360.0)
        ax_phase.semilogx(w, frf_phase, "o", ms=2.5, color="C1", label="FRF")
    # The axis follows the model and the FRF, not the band: a band reaching to |G| ~ 0 near an
    # antiresonance would otherwise squash the plot to a few pixels.
    shown = [_db(response)] + ([_db(np.asarray(frf.response))] if frf is not None else [])
    shown = np.concatenate([v[np.isfinite(v)] for v in shown])
    if shown.size:
        ax_mag.set_ylim(shown.min() - 10.0, shown.max() + 10.0)
    ax_mag.set_ylabel("magnitude [dB]")
    ax_phase.set_ylabel("phase [deg]")
    ax_phase.set_xlabel("frequency [rad/s]")
    for ax in (ax_mag, ax_phase):
        ax.grid(True, which="both", alpha=0.3)
    ax_mag.legend(fontsize=8)
    if title:
        ax_mag.set_title(title)
    return _finish(figure, filename)


def frf(estimate, title=None, filename=None):
    """A nonparametric FRF on its own: magnitude (dB), phase (deg) and, when the estimate has
    one (Welch), the squared coherence.

    ``estimate``: a ctid.Frf or any object with ``frequencies`` [rad/s], complex ``response``
    and optionally ``coherence``. Lines: "FRF" in each panel, "coherence". Returns the Figure.
    """
    w = np.asarray(estimate.frequencies, dtype=float)
    g = np.asarray(estimate.response)
    coherence = np.asarray(getattr(estimate, "coherence", []), dtype=float)
    coherent = coherence.size == w.size and w.size > 0
    figure, axes = plt.subplots(3 if coherent else 2, 1, sharex=True,
                                figsize=(7.0, 7.0 if coherent else 5.5))
    axes[0].semilogx(w, _db(g), ".-", ms=3, lw=0.8, label="FRF")
    axes[0].set_ylabel("magnitude [dB]")
    axes[1].semilogx(w, np.degrees(np.unwrap(np.angle(g))), ".-", ms=3, lw=0.8, label="FRF")
    axes[1].set_ylabel("phase [deg]")
    if coherent:
        axes[2].semilogx(w, coherence, ".-", ms=3, lw=0.8, label="coherence")
        axes[2].set_ylabel("coherence")
        axes[2].set_ylim(0.0, 1.05)
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[-1].set_xlabel("frequency [rad/s]")
    if title:
        axes[0].set_title(title)
    return _finish(figure, filename)


def frf_matrix(estimate, channels=None, max_outputs=4, title=None, filename=None):
    """Chosen channels of an FRF matrix over frequency in Hz: |H_ji| (dB) of each, and below
    the multiple coherence of each chosen output with all inputs.

    ``estimate``: a ctid.MimoFrf or the "mimo_frf" document of ``ctid frf -o X.json`` (a dict).
    ``channels``: (output name, input name) pairs; default every input of the first
    ``max_outputs`` outputs. Lines: "<output>/<input>" and "coherence <output>". Returns the
    Figure.
    """
    def get(name):
        return estimate[name] if isinstance(estimate, dict) else getattr(estimate, name)

    inputs = list(get("input_names") if not isinstance(estimate, dict) else estimate["inputs"])
    outputs = list(get("output_names") if not isinstance(estimate, dict) else estimate["outputs"])
    hz = np.asarray(get("frequencies"), dtype=float) / (2.0 * np.pi)
    response = get("response")
    if isinstance(estimate, dict):
        pairs = np.array(response, dtype=float)  # (lines, n_y, n_u, 2); null -> nan
        response = pairs[..., 0] + 1j * pairs[..., 1]
    response = np.asarray(response)
    coherence = np.asarray(get("coherence"), dtype=float)
    if channels is None:
        channels = [(y, u) for y in outputs[:max_outputs] for u in inputs]
    figure, axes = plt.subplots(2, 1, sharex=True, figsize=(8.0, 6.5),
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
    axes[1].set_xlabel("frequency [Hz]")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize="small", ncol=2)
    if title:
        axes[0].set_title(title)
    return _finish(figure, filename)


def stabilisation(scan, title=None, filename=None):
    """Stabilisation diagram of a structure scan: every pole pair of every fit at its natural
    frequency [Hz] (x) and its fit's order (y). Markers: "stable" (frequency and damping within
    the scan's tolerances of the previous order's), "stable frequency", "new", "unstable pole";
    the recommended fit's row is marked.

    ``scan``: a ctid.StructureScanResult or the JSON document `ctid structure -o` writes.
    Returns the Figure.
    """
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
        groups[name][0].append(get(p, "frequency") / (2.0 * np.pi))
        groups[name][1].append(get(p, "order"))
    figure, ax = plt.subplots(figsize=(7.0, 4.5))
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
    ax.set_xlabel("natural frequency [Hz]")
    ax.set_ylabel("model order (poles)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize="small")
    if title:
        ax.set_title(title)
    return _finish(figure, filename)


def modes(model, omegas=None, frf=None, title=None, filename=None):
    """Magnitude of each submodel of an additive model, their sum, and optionally the FRF.

    ``model``: EstimationResult or AdditiveModel. Lines: "submodel i" (with w_n and zeta
    for a second-order mode), "sum", "FRF". Returns the Figure.
    """
    base, _, _ = _as_model(model)
    if not isinstance(base, _ctid.AdditiveModel):
        raise TypeError("modes: needs an additive model")
    if omegas is None:
        omegas = _default_omegas(base, frf)
    omegas = np.asarray(omegas, dtype=float)
    columns = np.asarray(_ctid.submodel_frequency_responses(base, omegas))
    figure, ax = plt.subplots(figsize=(7.0, 4.5))
    for i in range(columns.shape[1]):
        label = f"submodel {i + 1}"
        modal = base.modal_parameters(i)
        if modal is not None:
            label += (f" (w_n = {modal.natural_frequency:.4g} rad/s, "
                      f"zeta = {modal.damping_ratio:.3g})")
        ax.semilogx(omegas, _db(columns[:, i]), "--", lw=1, label=label)
    ax.semilogx(omegas, _db(_ctid.frequency_response(base, omegas)), "k", lw=1.5, label="sum")
    if frf is not None:
        ax.semilogx(np.asarray(frf.frequencies), _db(frf.response), "o", ms=2.5, color="0.4",
                    label="FRF")
    ax.set_xlabel("frequency [rad/s]")
    ax.set_ylabel("magnitude [dB]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    if title:
        ax.set_title(title)
    return _finish(figure, filename)


def validation(data, simulated, title=None, filename=None):
    """Measured against simulated output over time, with the fit % in the title.

    ``data``: ctid.SampledData. ``simulated``: the model's output samples, or a model
    (EstimationResult / AdditiveModel / TransferFunction) simulated on ``data.input`` with
    its exact ZOH response. Lines: "measured", "simulated". Returns the Figure.
    """
    if not isinstance(simulated, np.ndarray) and not isinstance(simulated, (list, tuple)):
        base, _, _ = _as_model(simulated)
        if isinstance(base, _ctid.AdditiveModel):
            simulated = _ctid.model_output(base, data.input, data.sample_time)
        else:
            simulated = _ctid.simulate(base, data.input, data.sample_time)
    simulated = np.asarray(simulated, dtype=float)
    measured = np.asarray(data.output)
    fit = _ctid.fit_percent(measured, simulated)
    figure, ax = plt.subplots(figsize=(8.0, 4.0))
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


def compare(data, models, labels=None, options=None, title=None, filename=None):
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
    figure, ax = plt.subplots(figsize=(8.0, 4.0))
    ax.plot(t, measured, color="0.5", lw=1, label="measured")
    for i, (model, label) in enumerate(zip(models, labels)):
        if isinstance(model, (np.ndarray, list, tuple)):
            output = np.asarray(model, dtype=float)
            fit = _ctid.fit_percent(measured[inside], output[inside])
        else:
            base, _, _ = _as_model(model)
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
    e = np.asarray(residual, dtype=float) - np.mean(residual)
    u = np.asarray(input, dtype=float) - np.mean(input)
    if e.size != u.size:
        raise ValueError(f"correlations: residual has {e.size} samples but input {u.size}")
    if not 1 <= max_lag < e.size:
        raise ValueError(f"correlations: max_lag = {max_lag} must lie in [1, {e.size - 1}]")
    n = e.size
    ee, uu = float(e @ e), float(u @ u)
    lags_auto = np.arange(max_lag + 1)
    r_e = np.array([e[: n - k] @ e[k:] for k in lags_auto]) / ee
    lags_cross = np.arange(-max_lag, max_lag + 1)
    r_eu = np.array(
        [(e[k:] @ u[: n - k]) if k >= 0 else (e[: n + k] @ u[-k:]) for k in lags_cross]
    ) / math.sqrt(ee * uu)
    return lags_auto, r_e, lags_cross, r_eu


def residual_correlation(residual, input, max_lag=25, confidence=0.99, title=None,
                         filename=None):
    """Residual autocorrelation and residual-input cross-correlation with confidence bounds.

    The bounds +-z/sqrt(N) (z = 2.58 for 99 %) are those of a white residual uncorrelated
    with the input. Lines: "autocorrelation", "cross-correlation", and the bounds labelled
    "99% bound". Returns the Figure.
    """
    lags_auto, r_e, lags_cross, r_eu = correlations(residual, input, max_lag)
    bound = NormalDist().inv_cdf(0.5 + confidence / 2.0) / math.sqrt(len(residual))
    figure, (ax_auto, ax_cross) = plt.subplots(2, 1, figsize=(7.0, 5.5))
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
    ax_cross.set_xlabel("lag [samples] (residual leads input for lag > 0)")
    ax_cross.set_ylabel("residual-input correlation")
    if title:
        ax_auto.set_title(title)
    return _finish(figure, filename)


def _mse_rows(source):
    """Rows as dicts estimator, N, parameter, mse, predicted_mse."""
    if isinstance(source, _ctid.StudyResult):
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

    ``study``: a ctid.StudyResult, or rows (dicts) with the columns of the CLI's mse.csv
    (estimator, N, parameter, mse, predicted_mse). Returns the Figure.
    """
    rows = _mse_rows(study)
    if not rows:
        raise ValueError("mse_against_n: no rows to plot")
    parameters = list(dict.fromkeys(r["parameter"] for r in rows))
    estimators = list(dict.fromkeys(r["estimator"] for r in rows))
    cols = min(len(parameters), 2 if len(parameters) <= 4 else 3)
    nrows = math.ceil(len(parameters) / cols)
    figure, axes = plt.subplots(nrows, cols, figsize=(4.2 * cols, 3.2 * nrows), squeeze=False)
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
