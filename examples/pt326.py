#!/usr/bin/env python3
"""PT326 air heater (CONTSID aero-thermal data, data/contsid_aerothermal_pt326): a first-order
model with an input delay, the delay estimated, validated on the separate validation record.

SRIVC (Young & Jakeman; González et al., Remark 4) of K/(1 + T p) e^{-p d h} for every
delay d = 0..10 samples, the best output-error fit kept (ctid.srivc_delay_scan); then the
model is simulated on the validation record. The published structure (CONTSID's srivcstruc)
is first order with a 5-sample delay; ctid.scan_structures over 1-4 poles at that delay
(scored on the held-out last 30 % of the estimation record) recommends it too. Writes delay_scan.png, validation.png,
residuals.png and summary.json; discussed in docs/examples/pt326.md.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _common  # noqa: E402

MAX_DELAY = 10


def load(ctid, which):
    return ctid.read_csv(_common.data_file(f"contsid_aerothermal_pt326/pt326_{which}.csv"),
                         time="t_s", input="u_heater_voltage", output="y_outlet_temperature")


def main():
    args = _common.arguments("pt326", __doc__.splitlines()[0])
    ctid = _common.import_ctid()
    import matplotlib.pyplot as plt

    estimation, validation = load(ctid, "est"), load(ctid, "val")
    scan = ctid.srivc_delay_scan(estimation, ctid.SubmodelOrder(1, 0), 0, MAX_DELAY)
    r = scan.best
    a1, b0 = r.parameters
    se_a1, se_b0 = r.standard_errors
    report = ctid.validate_model(r.model, validation)
    h = estimation.sample_time

    print(f"PT326 air heater, N = {estimation.size()} + {validation.size()}, h = {h} s")
    print(f"  delay scan 0..{MAX_DELAY} samples: best {r.input_delay_samples} samples "
          f"({r.input_delay_samples * h:.1f} s); {r.message}")
    print(f"  model  {b0:.4f} / ({a1:.4f} p + 1) e^(-{r.input_delay_samples * h:.1f} p)")
    print(f"  gain   {b0:.4f} +- {se_b0:.4f},  time constant {a1:.4f} +- {se_a1:.4f} s")
    print(f"  fit    {r.fit_percent:.1f} % (estimation), {report.fit_percent:.1f} % (validation)")

    figure, ax = plt.subplots(figsize=(6.0, 3.5))
    ax.semilogy(scan.delays, scan.mean_squared_errors, "o-")
    ax.axvline(r.input_delay_samples, color="C1", ls="--", label=f"best: {r.input_delay_samples} samples")
    ax.set_xlabel("input delay [samples of 0.1 s]")
    ax.set_ylabel("output-error MSE")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    ax.set_title("SRIVC first order: delay scan on the estimation record")
    ctid.plotting.save(figure, os.path.join(args.out, "delay_scan.png"))
    plt.close(figure)
    simulated = ctid.model_output(r.model, validation.input, h)
    ctid.plotting.validation(validation, simulated, title="PT326 validation record",
                             filename=os.path.join(args.out, "validation.png"))
    ctid.plotting.residual_correlation(validation.output - simulated, validation.input,
                                       title="validation residuals",
                                       filename=os.path.join(args.out, "residuals.png"))
    # Structure selection without knowing the order: 1..4 poles, n - 1 zeros, at the delay.
    candidates = [ctid.ModelStructure.unfactored(n, n - 1) for n in range(1, 5)]
    options = ctid.StructureScanOptions()
    options.identification.refined_iv.input_delay_samples = r.input_delay_samples
    structures = ctid.scan_structures(estimation, candidates, options)
    chosen = structures.fits[structures.recommended].structure.orders[0]
    print(f"  structure scan 1..4 poles: recommended {chosen.n} pole(s) ({structures.rule})")
    for fit in structures.fits:
        print(f"    n = {fit.structure.orders[0].n}: validation fit {fit.validation_fit:.1f} %, "
              f"YIC {fit.yic:.2f}, usable {fit.usable}")

    def describe(structure):
        o = structure.orders[0]
        return f"{o.n} pole{'s' if o.n > 1 else ''}, {o.m} zero{'s' if o.m != 1 else ''}"

    d = r.input_delay_samples
    results = _common.markdown_table(["", "ours", "published"], [
        ["structure", "first order, m = 0", "first order, nb = 1 (nn = [1 1 5])"],
        ["delay", f"**{d} samples ({d * h:.1f} s)**", "5 samples"],
        ["gain K", f"{b0:.3f} ± {se_b0:.3f}", "—"],
        ["time constant T", f"{a1:.3f} ± {se_a1:.3f} s", "—"],
        ["fit, estimation record", _common.percent(r.fit_percent), "—"],
        ["fit, validation record", _common.percent(report.fit_percent), '"pretty good"'],
    ])
    mse = dict(zip(scan.delays, scan.mean_squared_errors))
    neighbours = [k for k in (d - 1, d, d + 1) if k in mse]
    notes = (
        "The delay scan's output-error MSE at "
        + ", ".join(f"{k}" for k in neighbours) + " samples: "
        + ", ".join((f"**{_common.significant(mse[k], 2)}**" if k == d
                     else _common.significant(mse[k], 2)) for k in neighbours)
        + f". Largest residual autocorrelation on the validation record: "
        f"{report.max_residual_autocorrelation:.2f}.")
    tables = {"results": results, "notes": notes,
              "scan": _common.scan_table(structures, describe)}
    index_row = (f"| [pt326](pt326.md) | CONTSID aero-thermal channel | first order + delay, "
                 f"SRIVC delay scan; scan: {describe(structures.fits[structures.recommended].structure)}"
                 f" | delay {d} samples (published 5), validation fit "
                 f"{_common.percent(report.fit_percent)} |")
    _common.publish(args, "pt326", tables, index_row)
    summary = {
        "example": "pt326", "sample_time": h,
        "delays": list(scan.delays), "mean_squared_errors": list(scan.mean_squared_errors),
        "delay_samples": r.input_delay_samples, "termination": r.termination.name,
        "time_constant_s": a1, "time_constant_se_s": se_a1, "gain": b0, "gain_se": se_b0,
        "fit_estimation_percent": r.fit_percent, "fit_validation_percent": report.fit_percent,
        "validation_max_residual_autocorrelation": report.max_residual_autocorrelation,
        "scan_recommended_poles": chosen.n,
        "scan_poles": [f.structure.orders[0].n for f in structures.fits],
        "scan_validation_fits": [f.validation_fit for f in structures.fits],
        "scan_yic": [f.yic for f in structures.fits],
        "scan_usable": [f.usable for f in structures.fits],
    }
    _common.write_summary(args.out, summary)
    print(f"  figures and summary in {args.out}/")
    return 0 if r.converged() else 1


if __name__ == "__main__":
    sys.exit(main())
