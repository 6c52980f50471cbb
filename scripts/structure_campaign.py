#!/usr/bin/env python3
"""Seeded campaign of the structure scan (issue 11): how often ctid.scan_structures recommends
the true number of modes, and whether an over-parameterised fit ever comes back usable with a
worse held-out fit than the true order.

Each run draws a system of K lightly damped modes (natural frequencies spread over a decade
and a half below a quarter of the Nyquist frequency, damping ratios 0.01-0.1, gains of both
signs), drives it with seeded white noise, adds white output noise at the given SNR, and
scans K-2..K+2 modes (at least 1). Usage:

    PYTHONPATH=build/python /usr/bin/python3 scripts/structure_campaign.py [--modes 1:6]
        [--seeds 20] [--snr 20] [--samples 4000] [--json out.json]

Prints one line per K and the overall rate; exit status 0 always (a measurement, not a test).
"""

import argparse
import json
import math
import sys

import numpy as np


def system(ctid, modes, rng, h):
    """K modes with natural frequencies in [top / 10^1.5, top], top a quarter of the Nyquist
    frequency, at least a factor 1.3 apart (so that K is well defined)."""
    top = math.pi / h / 4
    while True:
        freqs = np.sort(top * 10 ** (-1.5 * rng.random(modes)))
        if modes == 1 or np.min(freqs[1:] / freqs[:-1]) >= 1.3:
            break
    submodels = []
    for w in freqs:
        zeta = 10 ** rng.uniform(-2, -1)
        gain = rng.choice([-1, 1]) * 10 ** rng.uniform(-0.5, 0.5)
        a = ctid.Polynomial([1.0, 2 * zeta / w, 1 / w ** 2])
        submodels.append(ctid.Submodel(a=a, b=ctid.Polynomial([gain]), integrators=0))
    return ctid.AdditiveModel(submodels), freqs


def scan_once(ctid, modes, seed, samples=4000, snr=20.0, h=0.01):
    """One seeded run: (the recommended number of modes, 0 if none; how many usable
    over-parameterised fits score a held-out fit more than 1 point below the true order's)."""
    rng = np.random.default_rng(1000 * modes + seed)
    model, _ = system(ctid, modes, rng, h)
    u = ctid.white_noise(samples, 1.0, 10_000 + 100 * modes + seed)
    y0 = ctid.simulate(model, u, h)
    sigma = math.sqrt(np.mean(y0 ** 2)) * 10 ** (-snr / 20)
    y = y0 + ctid.white_noise(samples, sigma, 20_000 + 100 * modes + seed)
    counts = list(range(max(1, modes - 2), modes + 3))
    scan = ctid.scan_structures(ctid.SampledData(h, u, y),
                                [ctid.ModelStructure.modes(k) for k in counts])
    chosen = counts[scan.recommended] if scan.recommended >= 0 else 0
    true_fit = scan.fits[counts.index(modes)]
    worse = sum(1 for k, fit in zip(counts, scan.fits)
                if k > modes and fit.usable and true_fit.usable
                and fit.validation_fit < true_fit.validation_fit - 1.0)
    return chosen, worse


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", default="1:6")
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--snr", type=float, default=20.0)
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--json")
    args = parser.parse_args()
    import ctid

    low, high = (int(x) for x in args.modes.split(":"))
    rows, total, right, bad_over = [], 0, 0, 0
    for modes in range(low, high + 1):
        picks = []
        for seed in range(args.seeds):
            chosen, worse = scan_once(ctid, modes, seed, args.samples, args.snr)
            picks.append(chosen)
            bad_over += worse
        hits = sum(p == modes for p in picks)
        total += args.seeds
        right += hits
        rows.append({"modes": modes, "seeds": args.seeds, "true_order_recommended": hits,
                     "recommended": picks})
        print(f"K = {modes}: true order recommended in {hits}/{args.seeds} "
              f"(picks {picks})", flush=True)
    print(f"overall: {right}/{total} = {100 * right / total:.1f} % at {args.snr} dB; "
          f"over-parameterised usable fits worse than the true order by > 1 point: {bad_over}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"snr_db": args.snr, "samples": args.samples, "rows": rows,
                       "rate": right / total, "bad_overfits": bad_over}, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
