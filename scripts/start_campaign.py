#!/usr/bin/env python3
"""Seeded campaign of the automatic start (issue 11): how often the additive estimator started
from the data alone reaches the stationary point it reaches from the true model.

Each run draws K lightly damped modes as scripts/structure_campaign.py does, but with damping
ratios log-uniform in [--zeta-min, 0.05], drives them with seeded white noise, adds white
output noise at --snr, and fits K modes twice: with the automatic start (LSSVF grid and FRF
peaks, initialization.h) and from the true model. Same stationary point: parameters equal to
--match (relative). Usage:

    PYTHONPATH=build/python /usr/bin/python3 scripts/start_campaign.py [--modes 1:6]
        [--seeds 10] [--samples 2000,10000] [--zeta-min 1e-3] [--snr 30] [--match 1e-6]

Prints one line per (K, N) and the overall rate; exit status 0 always (a measurement).
"""

import argparse
import math
import sys

import numpy as np

sys.path.insert(0, __import__("os").path.dirname(__import__("os").path.abspath(__file__)))
import structure_campaign  # noqa: E402


def draw(ctid, modes, rng, h, zeta_min):
    model, _ = structure_campaign.system(ctid, modes, rng, h)
    submodels = []
    for s in model.submodels:
        a = s.a.coefficients
        w = 1 / math.sqrt(a[2])
        zeta = 10 ** rng.uniform(math.log10(zeta_min), math.log10(0.05))
        submodels.append(ctid.Submodel(a=ctid.Polynomial([1.0, 2 * zeta / w, 1 / w ** 2]),
                                       b=s.b, integrators=0))
    return ctid.AdditiveModel(submodels)


def same_point(ctid, modes, seed, n, zeta_min=1e-3, snr=30.0, match=1e-6, h=0.01):
    """One seeded run: whether K modes fitted from the automatic start and from the true model
    end at the same parameters (to `match`, relative; submodels sorted by frequency)."""
    rng = np.random.default_rng(7000 * modes + seed)
    truth = draw(ctid, modes, rng, h, zeta_min)
    u = ctid.white_noise(n, 1.0, 30_000 + 100 * modes + seed)
    y0 = ctid.simulate(truth, u, h)
    sigma = math.sqrt(np.mean(y0 ** 2)) * 10 ** (-snr / 20)
    data = ctid.SampledData(h, u, y0 + ctid.white_noise(n, sigma, 40_000 + seed))
    structure = ctid.ModelStructure.modes(modes)
    auto = ctid.identify(data, structure,
                         refined_iv=ctid.RefinedIvOptions(compute_covariance=False))
    true = ctid.identify(data, structure, refined_iv=ctid.RefinedIvOptions(
        compute_covariance=False, initial_model=truth))

    def key(e):
        return np.array(sorted((s.a.coefficients[2], s.a.coefficients[1], s.b.coefficients[0])
                               for s in e.estimate.model.submodels))

    a, t = key(auto), key(true)
    return bool(np.max(np.abs(a - t) / np.maximum(np.abs(t), 1e-12)) <= match)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", default="1:6")
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--samples", default="2000,10000")
    parser.add_argument("--zeta-min", type=float, default=1e-3)
    parser.add_argument("--snr", type=float, default=30.0)
    parser.add_argument("--match", type=float, default=1e-6)
    args = parser.parse_args()
    import ctid

    low, high = (int(x) for x in args.modes.split(":"))
    total, right = 0, 0
    for n in (int(x) for x in args.samples.split(",")):
        for modes in range(low, high + 1):
            misses = [seed for seed in range(args.seeds)
                      if not same_point(ctid, modes, seed, n, args.zeta_min, args.snr, args.match)]
            hits = args.seeds - len(misses)
            total += args.seeds
            right += hits
            print(f"N = {n}, K = {modes}: {hits}/{args.seeds} reach the true start's point"
                  f"{' (misses: seeds ' + str(misses) + ')' if misses else ''}", flush=True)
    print(f"overall: {right}/{total} = {100 * right / total:.1f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
