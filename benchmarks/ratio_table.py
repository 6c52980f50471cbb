#!/usr/bin/env python3
"""Issue 14's reference comparison in one run: ctid against a NumPy/SciPy implementation of
the same additive SRIVC iteration (benchmarks/reference_srivc.py) on one record.

1. `ctid simulate` writes the González et al. Section 6.1 system (four modes,
   examples/models/gonzalez_6_1_open_loop.json) under a 0.01-3 Hz multisine, N = 1e5 samples,
   h = 0.05 s, with the paper's coloured noise (q + 0.5)/(q - 0.85), var e = 0.02, to CSV,
   and the same numbers to .npy.
2. Both fit four modes from the same start (the truth with a_1 x 1.15, a_2 x 0.96, b_0 x 1.1):
   `ctid fit d.csv --modes 4 --initial start.json` as a whole process, also from d.npy, and
   the reference as a whole process (python3 startup, SciPy import, np.loadtxt, iteration);
   then the iterations alone, data in memory: ctid.additive_srivc through the Python
   package (without the covariance, which the reference does not compute) and the
   reference's function.
3. The estimates must agree: the largest relative difference over the 12 parameters is
   printed (and the script fails above --agreement).

Times are the best of --repeat runs (wall clock). Usage:
    python3 benchmarks/ratio_table.py [--build build] [--samples 100000] [--repeat 3]
"""

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
MODELS = ROOT / "examples" / "models"
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import reference_srivc  # noqa: E402


def best_time(action, repeat):
    best = float("inf")
    value = None
    for _ in range(repeat):
        began = time.perf_counter()
        value = action()
        best = min(best, time.perf_counter() - began)
    return best, value


def run(command, cwd):
    done = subprocess.run([str(c) for c in command], cwd=cwd, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{' '.join(map(str, command))} failed ({done.returncode}):\n{done.stderr}")
    return done.stdout


def parameters(submodels):
    return np.concatenate([np.r_[s["denominator_ascending"][1:], s["numerator_ascending"]]
                           for s in submodels])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", default=os.environ.get("CTID_BUILD_DIR", ROOT / "build"),
                        help="ctid build folder (apps/ctid/ctid, python/ctid)")
    parser.add_argument("--samples", type=int, default=100000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--agreement", type=float, default=1e-8,
                        help="largest allowed relative difference of the estimates")
    args = parser.parse_args()
    build = pathlib.Path(args.build).resolve()
    cli = build / "apps" / "ctid" / "ctid"
    if not cli.exists():
        sys.exit(f"{cli} not found; build ctid first (cmake --build build)")
    sys.path.insert(0, str(build / "python"))
    import ctid  # noqa: E402

    with tempfile.TemporaryDirectory(prefix="ctid_ratio_") as folder:
        folder = pathlib.Path(folder)
        periods = 8
        run([cli, "simulate", "-m", MODELS / "gonzalez_6_1_open_loop.json", "-e", "multisine",
             "-n", args.samples, "-T", "0.05", "--periods", periods, "--min-frequency-hz", "0.01",
             "--max-frequency-hz", "3", "--seed", "1", "--noise-filter",
             MODELS / "gonzalez_6_1_noise_filter.json", "--noise-std", "0.1414", "--noise-seed",
             "7", "-o", "d.csv", "-q"], folder)
        table = np.loadtxt(folder / "d.csv", delimiter=",", skiprows=1)
        np.save(folder / "d.npy", table)
        truth = json.loads((MODELS / "gonzalez_6_1_open_loop.json").read_text())
        start = {"type": "additive_model", "submodels": [], "input_delay": 0.0}
        for s in truth["submodels"]:
            a = s["denominator_ascending"]
            start["submodels"].append({
                "denominator_ascending": [1.0, a[1] * 1.15, a[2] * 0.96],
                "numerator_ascending": [s["numerator_ascending"][0] * 1.1],
                "integrators": 0})
        (folder / "start.json").write_text(json.dumps(start))

        fit = [cli, "fit", "--modes", "4", "--initial", "start.json", "-q", "--force"]
        ctid_csv, _ = best_time(lambda: run(fit + ["d.csv", "-o", "r.json"], folder),
                                args.repeat)
        ctid_npy, _ = best_time(
            lambda: run(fit + ["d.npy", "--time-column", "0", "--input-column", "1",
                               "--output-column", "2", "-o", "n.json"], folder), args.repeat)
        reference_process, printed = best_time(
            lambda: run([sys.executable, pathlib.Path(__file__).parent / "reference_srivc.py",
                         "d.csv", "start.json"], folder), args.repeat)
        reference = json.loads(printed)

        # The iterations alone, the data in memory.
        t, u, y = table[:, 0], table[:, 1], table[:, 2]
        h = (t[-1] - t[0]) / (len(t) - 1)
        data = ctid.SampledData(h, u, y)
        initial = ctid.AdditiveModel([
            ctid.Submodel(ctid.Polynomial(s["denominator_ascending"]),
                          ctid.Polynomial(s["numerator_ascending"])) for s in start["submodels"]])
        options = ctid.RefinedIvOptions(initial_model=initial, compute_covariance=False)
        orders = [ctid.SubmodelOrder(2, 0)] * 4
        ctid_memory, estimate = best_time(lambda: ctid.additive_srivc(data, orders, options),
                                          args.repeat)
        pairs = [(s["denominator_ascending"], s["numerator_ascending"])
                 for s in start["submodels"]]
        reference_memory, in_memory = best_time(
            lambda: reference_srivc.additive_srivc(u, y, h, pairs), args.repeat)

        # The automatic start against the fit it starts (issue 14: at most 2x), in memory:
        # four modes (initial_additive_model) and the unfactored SRIVC 8/6
        # (initial_transfer_function), each fit run from its start with the covariance, as
        # `ctid fit` runs it.
        starts = []
        for label, structure in (("4 modes", orders), ("SRIVC 8/6", [ctid.SubmodelOrder(8, 6)])):
            if len(structure) == 1:
                def find_start():
                    g = ctid.initial_transfer_function(data, structure[0])
                    return ctid.AdditiveModel([ctid.Submodel(g.denominator, g.numerator)])
            else:
                def find_start():
                    return ctid.initial_additive_model(data, structure)
            start_s, found = best_time(find_start, args.repeat)
            fit_s, fitted = best_time(lambda: ctid.additive_srivc(
                data, structure, ctid.RefinedIvOptions(initial_model=found)), args.repeat)
            starts.append((label, start_s, fit_s, fitted))

        result = json.loads((folder / "r.json").read_text())
        ours = parameters(result["model"]["submodels"])
        theirs = parameters(reference["submodels"])
        difference = np.max(np.abs(ours - theirs) / np.abs(theirs))
        from_npy = parameters(json.loads((folder / "n.json").read_text())["model"]["submodels"])
        memory_difference = np.max(np.abs(np.asarray(estimate.parameters) -
                                          parameters(in_memory["submodels"])) / np.abs(theirs))

    print(f"Section 6.1, four modes, N = {args.samples}, h = 0.05 s, coloured noise; "
          f"best of {args.repeat} runs")
    print(f"iterations: ctid {result['iterations']} ({result['termination']}), "
          f"reference {reference['iterations']} "
          f"({'converged' if reference['converged'] else 'iteration limit'})")
    print(f"largest relative difference of the 12 parameters: ctid fit vs reference "
          f"{difference:.2e}, in memory {memory_difference:.2e}; .npy vs CSV "
          f"{np.max(np.abs(from_npy - ours)):.1e} (bit-identical when 0)")
    print()
    print(f"{'what is timed':<58} {'ctid s':>8} {'reference s':>12} {'ratio':>7}")
    rows = [
        ("whole process: ctid fit d.csv vs python3 reference_srivc.py", ctid_csv,
         reference_process),
        ("whole process, ctid reading d.npy", ctid_npy, reference_process),
        ("iterations only, data in memory (no covariance)", ctid_memory, reference_memory),
    ]
    for name, ours_s, theirs_s in rows:
        print(f"{name:<58} {ours_s:8.3f} {theirs_s:12.3f} {theirs_s / ours_s:6.1f}x")
    print(f"(reference inside its process: np.loadtxt {reference['seconds_load']:.3f} s, "
          f"iterations {reference['seconds_fit']:.3f} s)")
    print()
    print(f"{'automatic start vs the fit it starts (in memory)':<58} {'start s':>8} {'fit s':>12} "
          f"{'ratio':>7}")
    for label, start_s, fit_s, fitted in starts:
        name = f"{label} ({fitted.iterations} iterations from the start, {fitted.termination.name})"
        print(f"{name:<58} {start_s:8.3f} {fit_s:12.3f} {start_s / fit_s:6.2f}x")
    if not difference <= args.agreement:
        sys.exit(f"the estimates differ by {difference:.2e} > {args.agreement:.0e}")


if __name__ == "__main__":
    main()
