#!/usr/bin/env python3
"""Pilot crane (CONTSID crane data, data/contsid_crane): motor voltage -> load angle, whose
lightly damped pendulum mode is found by a structure scan and validated from rest and from
the estimated initial state.

As in CONTSID's demo, the first two PRBS periods are a transient: periods 3-4 (t = 20.32 to
40.63 s) estimate, period 5 (t = 40.64 to 50.79 s) validates. Both records are cut out of the
running experiment, so neither starts at rest.

1. ctid.scan_structures on the estimation record: 1 pole, then 2-4 poles with one zero, each
   fitted with its initial conditions estimated (RefinedIvOptions.initial_conditions) on
   the first 70 % and scored on the held-out last 30 %; the stabilisation diagram of the
   poles.
2. The recommended structure fitted by ctid.identify with the initial conditions assumed zero
   and estimated, each model validated on period 5 from rest and from the least-squares
   initial state (ValidationOptions.initial_state).
Writes stabilisation.png, validation.png and summary.json; discussed in docs/examples/crane.md.
"""

import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _common  # noqa: E402

PERIOD = 1016  # PRBS period [samples] (PROVENANCE.md)
ESTIMATION = (2 * PERIOD, 4 * PERIOD)
VALIDATION = (4 * PERIOD, 5 * PERIOD)
STRUCTURES = [(1, 0), (2, 1), (3, 1), (4, 1)]


def load(ctid):
    return ctid.read_csv(_common.data_file("contsid_crane/crane.csv"), time="t_s",
                         input="u_motor_voltage", output="y2_load_angle")


def describe(structure):
    o = structure.orders[0]
    return f"{o.n} pole{'s' if o.n > 1 else ''}, {o.m} zero{'s' if o.m != 1 else ''}"


def pendulum(tf):
    """(f_n [Hz], zeta) of the lightly damped complex pole pair of a transfer function."""
    poles = [p for p in tf.poles() if p.imag > 0]
    p = min(poles, key=lambda p: -p.real / abs(p))
    return abs(p) / (2 * math.pi), -p.real / abs(p)


def main():
    args = _common.arguments("crane", __doc__.splitlines()[0])
    ctid = _common.import_ctid()
    import matplotlib.pyplot as plt

    data = load(ctid)
    h = data.sample_time
    est = data.preprocess(first_row=ESTIMATION[0], end_row=ESTIMATION[1]).data
    val = data.preprocess(first_row=VALIDATION[0], end_row=VALIDATION[1]).data

    options = ctid.StructureScanOptions()
    options.identification.refined_iv.initial_conditions = ctid.InitialConditions.estimate
    scan = ctid.scan_structures(est, [ctid.ModelStructure.unfactored(n, m) for n, m in STRUCTURES],
                                options)
    chosen = scan.fits[scan.recommended]
    ctid.plotting.stabilisation(scan, title="crane load angle: poles of 1-4 pole fits",
                                filename=os.path.join(args.out, "stabilisation.png"))
    plt.close("all")

    rows, models = {}, {}
    for label, conditions in (("zero", ctid.InitialConditions.zero),
                              ("estimate", ctid.InitialConditions.estimate)):
        r = ctid.identify(est, chosen.structure,
                          refined_iv=ctid.RefinedIvOptions(initial_conditions=conditions)).estimate
        fn, zeta = pendulum(r.transfer_function)
        fits = {}
        for state in ("zero", "estimate"):
            report = ctid.validate_model(
                r.model, val, ctid.ValidationOptions(initial_state=getattr(ctid.InitialState, state)))
            fits[state] = report.fit_percent
        models[label] = r
        rows[label] = {"termination": r.termination.name, "fit_estimation_percent": r.fit_percent,
                       "pendulum_hz": fn, "pendulum_damping": zeta,
                       "stable": bool(r.transfer_function.is_stable()),
                       "fit_validation_from_rest_percent": fits["zero"],
                       "fit_validation_estimated_state_percent": fits["estimate"]}

    before, after = rows["zero"], rows["estimate"]
    print(f"Crane, motor voltage -> load angle, h = {h} s; periods 3-4 estimate "
          f"({est.size()} samples), period 5 validates ({val.size()})")
    print(f"  structure scan: recommended {describe(chosen.structure)}, held-out fit "
          f"{chosen.validation_fit:.1f} % ({scan.rule})")
    for label, row in rows.items():
        print(f"  initial conditions {label:8s}: pendulum {row['pendulum_hz']:.4f} Hz, zeta "
              f"{row['pendulum_damping']:.4f}; fit {row['fit_estimation_percent']:.1f} % "
              f"(estimation), validation {row['fit_validation_from_rest_percent']:.1f} % from rest, "
              f"{row['fit_validation_estimated_state_percent']:.1f} % from the estimated state")

    figure, axes = plt.subplots(2, 1, sharex=True, figsize=(8.0, 5.5))
    t = np.asarray(val.time)
    for ax, label, state, text in (
            (axes[0], "zero", ctid.InitialState.zero,
             "fitted and validated from rest"),
            (axes[1], "estimate", ctid.InitialState.estimate,
             "initial conditions estimated in the fit and the validation")):
        key = "fit_validation_from_rest_percent" if state == ctid.InitialState.zero \
            else "fit_validation_estimated_state_percent"
        simulated = ctid.validation_output(models[label].model, val,
                                           ctid.ValidationOptions(initial_state=state))
        ax.plot(t, val.output, color="0.5", lw=1, label="measured")
        ax.plot(t, simulated, color="C0" if label == "zero" else "C1", lw=1,
                label=f"{text}: fit {rows[label][key]:.1f} %")
        ax.set_ylabel("load angle [rad]")
        ax.grid(True, alpha=0.3)
        ax.margins(y=0.3)
        ax.legend(fontsize=8, loc="lower right")
    axes[0].set_title("crane validation record (PRBS period 5)")
    axes[1].set_xlabel("time [s]")
    ctid.plotting.save(figure, os.path.join(args.out, "validation.png"))
    plt.close(figure)

    results = _common.markdown_table(
        ["fit's initial conditions", "pendulum f_n", "ζ", "fit, estimation",
         "validation fit from rest", "validation fit, estimated initial state"],
        [[label, f"{_common.significant(row['pendulum_hz'])} Hz",
          _common.significant(row["pendulum_damping"], 3),
          _common.percent(row["fit_estimation_percent"]),
          _common.percent(row["fit_validation_from_rest_percent"]),
          _common.percent(row["fit_validation_estimated_state_percent"])]
         for label, row in (("zero", before), ("estimated", after))])
    results += (f"\n\nBefore (fitted and validated from rest): "
                f"**{_common.percent(before['fit_validation_from_rest_percent'])}**; after "
                f"(initial conditions estimated in both): "
                f"**{_common.percent(after['fit_validation_estimated_state_percent'])}**.")
    tables = {"scan": _common.scan_table(scan, describe), "results": results}
    index_row = (f"| [crane](crane.md) | CONTSID pilot crane, motor voltage → load angle | "
                 f"{describe(chosen.structure)} (scan), pendulum "
                 f"{_common.significant(after['pendulum_hz'])} Hz | validation fit "
                 f"{_common.percent(before['fit_validation_from_rest_percent'])} from rest, "
                 f"{_common.percent(after['fit_validation_estimated_state_percent'])} with the "
                 f"initial state estimated |")
    _common.publish(args, "crane", tables, index_row)
    _common.write_summary(args.out, {
        "example": "crane", "sample_time": h, "estimation_rows": list(ESTIMATION),
        "validation_rows": list(VALIDATION),
        "scan_recommended": list(STRUCTURES[scan.recommended]),
        "scan_structures": [list(s) for s in STRUCTURES],
        "scan_validation_fits": [f.validation_fit for f in scan.fits],
        "scan_usable": [f.usable for f in scan.fits],
        "stabilisation": [{"order": p.order, "frequency_hz": p.frequency / (2 * math.pi),
                           "damping_ratio": p.damping_ratio, "stable_pole": p.stable_pole,
                           "stable_frequency": p.stable_frequency}
                          for p in scan.stabilisation],
        "initial_conditions_zero": before, "initial_conditions_estimate": after,
    })
    print(f"  figures and summary in {args.out}/")
    return 0 if all(m.converged() for m in models.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
