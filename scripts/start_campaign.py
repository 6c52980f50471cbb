#!/usr/bin/env python3
"""Seeded campaign of the automatic start (issue 11): how often the additive estimator started
from the data alone reaches the stationary point it reaches from the true model.

Each run draws K lightly damped modes as scripts/structure_campaign.py does, but with damping
ratios log-uniform in [--zeta-min, 0.05], drives them with seeded white noise, adds white
output noise at --snr, and fits K modes twice: with the automatic start (LSSVF grid and FRF
peaks, initialization.h) and from the true model. Same stationary point: parameters equal to
--match (relative).

With --closed-loop GM the record comes from a loop r -> k -> ZOH -> G -> y (+ noise), k the
proportional gain that leaves a gain margin of GM dB (k_crit / 10^(GM/20), k_crit the first
unstable gain of the sign with the wider stable range, on the closed-loop poles of the ZOH truth), r seeded white noise, the output noise at
--snr relative to the noise-free closed-loop output, and both fits are additive CLSRIVC with the
controller known. Usage:

    PYTHONPATH=build/python /usr/bin/python3 scripts/start_campaign.py [--modes 1:6]
        [--seeds 10] [--samples 2000,10000] [--zeta-min 1e-3] [--snr 30] [--match 1e-6]
        [--closed-loop GM]

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


def proportional_controller(ctid, truth, h, margin_db):
    """The proportional gain k that leaves margin_db of gain margin on the ZOH truth: of the
    two signs, the one with the wider stable range 0 < |k| < k_crit (the first unstable gain
    on a geometric grid from 1e-6, refined by bisection); a mode of the wrong sign can make
    the other one unstable at any gain."""
    plant = ctid.zoh_equivalent(truth, h)

    def stable(k):
        c = ctid.DiscreteTransferFunction(ctid.Polynomial([k]), ctid.Polynomial([1.0]), h)
        return np.max(np.abs(ctid.closed_loop_poles(plant, c))) < 1.0

    best = 0.0
    for sign in (1.0, -1.0):
        grid = sign * np.logspace(-6, 6, 97)
        unstable = [k for k in grid if not stable(k)]
        if not unstable:
            critical = grid[-1]
        elif unstable[0] == grid[0]:
            continue
        else:
            high = unstable[0]
            low = grid[list(grid).index(high) - 1]
            for _ in range(60):
                mid = 0.5 * (low + high)
                low, high = (mid, high) if stable(mid) else (low, mid)
            critical = low
        if abs(critical) > abs(best):
            best = critical
    k = best * 10 ** (-margin_db / 20)
    return ctid.DiscreteTransferFunction(ctid.Polynomial([k]), ctid.Polynomial([1.0]), h)


def record(ctid, truth, modes, seed, n, snr, h, closed_loop):
    """The seeded record, and the options that fit it (the controller in closed loop)."""
    excitation = ctid.white_noise(n, 1.0, 30_000 + 100 * modes + seed)
    if closed_loop is None:
        y0 = ctid.simulate(truth, excitation, h)
        sigma = math.sqrt(np.mean(y0 ** 2)) * 10 ** (-snr / 20)
        return ctid.SampledData(h, excitation, y0 + ctid.white_noise(n, sigma, 40_000 + seed)), {}
    controller = proportional_controller(ctid, truth, h, closed_loop)
    y0 = ctid.simulate_closed_loop(truth, controller, excitation).output
    sigma = math.sqrt(np.mean(y0 ** 2)) * 10 ** (-snr / 20)
    loop = ctid.simulate_closed_loop(truth, controller, excitation,
                                     ctid.white_noise(n, sigma, 40_000 + seed))
    return (ctid.SampledData(h, loop.input, loop.output, excitation),
            {"controller": controller})


def same_point(ctid, modes, seed, n, zeta_min=1e-3, snr=30.0, match=1e-6, h=0.01,
               closed_loop=None):
    """One seeded run: whether K modes fitted from the automatic start and from the true model
    end at the same parameters (to `match`, relative; submodels sorted by frequency). None when
    the fit from the true model is itself not usable (in closed loop, e.g., a model the
    controller does not stabilise): such a run has no point worth reaching and is set aside
    (decision 0028)."""
    rng = np.random.default_rng(7000 * modes + seed)
    truth = draw(ctid, modes, rng, h, zeta_min)
    data, loop = record(ctid, truth, modes, seed, n, snr, h, closed_loop)
    structure = ctid.ModelStructure.modes(modes)
    auto = ctid.identify(data, structure,
                         refined_iv=ctid.RefinedIvOptions(compute_covariance=False), **loop)
    true = ctid.identify(data, structure, refined_iv=ctid.RefinedIvOptions(
        compute_covariance=False, initial_model=truth), **loop)

    def key(e):
        return np.array(sorted((s.a.coefficients[2], s.a.coefficients[1], s.b.coefficients[0])
                               for s in e.estimate.model.submodels))

    if not true.estimate.verdict.usable:
        return None
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
    parser.add_argument("--closed-loop", type=float, metavar="GM",
                        help="closed loop under a proportional controller with GM dB of margin")
    args = parser.parse_args()
    import ctid

    low, high = (int(x) for x in args.modes.split(":"))
    total, right, aside = 0, 0, 0
    for n in (int(x) for x in args.samples.split(",")):
        for modes in range(low, high + 1):
            ends = {seed: same_point(ctid, modes, seed, n, args.zeta_min, args.snr, args.match,
                                     closed_loop=args.closed_loop)
                    for seed in range(args.seeds)}
            misses = [seed for seed, end in ends.items() if end is False]
            unusable = [seed for seed, end in ends.items() if end is None]
            hits = args.seeds - len(misses) - len(unusable)
            total += args.seeds - len(unusable)
            right += hits
            aside += len(unusable)
            print(f"N = {n}, K = {modes}: {hits}/{args.seeds - len(unusable)} reach the true "
                  f"start's point"
                  f"{' (misses: seeds ' + str(misses) + ')' if misses else ''}"
                  f"{' (set aside, the true start ends unusable: seeds ' + str(unusable) + ')' if unusable else ''}",
                  flush=True)
    print(f"overall: {right}/{total} = {100 * right / total:.1f} %; {aside} runs set aside")
    return 0


if __name__ == "__main__":
    sys.exit(main())
