#!/usr/bin/env python3
"""Issue 38's SSI-cov speed comparison in one run: `ctid oma --method ssi-cov` against a
NumPy/SciPy implementation of the same estimator (benchmarks/reference_ssi_cov.py) on one
record.

1. The record: an 8-mass chain of springs and masses with Rayleigh damping (the chain of
   tests/oma/chain_model.h with 8 masses: springs 2e4 N/m, masses 1 + 0.25 i kg, alpha 0.5,
   beta 1e-4; modes 2.77-38.3 Hz, damping 0.7-1.5 %) driven by unit white forces on every mass
   (held over each sample, exact discretisation), h = 5 ms, N = 1e5 samples of the 8
   displacements, 5 % sensor noise, seeded; written as a float64 .npy file (N x 8).
2. `ctid oma d.npy -T 0.005 --output-columns 0:7 --max-order 60` as a whole process, without
   standard errors (`--uncertainty-blocks 0`: the reference computes none) and with them (the
   default), and the reference as a whole process (python3 startup, NumPy/SciPy import,
   np.load, SSI) with the block rows ctid chose (read from its result) and orders 2..60 step 2.
3. The in-process times: ctid.oma through the Python package and the reference's function,
   the record in memory (skipped when the package is not built).
4. The spectral side: `ctid oma --method fdd` as a whole process against the Welch spectral
   matrix by scipy.signal.csd and its singular values at every line by numpy.linalg.svd
   (reference_ssi_cov.py --fdd; ctid's peak picking is not repeated), the same segment
   length; their first singular values must agree to 1e-9 relative.
5. The two must agree on the poles: at every order the same number of poles, and each of
   ctid's poles within --agreement (relative, frequency and damping) of the reference's pole of
   that order nearest it; the largest differences are printed, for the picked modes and for
   every pole of the stabilisation diagram.

Times are medians of --repeat runs (wall clock; CPU time of the child process beside it).
Usage:
    /usr/bin/python3 benchmarks/ssi_cov_benchmark.py [--build build] [--samples 100000]
        [--repeat 5] [--write-record d.npy]
"""

import argparse
import json
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy import linalg

ROOT = pathlib.Path(__file__).resolve().parents[1]
HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import reference_ssi_cov  # noqa: E402

H = 0.005
CHANNELS = 8
MAX_ORDER = 60


def chain_record(samples, seed=1, noise=0.05, masses=CHANNELS):
    """Seeded ambient record of the chain (displacements of every mass, N x masses)."""
    n = masses
    k = np.zeros((n, n))
    for i in range(n):
        k[i, i] = 2.0e4 * (2.0 if i + 1 < n else 1.0)
        if i + 1 < n:
            k[i, i + 1] = k[i + 1, i] = -2.0e4
    m = np.diag(1.0 + 0.25 * np.arange(n))
    minv = np.linalg.inv(m)
    a_c = np.zeros((2 * n, 2 * n))
    a_c[:n, n:] = np.eye(n)
    a_c[n:, :n] = -minv @ k
    a_c[n:, n:] = -minv @ (0.5 * m + 1e-4 * k)
    a_d = linalg.expm(a_c * H)
    b_c = np.zeros((2 * n, n))
    b_c[n:] = minv
    gamma = np.linalg.solve(a_c, (a_d - np.eye(2 * n)) @ b_c)
    rng = np.random.default_rng(seed)
    warmup = 2000
    driven = rng.standard_normal((samples + warmup, n)) @ gamma.T
    state = np.zeros(2 * n)
    y = np.empty((samples + warmup, n))
    for t in range(samples + warmup):
        y[t] = state[:n]
        state = a_d @ state + driven[t]
    y = y[warmup:]
    y += noise * y.std(axis=0) * rng.standard_normal(y.shape)
    lam = np.linalg.eigvals(a_c)
    lam = lam[lam.imag > 0]
    order = np.argsort(np.abs(lam))
    return y, np.abs(lam[order]) / (2 * np.pi), -lam[order].real / np.abs(lam[order])


def timed(command, cwd, repeat):
    """Median wall and CPU seconds of `repeat` runs of a command, and its last stdout."""
    walls, cpus, out = [], [], ""
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        began = time.perf_counter()
        done = subprocess.run([str(c) for c in command], cwd=cwd, capture_output=True, text=True)
        walls.append(time.perf_counter() - began)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
        if done.returncode != 0:
            sys.exit(f"{' '.join(map(str, command))} failed ({done.returncode}):\n{done.stderr}")
        out = done.stdout
    return statistics.median(walls), statistics.median(cpus), out


def median_time(action, repeat):
    times, value = [], None
    for _ in range(repeat):
        began = time.perf_counter()
        value = action()
        times.append(time.perf_counter() - began)
    return statistics.median(times), value


def agreement(ctid_poles, reference_orders):
    """Largest relative frequency and damping differences of each ctid pole (order, f, zeta)
    from the reference's nearest pole of its order, and the orders whose pole counts differ."""
    by_order = {o["order"]: np.array(o["poles"]).reshape(-1, 2) for o in reference_orders}
    counts = {}
    for order, _, _ in ctid_poles:
        counts[order] = counts.get(order, 0) + 1
    differing = [o for o, poles in by_order.items() if len(poles) != counts.get(o, 0)]
    worst_f = worst_z = 0.0
    for order, f, z in ctid_poles:
        poles = by_order.get(order)
        if poles is None or len(poles) == 0:
            return np.inf, np.inf, differing or [order]
        nearest = poles[np.argmin(np.abs(poles[:, 0] - f))]
        worst_f = max(worst_f, abs(nearest[0] - f) / f)
        worst_z = max(worst_z, abs(nearest[1] - z) / z)
    return worst_f, worst_z, differing


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", default=os.environ.get("CTID_BUILD_DIR", ROOT / "build"),
                        help="ctid build folder (apps/ctid/ctid, python/ctid)")
    parser.add_argument("--samples", type=int, default=100000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--agreement", type=float, default=1e-6,
                        help="largest allowed relative difference of a picked mode's frequency "
                             "and damping ratio from the reference's")
    parser.add_argument("--write-record", metavar="FILE.npy",
                        help="only write the record to this .npy file (to time the commands "
                             "by hand) and stop")
    args = parser.parse_args()
    if args.write_record:
        np.save(args.write_record, chain_record(args.samples)[0])
        return
    build = pathlib.Path(args.build).resolve()
    cli = build / "apps" / "ctid" / "ctid"
    if not cli.exists():
        sys.exit(f"{cli} not found; build ctid first (cmake --build build --target ctid_app)")

    y, true_hz, true_zeta = chain_record(args.samples)
    with tempfile.TemporaryDirectory(prefix="ctid_ssi_") as folder:
        folder = pathlib.Path(folder)
        np.save(folder / "d.npy", y)
        oma = [cli, "oma", "d.npy", "-T", H, "--output-columns", f"0:{CHANNELS - 1}",
               "--max-order", MAX_ORDER, "-q", "--force"]
        plain_wall, plain_cpu, _ = timed(oma + ["--uncertainty-blocks", 0, "-o", "r.json"],
                                         folder, args.repeat)
        errors_wall, errors_cpu, _ = timed(oma + ["-o", "e.json"], folder, args.repeat)
        result = json.loads((folder / "r.json").read_text())
        p = result["block_rows"]
        ref_wall, ref_cpu, printed = timed(
            [sys.executable, HERE / "reference_ssi_cov.py", "d.npy", H, p, MAX_ORDER], folder,
            args.repeat)
        reference = json.loads(printed)
        # The spectral side: `ctid oma --method fdd` (automatic segment length) against the
        # Welch spectral matrix and its singular values by SciPy/NumPy.
        fdd_wall, fdd_cpu, _ = timed(oma + ["--method", "fdd", "-o", "f.json"], folder,
                                     args.repeat)
        spectral = json.loads((folder / "f.json").read_text())
        segment = 2 * (len(spectral["spectrum_hz"]) - 1)
        welch_wall, welch_cpu, printed = timed(
            [sys.executable, HERE / "reference_ssi_cov.py", "--fdd", "d.npy", H, segment],
            folder, args.repeat)
        welch = json.loads(printed)

    in_memory = None
    sys.path.insert(0, str(build / "python"))
    try:
        import ctid  # noqa: E402
    except ImportError:
        ctid = None
    if ctid is not None and hasattr(ctid, "oma"):
        ours_s, _ = median_time(lambda: ctid.oma(y, H, max_order=MAX_ORDER, block_rows=p,
                                                 uncertainty_blocks=0), args.repeat)
        theirs_s, _ = median_time(
            lambda: reference_ssi_cov.ssi_cov(y, H, p, MAX_ORDER), args.repeat)
        in_memory = (ours_s, theirs_s)

    poles = [(s["order"], s["frequency_hz"], s["damping_ratio"])
             for s in result["stabilisation"]]
    modes = [(m["order"], m["frequency_hz"], m["damping_ratio"]) for m in result["modes"]]
    all_f, all_z, differing = agreement(poles, reference["orders"])
    mode_f, mode_z, _ = agreement(modes, reference["orders"])

    print(f"SSI-cov, {CHANNELS} channels x N = {args.samples}, h = {H} s, orders 2..{MAX_ORDER}, "
          f"{p} block rows (ctid's automatic choice); medians of {args.repeat} runs")
    print(f"modes: ctid {len(modes)} picked; truth "
          + ", ".join(f"{f:.2f}" for f in true_hz) + " Hz")
    print(f"poles per order: {len(poles)} in all, pole counts differ at "
          f"{len(differing)} of {len(reference['orders'])} orders")
    print(f"largest relative difference from the reference: picked modes frequency "
          f"{mode_f:.1e}, damping {mode_z:.1e}; every pole frequency {all_f:.1e}, "
          f"damping {all_z:.1e}")
    s1 = np.asarray(spectral["first_singular_value"])
    welch_s1 = np.asarray(welch["first_singular_value"])
    s1_difference = (np.max(np.abs(s1 - welch_s1) / np.abs(welch_s1))
                     if s1.shape == welch_s1.shape else np.inf)
    print(f"fdd: {len(spectral['modes'])} modes; first singular value ({segment}-sample segments, "
          f"{len(s1)} lines) vs scipy.signal.csd + numpy.linalg.svd: largest relative "
          f"difference {s1_difference:.1e}")
    print()
    print(f"{'what is timed':<60} {'ctid s':>8} {'reference s':>12} {'ratio':>7}")
    rows = [("whole process, no standard errors (wall)", plain_wall, ref_wall),
            ("whole process, no standard errors (CPU)", plain_cpu, ref_cpu),
            ("whole process, ctid with standard errors (wall)", errors_wall, ref_wall)]
    if in_memory is not None:
        rows.append(("in memory: ctid.oma vs reference_ssi_cov.ssi_cov", *in_memory))
    rows += [("fdd whole process vs Welch matrix + SVD by SciPy (wall)", fdd_wall, welch_wall),
             ("fdd whole process vs Welch matrix + SVD by SciPy (CPU)", fdd_cpu, welch_cpu)]
    for name, ours_s, theirs_s in rows:
        print(f"{name:<60} {ours_s:8.3f} {theirs_s:12.3f} {theirs_s / ours_s:6.1f}x")
    print(f"(reference inside its process: np.load {reference['seconds_load']:.3f} s, "
          f"SSI {reference['seconds_ssi']:.3f} s)")
    if not s1_difference <= 1e-9:
        sys.exit(f"the first singular values differ from SciPy's by {s1_difference:.2e}")
    if not (mode_f <= args.agreement and mode_z <= args.agreement):
        sys.exit(f"the picked modes differ from the reference by {max(mode_f, mode_z):.2e} > "
                 f"{args.agreement:.0e}")


if __name__ == "__main__":
    main()
