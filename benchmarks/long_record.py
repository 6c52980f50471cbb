#!/usr/bin/env python3
"""Issue 14's long-record targets in one run: `ctid fit` of two modes from the automatic start,
and `ctid frf` (Welch), on a record of N samples (default 1e7), each as a whole process, with
its wall time and peak memory.

The record: two modes 1/(1 + 0.0318 p + 0.00253 p^2) (19.9 rad/s, zeta 0.32) and
0.2/(1 + 0.0064 p + 0.000101 p^2) (99.5 rad/s, zeta 0.32) in parallel, driven by a PRBS held
for 5 samples, h = 0.5 ms, white output noise of standard deviation 0.05; written as a
float64 .npy file (t, u, y columns), the binary input meant for long records (decision 0022).
The fit must find both modes within 1 % of the truth. Wall time and peak resident memory
(and user + system CPU time) come from /usr/bin/time; a second line gives the same for --samples / 10 so the growth per
sample shows, and a `fit4` line fits four modes to the shorter record (memory per sample must
not grow with the order). Usage:

    /usr/bin/python3 benchmarks/long_record.py [--build build] [--samples 10000000]
"""

import argparse
import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
TRUTH = [((1.0, 0.0318, 0.00253), 1.0), ((1.0, 0.0064, 0.000101), 0.2)]


def record(ctid, n, h=0.0005):
    u = ctid.prbs(n, register_length=10, samples_per_bit=5)
    model = ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial(list(a)), ctid.Polynomial([b]))
                                for a, b in TRUTH])
    y = ctid.simulate(model, u, h) + ctid.white_noise(n, 0.05, 3)
    return np.column_stack([h * np.arange(n), u, y])


def timed(cli, command, path, folder, *flags):
    out = folder / "r.json"
    done = subprocess.run(["/usr/bin/time", "-f", "%e %U %S %M", str(cli), command, str(path),
                           "--time-column", "0", "--input-column", "1", "--output-column", "2",
                           *flags, "-q", "--force", "-o", str(out)],
                          capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"ctid {command} failed ({done.returncode}):\n{done.stderr}")
    wall, user, system, kilobytes = done.stderr.strip().splitlines()[-1].split()
    return (float(wall), float(user) + float(system), float(kilobytes) / 1024,
            json.loads(out.read_text()))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", default=os.environ.get("CTID_BUILD_DIR", ROOT / "build"))
    parser.add_argument("--samples", type=int, default=10_000_000)
    args = parser.parse_args()
    build = pathlib.Path(args.build).resolve()
    cli = build / "apps" / "ctid" / "ctid"
    if not cli.exists():
        sys.exit(f"{cli} not found; build ctid first (cmake --build build)")
    sys.path.insert(0, str(build / "python"))
    import ctid  # noqa: E402

    print(f"{'ctid':<5} {'N':>10} {'wall s':>8} {'CPU s':>6} {'peak MiB':>9} {'bytes/sample':>13} {'iterations':>10}  modes "
          "(rad/s, zeta)")
    with tempfile.TemporaryDirectory(prefix="ctid_long_") as folder:
        folder = pathlib.Path(folder)
        for n in (args.samples // 10, args.samples):
            path = folder / "d.npy"
            np.save(path, record(ctid, n))
            wall, cpu, mib, _ = timed(cli, "frf", path, folder)
            print(f"{'frf':<5} {n:>10} {wall:8.2f} {cpu:6.2f} {mib:9.0f} {mib * 2**20 / n:13.0f}")
            wall, cpu, mib, result = timed(cli, "fit", path, folder, "--modes", "2")
            modes = sorted((m["natural_frequency"], m["damping_ratio"]) for m in result["modes"])
            truth = sorted((1 / math.sqrt(a[2]), a[1] / (2 * math.sqrt(a[2]))) for a, _ in TRUTH)
            found = all(abs(w - wt) <= 0.01 * wt and abs(z - zt) <= 0.01 * zt
                        for (w, z), (wt, zt) in zip(modes, truth))
            print(f"{'fit':<5} {n:>10} {wall:8.2f} {cpu:6.2f} {mib:9.0f} {mib * 2**20 / n:13.0f} "
                  f"{result['iterations']:>10}  " +
                  ", ".join(f"({w:.2f}, {z:.4f})" for w, z in modes))
            if not found:
                sys.exit(f"the fit missed the modes {truth}")
            if n == args.samples // 10:
                # Memory per sample must not grow with the model order: four modes (two of
                # them spurious) on the same record.
                wall, cpu, mib, result = timed(cli, "fit", path, folder, "--modes", "4")
                print(f"{'fit4':<5} {n:>10} {wall:8.2f} {cpu:6.2f} {mib:9.0f} "
                      f"{mib * 2**20 / n:13.0f} {result['iterations']:>10}")


if __name__ == "__main__":
    main()
