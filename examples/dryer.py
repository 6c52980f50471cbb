#!/usr/bin/env python3
"""Hair dryer (DaISy dryer, Ljung's PT326, data/daisy_dryer_ljung): heater voltage -> outlet
temperature, the structure chosen by a scan, validated before and after removing the means.

The record is not centred (input mean 5.0 V, output mean 4.89 V, PROVENANCE.md), and a linear
model G(p) simulated from rest cannot produce an output offset it was not given an input
for. Samples 1-500 estimate, 501-1000 validate (each part with its own means removed when
detrending, as `ctid validate --detrend mean` does on a validation file).

1. ctid.scan_structures on the detrended estimation record: 1-4 poles, no zero, each with a
   delay scan over 0-10 samples; first 70 % fitted, last 30 % held out.
2. The recommended structure fitted by ctid.identify (SRIVC with its delay scan) on the raw
   and on the detrended estimation record, each validated on the matching validation record
   (ctid.validate_model from rest; the raw one also from its estimated initial state).
Writes validation.png and summary.json; discussed in docs/examples/dryer.md.
"""

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _common  # noqa: E402

ESTIMATION = 500
MAX_POLES = 4
MAX_DELAY = 10


def load(ctid):
    return ctid.read_csv(_common.data_file("daisy_dryer_ljung/dryer.csv"),
                         time="t_s_assumed_0.08", input="u_heater_voltage",
                         output="y_outlet_temperature")


def parts(data, detrend):
    """(estimation, validation) SampledData, each preprocessed on its own."""
    return (data.preprocess(end_row=ESTIMATION, detrend=detrend).data,
            data.preprocess(first_row=ESTIMATION, detrend=detrend).data)


def describe(structure):
    o = structure.orders[0]
    return f"{o.n} pole{'s' if o.n > 1 else ''}, {o.m} zeros"


def main():
    args = _common.arguments("dryer", __doc__.splitlines()[0])
    ctid = _common.import_ctid()
    import matplotlib.pyplot as plt

    data = load(ctid)
    h = data.sample_time
    raw_est, raw_val = parts(data, ctid.Detrend.none)
    est, val = parts(data, ctid.Detrend.mean)

    options = ctid.StructureScanOptions()
    options.identification.delay_scan_samples = ctid.DelayRange(min=0, max=MAX_DELAY)
    candidates = [ctid.ModelStructure.unfactored(n, 0) for n in range(1, MAX_POLES + 1)]
    scan = ctid.scan_structures(est, candidates, options)
    chosen = scan.fits[scan.recommended]

    fit_options = ctid.IdentificationOptions(delay_scan_samples=ctid.DelayRange(min=0, max=MAX_DELAY))
    rows = {}
    models = {}
    from_state = ctid.ValidationOptions(initial_state=ctid.InitialState.estimate)
    for label, e, v in (("raw", raw_est, raw_val), ("detrended", est, val)):
        r = ctid.identify(e, chosen.structure, fit_options).estimate
        zero = ctid.validate_model(r.model, v)
        state = ctid.validate_model(r.model, v, from_state)
        models[label] = r
        rows[label] = {
            "termination": r.termination.name, "delay_samples": round(r.model.input_delay / h),
            "static_gain": float(r.transfer_function.dc_gain()),
            "poles": sorted(float(p.real) for p in r.transfer_function.poles()),
            "poles_imag": sorted(abs(float(p.imag)) for p in r.transfer_function.poles()),
            "fit_estimation_percent": r.fit_percent,
            "fit_validation_percent": zero.fit_percent,
            "fit_validation_estimated_state_percent": state.fit_percent,
        }

    raw, done = rows["raw"], rows["detrended"]
    print(f"Dryer (PT326), N = {data.size()}, h = {h} s; samples 1-{ESTIMATION} estimate, "
          f"{ESTIMATION + 1}-{data.size()} validate")
    print(f"  structure scan (detrended): recommended {describe(chosen.structure)}, "
          f"held-out fit {chosen.validation_fit:.1f} % ({scan.rule})")
    for label, row in rows.items():
        print(f"  {label:9s} delay {row['delay_samples']}, static gain {row['static_gain']:.3f}, "
              f"fit {row['fit_estimation_percent']:.1f} % (estimation), "
              f"{row['fit_validation_percent']:.1f} % (validation from rest), "
              f"{row['fit_validation_estimated_state_percent']:.1f} % (estimated state)")

    figure, (ax_raw, ax_done) = plt.subplots(2, 1, sharex=True, figsize=(8.0, 5.5))
    for ax, label, v in ((ax_raw, "raw", raw_val), (ax_done, "detrended", val)):
        simulated = ctid.validation_output(models[label].model, v, ctid.ValidationOptions())
        t = np.asarray(v.time)
        ax.plot(t, v.output, color="0.5", lw=1, label="measured")
        ax.plot(t, simulated, color="C0" if label == "raw" else "C1", lw=1,
                label=f"{label} model from rest: fit {rows[label]['fit_validation_percent']:.1f} %")
        ax.set_ylabel("outlet temperature [V]")
        ax.grid(True, alpha=0.3)
        ax.margins(y=0.3)
        ax.legend(fontsize=8, loc="lower right")
    ax_raw.set_title("dryer validation record (samples 501-1000): raw, then means removed")
    ax_done.set_xlabel("time [s]")
    ctid.plotting.save(figure, os.path.join(args.out, "validation.png"))
    plt.close(figure)

    results = _common.markdown_table(
        ["data", "delay", "static gain", "fit, estimation", "validation fit from rest",
         "validation fit, estimated initial state"],
        [[label, f"{row['delay_samples']} samples", f"{row['static_gain']:.3f}",
          _common.percent(row["fit_estimation_percent"]),
          ("**" + _common.percent(row["fit_validation_percent"]) + "**"),
          _common.percent(row["fit_validation_estimated_state_percent"])]
         for label, row in (("raw (means kept)", raw), ("means removed", done))])
    tables = {"scan": _common.scan_table(scan, describe), "results": results}
    index_row = (f"| [dryer](dryer.md) | DaISy dryer (Ljung's PT326) | "
                 f"{describe(chosen.structure)}, delay {done['delay_samples']} samples (scan) | "
                 f"validation fit {_common.percent(raw['fit_validation_percent'])} raw, "
                 f"{_common.percent(done['fit_validation_percent'])} with the means removed |")
    _common.publish(args, "dryer", tables, index_row)
    _common.write_summary(args.out, {
        "example": "dryer", "sample_time": h, "estimation_samples": ESTIMATION,
        "scan_recommended_poles": chosen.structure.orders[0].n,
        "scan_poles": [f.structure.orders[0].n for f in scan.fits],
        "scan_validation_fits": [f.validation_fit for f in scan.fits],
        "scan_yic": [f.yic for f in scan.fits], "scan_usable": [f.usable for f in scan.fits],
        "raw": raw, "detrended": done,
    })
    print(f"  figures and summary in {args.out}/")
    return 0 if all(m.converged() for m in models.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
