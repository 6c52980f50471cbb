#!/usr/bin/env python3
"""Headline example: a modal (additive) model of a flexible steel subframe from measured
data (DaISy 96-013, data/daisy_flexible_structure): shaker 2 force -> accelerometer 28.

Steps: zero-phase low-pass (8th-order Butterworth, 220 Hz) applied identically to force and
acceleration, then every second sample kept (h = 1/512 s), so the model covers 0-220 Hz;
Welch H1 FRF; the most prominent resonance peaks below 200 Hz give the starting modes;
the additive refined IV estimator (González et al., eq. 29) fits one biproper mode (it
carries the accelerance's direct term) plus strictly proper modes B_i(p)/(1 + a_i1 p +
a_i2 p^2). Prints natural frequencies [Hz] and damping ratios +- standard errors, writes
bode.png, modes.png and summary.json. Results are discussed in
docs/examples/flexible_structure.md.
"""

import math
import os
import sys
import types

import numpy as np
from scipy import signal

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _common  # noqa: E402

SHAKER = 2
SENSOR = 28
MODES = 3
CUTOFF_HZ = 220.0
MAX_MODE_HZ = 200.0
SCAN_MODES = 4


def load(ctid):
    record = ctid.read_csv(_common.data_file("daisy_flexible_structure/flexible_structure.csv"),
                           time="t_s", input=f"u{SHAKER}_force", output=f"y{SENSOR}_acc")
    h, u, y = record.sample_time, record.input, record.output
    u, y = u - u.mean(), y - y.mean()
    # The same zero-phase filter on both signals leaves the force-to-acceleration relation
    # unchanged in the pass band; decimating by 2 then puts the band near Nyquist.
    sos = signal.butter(8, CUTOFF_HZ, fs=1.0 / h, output="sos")
    return 2.0 * h, signal.sosfiltfilt(sos, u)[::2], signal.sosfiltfilt(sos, y)[::2]


def starting_model(ctid, data, frf):
    peaks = [p for p in ctid.resonance_peaks(frf.frequencies, frf.response, min_prominence_db=6)
             if p.frequency / (2 * math.pi) < MAX_MODE_HZ]
    peaks = sorted(sorted(peaks, key=lambda p: -p.prominence_db)[:MODES],
                   key=lambda p: p.frequency)
    submodels = []
    for p in peaks:
        zeta = p.damping_ratio if math.isfinite(p.damping_ratio) else 0.01
        zeta = min(max(zeta, 0.002), 0.05)
        w = p.frequency
        submodels.append(ctid.Submodel(ctid.Polynomial([1.0, 2 * zeta / w, 1 / w**2]),
                                       ctid.Polynomial([1.0]), 0))
    # Poles from the peaks; numerators by linear least squares on the data.
    poles_only = ctid.AdditiveModel(submodels).to_transfer_function()
    orders = [ctid.SubmodelOrder(2, 2)] + [ctid.SubmodelOrder(2, 1)] * (len(peaks) - 1)
    return orders, ctid.group_into_submodels(poles_only, orders, data), peaks


def main():
    args = _common.arguments("flexible_structure", __doc__.splitlines()[0])
    ctid = _common.import_ctid()
    h, u, y = load(ctid)
    data = ctid.SampledData(h, u, y)
    frf = ctid.welch_frf(data, segment_length=1024, overlap=0.5)
    orders, start, peaks = starting_model(ctid, data, frf)
    result = ctid.additive_srivc(data, orders, initial_model=start, max_iterations=200)

    modes = []
    print(f"Flexible structure, shaker {SHAKER} -> accelerometer {SENSOR}, N = {data.size()}, "
          f"h = 1/{round(1 / h)} s")
    print(f"  {result.message}")
    print(f"  fit {result.fit_percent:.1f} %  (the other shaker's response counts as noise)")
    for m in sorted(result.modes, key=lambda m: m.value.natural_frequency):
        f_hz = m.value.natural_frequency / (2 * math.pi)
        f_se = m.standard_error.natural_frequency / (2 * math.pi)
        print(f"  mode {len(modes) + 1}: f_n = {f_hz:8.3f} +- {f_se:.3f} Hz   "
              f"zeta = {m.value.damping_ratio:.5f} +- {m.standard_error.damping_ratio:.5f}")
        modes.append({"natural_frequency_hz": f_hz, "natural_frequency_se_hz": f_se,
                      "damping_ratio": m.value.damping_ratio,
                      "damping_ratio_se": m.standard_error.damping_ratio,
                      "modal_gain": m.value.gain, "modal_gain_se": m.standard_error.gain})

    summary_peaks = [p.frequency / (2 * math.pi) for p in peaks]
    band = np.asarray(frf.frequencies) < 2 * math.pi * CUTOFF_HZ
    shown = types.SimpleNamespace(frequencies=np.asarray(frf.frequencies)[band],
                                  response=np.asarray(frf.response)[band],
                                  coherence=np.asarray(frf.coherence)[band])
    omegas = np.linspace(shown.frequencies[0], 2 * math.pi * CUTOFF_HZ, 4000)
    title = f"shaker {SHAKER} -> accelerometer {SENSOR}"
    ctid.plotting.bode(result, frf=shown, omegas=omegas, title=title,
                       filename=os.path.join(args.out, "bode.png"))
    ctid.plotting.modes(result, frf=shown, omegas=omegas, title=title,
                        filename=os.path.join(args.out, "modes.png"))
    # Structure selection: 1-4 modes of the same form (the first biproper), each started from
    # the FRF peaks, fitted on the first 70 % and scored on the last 30 % (from rest).
    candidates = [ctid.ModelStructure.additive(
        [ctid.SubmodelOrder(2, 2)] + [ctid.SubmodelOrder(2, 1)] * (k - 1))
        for k in range(1, SCAN_MODES + 1)]
    options = ctid.StructureScanOptions()
    options.identification.refined_iv.start = ctid.StartMethod.frf
    options.identification.refined_iv.max_iterations = 200
    scan = ctid.scan_structures(data, candidates, options)

    def describe(structure):
        k = len(structure.orders)
        return f"{k} mode{'s' if k > 1 else ''}"

    ctid.plotting.stabilisation(scan, title=f"{title}: poles of 1-{SCAN_MODES} mode fits",
                                filename=os.path.join(args.out, "stabilisation.png"))
    stable = sorted({round(p.frequency / (2 * math.pi), 1) for p in scan.stabilisation
                     if p.stable_frequency and p.stable_pole})
    held_out = ", ".join(f"{f.validation_fit:.1f}" for f in scan.fits)
    print(f"  structure scan 1..{SCAN_MODES} modes: held-out fits {held_out} %; by held-out "
          f"fit alone {describe(scan.fits[scan.recommended].structure)} ({scan.rule})")
    print(f"  why {MODES} modes nonetheless: the other shaker's response dominates the held-out "
          f"output, so held-out fit barely tells the counts apart; the stabilisation diagram "
          f"shows {len(stable)}: poles at {', '.join(f'{f:.1f}' for f in stable)} Hz keep their "
          f"frequency as the order grows (docs/examples/flexible_structure.md)")

    rows = [[i + 1, f"{m['natural_frequency_hz']:.2f}",
             _common.significant(m["natural_frequency_se_hz"], 2),
             _common.significant(m["damping_ratio"], 2), _common.significant(m["damping_ratio_se"], 2),
             f"{min(summary_peaks, key=lambda f: abs(f - m['natural_frequency_hz'])):.2f}"]
            for i, m in enumerate(modes)]
    table = _common.markdown_table(["mode", "f_n [Hz]", "± s.e.", "ζ", "± s.e.",
                                    "nearest FRF peak [Hz]"], rows)
    header = (f"{result.termination.name.replace('_', ' ').capitalize()} after "
              f"{result.iterations} iterations; fit {_common.percent(result.fit_percent)}.")
    stable_rows = []
    for point in sorted(scan.stabilisation, key=lambda p: (p.order, p.frequency)):
        if point.stable_pole and point.stable_frequency:
            stable_rows.append(f"{point.frequency / (2 * math.pi):.2f} Hz ({point.order} poles"
                               f"{', damping stable too' if point.stable_damping else ''})")
    diagram = "Stable-frequency poles of the diagram: " + "; ".join(stable_rows) + "."
    tables = {"results": header + "\n\n" + table, "scan": _common.scan_table(scan, describe),
              "stabilisation": diagram}
    index_row = (f"| [flexible_structure](flexible_structure.md) | DaISy 96-013, shaker "
                 f"{SHAKER} → accelerometer {SENSOR} | additive, {MODES} modes; scan: "
                 f"{describe(scan.fits[scan.recommended].structure)} by held-out fit, "
                 f"{MODES} modes stable in its diagram | f_n = "
                 + ", ".join(f"{m['natural_frequency_hz']:.2f}" for m in modes) + " Hz |")
    _common.publish(args, "flexible_structure", tables, index_row)
    summary = {
        "example": "flexible_structure",
        "scan_recommended_modes": len(scan.fits[scan.recommended].structure.orders),
        "scan_validation_fits": [f.validation_fit for f in scan.fits],
        "scan_usable": [f.usable for f in scan.fits],
        "stabilisation": [{"order": p.order, "frequency_hz": p.frequency / (2 * math.pi),
                           "damping_ratio": p.damping_ratio, "stable_pole": p.stable_pole,
                           "stable_frequency": p.stable_frequency,
                           "stable_damping": p.stable_damping} for p in scan.stabilisation], "shaker": SHAKER, "accelerometer": SENSOR,
        "sample_time": h, "samples": data.size(),
        "peaks_hz": [p.frequency / (2 * math.pi) for p in peaks],
        "termination": result.termination.name, "iterations": result.iterations,
        "fit_percent": result.fit_percent, "modes": modes,
    }
    print(f"  figures and summary in {args.out}/ (bode.png, modes.png, stabilisation.png, "
          f"{os.path.basename(_common.write_summary(args.out, summary))})")
    return 0 if result.converged() else 1


if __name__ == "__main__":
    sys.exit(main())
