#!/usr/bin/env python3
"""Headline example: one modal model of the measured flexible steel subframe (DaISy 96-013,
data/daisy_flexible_structure) from both shaker forces to all 28 accelerometers, every
channel sharing the same poles (ctid.mimo_srivc, issue 13).

Steps: the record's means removed and every second sample kept behind ctid's zero-phase
anti-alias filter (h = 1/512 s); the model (seven modes, the peaks of the FRF matrix's summed
power below Nyquist, each R_i(p) / (1 + a_i1 p + a_i2 p^2) with first-degree numerators,
plus a direct term: accelerations from forces) is fitted on the first 70 % of the record
from the data alone. Printed and written: natural frequencies and damping ratios with
standard errors, the mode shapes and their MAC; per accelerometer the fit on the held-out
last 30 % (least-squares initial state) beside the fit of shaker 2 alone with the SISO
example's three modes and beside the multiple-coherence bound; the modes of the two halves
of the record compared (MAC, frequency difference in standard errors); a stabilisation
diagram of 3 to 8 modes. Figures, summary.json and docs/examples/flexible_structure_mimo.md.
"""

import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _common  # noqa: E402

MODES = 7
ESTIMATION_SHARE = 0.7
SISO_SHAKER = 2
SISO_MODES = 3
SCAN_MODES = range(3, 9)
WELCH_SEGMENT = 1024
FREQUENCY_TOLERANCE = 0.01  # stabilisation: as ctid.StructureScanOptions
DAMPING_TOLERANCE = 0.05
SHOWN_CHANNELS = [("y28_acc", "u2_force"), ("y28_acc", "u1_force"), ("y7_acc", "u1_force"),
                  ("y17_acc", "u2_force")]


def load(ctid):
    record = ctid.read_mimo_data(
        os.path.join(_common.DATA, "daisy_flexible_structure", "flexible_structure.csv"),
        time="t_s", inputs=["u1_force:u2_force"], outputs=["y1_acc:y28_acc"])
    return ctid.preprocess(record, detrend=ctid.Detrend.mean, decimate=2).data


def orders(ctid, k):
    return [ctid.SubmodelOrder(2, 1)] * k


def fit(ctid, data, k=MODES):
    return ctid.mimo_srivc(data, orders(ctid, k), direct_term=True)


def coherence_bounds(frf, inputs):
    """Per output, the fit % a linear model of the inputs could reach: 100 (1 - sqrt(noise
    power / output power)) with the noise power sum_k (1 - gamma_j^2) S_yjyj over the lines,
    (1 - gamma^2) corrected for its bias with M averages, times M / (M - n_u)."""
    coherence = np.asarray(frf.coherence)
    power = np.asarray(frf.output_power)
    m = frf.averages
    noise = (1.0 - coherence) * power * m / (m - inputs)
    ok = np.isfinite(noise).all(axis=1)
    share = noise[ok].sum(axis=0) / power[ok].sum(axis=0)
    return 100.0 * (1.0 - np.sqrt(np.minimum(share, 1.0)))


def siso_fits(ctid, estimation, validation, options):
    """Held-out fit of shaker SISO_SHAKER alone, per accelerometer, with the SISO example's
    structure (one biproper mode, the others strictly proper), started from the data."""
    structure = [ctid.SubmodelOrder(2, 2)] + [ctid.SubmodelOrder(2, 1)] * (SISO_MODES - 1)
    k = SISO_SHAKER - 1
    fits = []
    for j in range(estimation.output_count):
        r = ctid.additive_srivc(estimation.channel(k, j), structure, max_iterations=200)
        fits.append(ctid.validate_model(r.model, validation.channel(k, j), options).fit_percent
                    if r.model is not None else float("nan"))
    return np.array(fits)


def hz(w):
    return w / (2.0 * math.pi)


def pair_modes(a, b):
    """For each mode of `a`, the mode of `b` nearest in frequency."""
    return [min(b, key=lambda m: abs(m.natural_frequency - ma.natural_frequency)) for ma in a]


def stabilisation_points(fits):
    """Stabilisation diagram data over the mode counts: every mode of every usable fit, marked
    stable in frequency / damping when the previous usable count has a mode within the
    tolerances."""
    points = []
    previous = []
    for index, (k, r) in enumerate(fits):
        if not r.verdict.usable:
            continue
        for m in r.modes:
            near = [p for p in previous
                    if abs(p.natural_frequency - m.natural_frequency)
                    <= FREQUENCY_TOLERANCE * m.natural_frequency]
            stable_damping = any(abs(p.damping_ratio - m.damping_ratio)
                                 <= DAMPING_TOLERANCE * m.damping_ratio for p in near)
            points.append({"fit": index, "order": 2 * k, "frequency": m.natural_frequency,
                           "damping_ratio": m.damping_ratio, "stable_pole": m.damping_ratio > 0,
                           "stable_frequency": bool(near), "stable_damping": stable_damping,
                           "converged": r.converged(), "usable": r.verdict.usable})
        previous = list(r.modes)
    return points


def main():
    args = _common.arguments("flexible_structure_mimo", __doc__.splitlines()[0])
    ctid = _common.import_ctid()
    data = load(ctid)
    n = data.size()
    n_est = int(ESTIMATION_SHARE * n)
    estimation, validation = data.segment(0, n_est), data.segment(n_est, n - n_est)
    h = data.sample_time

    result = fit(ctid, estimation)
    print(f"Flexible structure, {data.input_count} shakers -> {data.output_count} "
          f"accelerometers, N = {n} (h = 1/{round(1 / h)} s), {MODES} modes + direct term "
          f"fitted on the first {round(100 * ESTIMATION_SHARE)} %")
    print(f"  {result.message}")
    verdict = "usable" if result.verdict.usable else "WARNING: " + result.verdict.summary()
    print(f"  verdict: {verdict}")
    for m in result.modes:
        print(f"  mode {m.submodel + 1}: f_n = {hz(m.natural_frequency):8.3f} +- "
              f"{hz(m.natural_frequency_se):.3f} Hz   zeta = {m.damping_ratio:.5f} +- "
              f"{m.damping_ratio_se:.5f}   rank-one share {m.rank_one_share:.3f}")

    options = ctid.ValidationOptions()
    options.initial_state = ctid.InitialState.estimate
    held_out = np.asarray(ctid.validate_model(result.model, validation, options).fit_percent)
    single = siso_fits(ctid, estimation, validation, options)
    frf = ctid.welch_frf(data, segment_length=WELCH_SEGMENT, overlap=0.5)
    bound = coherence_bounds(frf, data.input_count)
    better = int(np.sum(held_out > single))
    print(f"  held-out fit (last {round(100 * (1 - ESTIMATION_SHARE))} %): two shakers "
          f"{held_out.min():.1f} to {held_out.max():.1f} %, shaker {SISO_SHAKER} alone "
          f"{np.nanmin(single):.1f} to {np.nanmax(single):.1f} %; the two-shaker model is "
          f"better on {better} of {data.output_count} accelerometers; multiple-coherence "
          f"bound {bound.min():.1f} to {bound.max():.1f} %")

    halves = [fit(ctid, data.segment(0, n // 2)), fit(ctid, data.segment(n // 2, n - n // 2))]
    comparison = []
    for ma, mb in zip(halves[0].modes, pair_modes(halves[0].modes, halves[1].modes)):
        difference = ma.natural_frequency - mb.natural_frequency
        z = difference / math.hypot(ma.natural_frequency_se, mb.natural_frequency_se)
        comparison.append({"first_hz": hz(ma.natural_frequency),
                           "second_hz": hz(mb.natural_frequency),
                           "difference_in_standard_errors": z,
                           "mac": ctid.modal_assurance(ma.shape, mb.shape)})
    print("  two halves: MAC " + ", ".join(f"{c['mac']:.3f}" for c in comparison)
          + "; frequency differences " + ", ".join(
              f"{c['difference_in_standard_errors']:+.1f}" for c in comparison) + " s.e.")

    scan = [(k, result if k == MODES else fit(ctid, estimation, k)) for k in SCAN_MODES]
    points = stabilisation_points(scan)

    # Figures.
    names = list(data.output_names)
    ctid.plotting.mode_shapes(result, output_names=names,
                              title="flexible structure: mode shapes (2 x 28 fit)",
                              filename=os.path.join(args.out, "mode_shapes.png"))
    ctid.plotting.mac_matrix(halves[0].modes, halves[1].modes,
                             title="MAC: first half (rows) against second half",
                             filename=os.path.join(args.out, "mac_halves.png"))
    ctid.plotting.mac_matrix(result.modes, title="MAC between the modes",
                             filename=os.path.join(args.out, "mac.png"))
    ctid.plotting.frf_matrix_overlay(result.model, frf, channels=SHOWN_CHANNELS,
                                     title="FRF (Welch H1) and the 2 x 28 model",
                                     filename=os.path.join(args.out, "frf_overlay.png"))
    ctid.plotting.stabilisation(
        {"stabilisation": points, "fits": [None] * len(scan),
         "recommended": list(SCAN_MODES).index(MODES)},
        title=f"stabilisation: {SCAN_MODES[0]} to {SCAN_MODES[-1]} modes over all channels",
        filename=os.path.join(args.out, "stabilisation.png"))
    ctid.plotting.channel_fits(
        names, {"two shakers": held_out, f"shaker {SISO_SHAKER} alone": single,
                "multiple-coherence bound": bound},
        title="held-out fit per accelerometer",
        filename=os.path.join(args.out, "channel_fits.png"))

    # Tables for docs/examples/flexible_structure_mimo.md.
    mode_rows = [[m.submodel + 1, f"{hz(m.natural_frequency):.3f}",
                  _common.significant(hz(m.natural_frequency_se), 2),
                  _common.significant(m.damping_ratio, 3), _common.significant(m.damping_ratio_se, 2),
                  f"{m.rank_one_share:.3f}"] for m in result.modes]
    # How the iteration ended, without its count: at the rounding floor the count and the
    # last change depend on the machine's last bits (39 or 41 iterations on two x86-64 CPUs),
    # while every figure in the tables agrees.
    ending = ("The iteration converged." if result.converged()
              else f"{result.message[len('mimo_srivc: '):].capitalize()}.")
    modes_table = (f"{ending}\n\n"
                   + _common.markdown_table(["mode", "f_n [Hz]", "± s.e.", "ζ", "± s.e.",
                                             "rank-one share"], mode_rows))
    channel_rows = [[name, _common.percent(a), _common.percent(b), _common.percent(c)]
                    for name, a, b, c in zip(names, held_out, single, bound)]
    channels_table = _common.markdown_table(
        ["accelerometer", "two shakers [%]", f"shaker {SISO_SHAKER} alone [%]",
         "coherence bound [%]"], channel_rows)
    halves_table = _common.markdown_table(
        ["first half [Hz]", "second half [Hz]", "difference [s.e.]", "MAC"],
        [[f"{c['first_hz']:.3f}", f"{c['second_hz']:.3f}",
          f"{c['difference_in_standard_errors']:+.1f}", f"{c['mac']:.3f}"] for c in comparison])
    stable = sorted({round(hz(p["frequency"]), 1) for p in points
                     if p["stable_frequency"] and p["order"] == 2 * MODES})
    # Why a fit failed is left out for the same reason: the 8-mode fit fails at its first step
    # with singular equations on one CPU and a pole at infinity on another.
    left_out = [f"{k} modes (its iteration stopped "
                + ("before completing a step)" if r.iterations == 0
                   else f"after {r.iterations} steps)") for k, r in scan if not r.verdict.usable]
    stabilisation_text = (f"Modes of the {MODES}-mode fit whose frequency the fit with one mode "
                          "fewer has within 1 %: " + ", ".join(f"{f:.1f}" for f in stable)
                          + " Hz.")
    if left_out:
        stabilisation_text += (" Not usable, so not in the diagram: " + "; ".join(left_out)
                               + ".")
    tables = {"modes": modes_table, "channels": channels_table, "halves": halves_table,
              "stabilisation": stabilisation_text}
    index_row = ("| [flexible_structure_mimo](flexible_structure_mimo.md) (main job) | DaISy "
                 f"96-013, 2 shakers → 28 accelerometers | {MODES} shared modes + direct term | "
                 f"held-out fit {held_out.min():.1f}–{held_out.max():.1f} % (shaker "
                 f"{SISO_SHAKER} alone {np.nanmin(single):.1f}–{np.nanmax(single):.1f} %) |")
    readme = (f"It prints the {len(result.modes)} modes it finds ("
              + ", ".join(f"{hz(m.natural_frequency):.2f}" for m in result.modes)
              + f" Hz, each with its standard error and damping ratio); on the held-out last "
              f"{round(100 * (1 - ESTIMATION_SHARE))} % of the record the model fits the 28 "
              f"accelerometers at {held_out.min():.1f} to {held_out.max():.1f} %, where shaker "
              f"{SISO_SHAKER} alone reaches {np.nanmin(single):.1f} to {np.nanmax(single):.1f} "
              f"%, and the two halves of the record give the same modes (MAC ≥ "
              f"{math.floor(min(c['mac'] for c in comparison) * 100) / 100:.2f}).")
    _common.publish(args, "flexible_structure_mimo", tables, index_row, readme)

    summary = {
        "example": "flexible_structure_mimo", "sample_time": h, "samples": n,
        "estimation_samples": n_est, "termination": result.termination.name,
        "iterations": result.iterations, "usable": result.verdict.usable,
        "modes": [{"natural_frequency_hz": hz(m.natural_frequency),
                   "natural_frequency_se_hz": hz(m.natural_frequency_se),
                   "damping_ratio": m.damping_ratio, "damping_ratio_se": m.damping_ratio_se,
                   "rank_one_share": m.rank_one_share,
                   "shape_real": [z.real for z in m.shape],
                   "shape_imag": [z.imag for z in m.shape]} for m in result.modes],
        "output_names": names,
        "held_out_fit_percent": held_out.tolist(), "single_input_fit_percent": single.tolist(),
        "coherence_bound_percent": bound.tolist(), "halves": comparison,
        "halves_usable": [r.verdict.usable for r in halves],
        "stabilisation": [{k: (hz(v) if k == "frequency" else v) for k, v in p.items()}
                          for p in points],
        "scan_usable": {str(k): r.verdict.usable for k, r in scan},
    }
    print(f"  figures and summary in {args.out}/ (mode_shapes.png, mac.png, mac_halves.png, "
          f"frf_overlay.png, stabilisation.png, channel_fits.png, "
          f"{os.path.basename(_common.write_summary(args.out, summary))})")
    return 0 if result.converged() and result.verdict.usable else 1


if __name__ == "__main__":
    sys.exit(main())
