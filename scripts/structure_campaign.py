#!/usr/bin/env python3
"""Seeded campaign of the structure scan (issue 11): how often ctid.scan_structures recommends
the true structure, and whether an over-parameterised fit ever comes back usable with a
worse held-out fit than the true structure.

Each run draws a system of K lightly damped modes (natural frequencies spread over a decade
and a half below a quarter of the Nyquist frequency, damping ratios 0.01-0.1, gains of both
signs), drives it with seeded white noise, adds white output noise at the given SNR, and
scans K-2..K+2 modes (at least 1). Variants (combinable):

  --integrator       the system also has one integrator b/p (a rigid-body mode), whose share
                     of the output is drawn (see integrator_share()); every candidate has
                     it too, unless --scan-integrators
  --scan-integrators the candidates are K-2..K+2 modes each with 0 and with 1 integrator, so the
                     scan has to find the integrator (or find that there is none)
  --delay            the system has an input delay of 1-5 samples; every fit scans the whole
                     delays 0-8 (IdentificationOptions.delay_scan_samples)
  --closed-loop      the data come from a sampled loop with a proportional controller with a
                     6 dB gain margin designed from the drawn system (white-noise reference,
                     the output noise fed back); the scan is told the controller

A run is right when the recommended fit has the true number of modes, the true number of
integrators and (--delay) the true delay in samples (docs/decisions/0016). Usage:

    PYTHONPATH=build/python /usr/bin/python3 scripts/structure_campaign.py [--modes 1:6]
        [--seeds 20] [--snr 20] [--samples 4000] [--integrator] [--scan-integrators]
        [--delay] [--closed-loop] [--any-system] [--json out.json]

Prints one line per K (with the seeds of the misses and how many drawn systems were set aside
because the data do not define their order, see record()) and the overall rate; exit status 0
always (a measurement, not a test). Runtimes: about 2 min (plain, --integrator), 5 min
(--scan-integrators), 7 min (--closed-loop) and 30 min (--delay) on one core.
"""

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass

import numpy as np

MAX_DELAY = 5  # true delays are 1..MAX_DELAY samples
SCANNED_DELAYS = (0, 8)  # whole-sample delays every fit scans with --delay


@dataclass(frozen=True)
class Variant:
    integrator: bool = False
    scan_integrators: bool = False
    delay: bool = False
    closed_loop: bool = False

    def seed_offset(self):
        """Separate seed streams per system family (the plain variant's are those of decision
        0015's campaign)."""
        return 100_000 * (1 * self.integrator + 2 * self.delay + 4 * self.closed_loop)

    def name(self):
        parts = [p for p, on in (("integrator", self.integrator),
                                 ("scan-integrators", self.scan_integrators),
                                 ("delay", self.delay), ("closed-loop", self.closed_loop)) if on]
        return "+".join(parts) or "plain"


@dataclass
class Run:
    modes: int
    seed: int
    chosen: tuple  # (modes, integrators, delay samples) of the recommended fit; None if none
    truth: tuple
    worse: int  # usable over-parameterised fits worse than the truth beyond the tolerance
    strictly_worse: int  # the same with no tolerance at all
    redrawn: int  # systems set aside before this one (record())
    seconds: float

    @property
    def right(self):
        return self.chosen == self.truth


def system(ctid, modes, rng, h, integrator=False, delay=0):
    """K modes with natural frequencies in [top / 10^1.5, top], top a quarter of the Nyquist
    frequency, at least a factor 1.3 apart (so that K is well defined). With `integrator`, a
    first submodel b/p of either sign, scaled by integrator_gain() once the input is known."""
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
    if integrator:
        b = rng.choice([-1, 1]) * 10 ** rng.uniform(-0.5, 0.5)
        submodels.insert(0, ctid.Submodel(a=ctid.Polynomial([1.0]), b=ctid.Polynomial([b]),
                                          integrators=1))
    return ctid.AdditiveModel(submodels, delay * h), freqs


def integrator_share(ctid, model, excitation, h):
    """The model with its integrator's gain b rescaled so that the integrator's part of the
    output has b_drawn times the root mean square of the modes' part (b_drawn = +-10^U(-0.5,
    0.5), from system()): the integrator carries a share of the output drawn like a mode's
    gain. With the gain drawn on its own scale the random walk of an integrator driven by white
    noise is ten to a hundred times the modes, the SNR (on the whole output) puts the modes
    under the noise and the number of modes is no longer defined by the data
    (docs/decisions/0016)."""
    submodels = list(model.submodels)
    parts = ctid.simulate_submodels(model, excitation, h)
    integrator = parts[:, 0]
    modes = parts[:, 1:].sum(axis=1)
    drawn = submodels[0].b.coefficients[0]
    scale = math.sqrt(np.mean(modes ** 2) / np.mean(integrator ** 2))
    submodels[0] = ctid.Submodel(a=submodels[0].a, b=ctid.Polynomial([drawn * scale]),
                                 integrators=1)
    return ctid.AdditiveModel(submodels, model.input_delay)


def proportional_controller(ctid, model, h, margin_db=6.0):
    """u_k = k (r_k - y_k) with the gain margin `margin_db` on the drawn system's sampled
    (ZOH) response: k_max is the smallest k > 0 for which 1 + k G(e^{jwh}) = 0 somewhere on the
    unit circle (where the response crosses the negative real axis), k = k_max / 10^(margin/20).
    Checked against the closed-loop poles."""
    omegas = np.linspace(1e-6, math.pi / h, 40_001)
    g = ctid.sampled_frequency_response(model, omegas, h)
    im, re = g.imag, g.real
    crossings = np.nonzero(np.sign(im[1:]) != np.sign(im[:-1]))[0]
    k_max = math.inf
    for i in crossings:
        t = im[i] / (im[i] - im[i + 1])
        r = re[i] + t * (re[i + 1] - re[i])
        if r < 0:
            k_max = min(k_max, -1 / r)
    for r in (re[0], re[-1]):  # the ends of the grid lie on the real axis
        if r < 0:
            k_max = min(k_max, -1 / r)
    if not math.isfinite(k_max):  # never crosses: no upper limit; a gain of 1/|G| at its peak
        k_max = 10 ** (margin_db / 20) / np.max(np.abs(g))
    k = k_max / 10 ** (margin_db / 20)
    controller = ctid.DiscreteTransferFunction(ctid.Polynomial([k]), ctid.Polynomial([1.0]), h)
    poles = ctid.closed_loop_poles(ctid.zoh_equivalent(model, h), controller)
    assert np.max(np.abs(poles)) < 1, f"controller k = {k} does not stabilise the loop"
    return controller


def candidates(ctid, modes, variant):
    """(modes, integrators) of each candidate and its ModelStructure."""
    counts = range(max(1, modes - 2), modes + 3)
    integrators = (0, 1) if variant.scan_integrators else (int(variant.integrator),)
    keys = [(k, i) for i in integrators for k in counts]
    structures = []
    for k, i in keys:
        orders = [ctid.SubmodelOrder(2, 0, 0)] * k
        if i:
            orders = [ctid.SubmodelOrder(0, 0, 1)] + orders
        structures.append(ctid.ModelStructure.additive(orders))
    return keys, structures


def resolution(samples, validation_fraction=0.3):
    """The scan's default tolerance, 2 sqrt(2 / N_v) (decision 0015): the relative rise of the
    held-out mean squared error that the rule takes for noise."""
    return 2 * math.sqrt(2 / math.floor(validation_fraction * samples))


def shares(ctid, model, plant_input, sigma, h, validation_fraction=0.3):
    """Mean square of each submodel's output on the held-out end of the record, over the noise
    variance sigma^2."""
    parts = ctid.simulate_submodels(model, plant_input, h)
    held_out = math.floor(validation_fraction * len(plant_input))
    return np.mean(parts[-held_out:, :] ** 2, axis=0) / sigma ** 2


def record(ctid, modes, seed, samples, snr, h, variant, any_system=False):
    """The seeded record of one run: (data, true model, delay in samples, controller or None,
    systems drawn before this one and set aside). Unless `any_system`, a drawn system is set
    aside and another drawn from the same stream when some submodel's output on the held-out
    part has a mean square below twice the scan's resolution times the noise variance: the
    data then do not define its order under the rule (docs/decisions/0016)."""
    offset = variant.seed_offset()
    rng = np.random.default_rng(offset + 1000 * modes + seed)
    excitation = ctid.white_noise(samples, 1.0, offset + 10_000 + 100 * modes + seed)
    noise = ctid.white_noise(samples, 1.0, offset + 20_000 + 100 * modes + seed)
    for redrawn in range(1000):
        delay = int(rng.integers(1, MAX_DELAY + 1)) if variant.delay else 0
        model, _ = system(ctid, modes, rng, h, variant.integrator, delay)
        if variant.integrator:
            model = integrator_share(ctid, model, excitation, h)
        if variant.closed_loop:
            controller = proportional_controller(ctid, model, h)
            free = ctid.simulate_closed_loop(model, controller, excitation)
            y0, plant_input = free.output, free.input
        else:
            controller = None
            y0, plant_input = ctid.simulate(model, excitation, h), excitation
        sigma = math.sqrt(np.mean(y0 ** 2)) * 10 ** (-snr / 20)
        if any_system or min(shares(ctid, model, plant_input, sigma, h)) >= \
                2 * resolution(samples):
            break
    else:
        raise RuntimeError(f"no system of {modes} modes with every submodel above the noise")
    if variant.closed_loop:
        loop = ctid.simulate_closed_loop(model, controller, excitation, sigma * noise)
        data = ctid.SampledData(h, loop.input, loop.output, excitation)
    else:
        data = ctid.SampledData(h, excitation, y0 + sigma * noise)
    return data, model, delay, controller, redrawn


def scan_once(ctid, modes, seed, samples=4000, snr=20.0, h=0.01, variant=Variant(),
              any_system=False):
    """One seeded run of a variant, as a Run."""
    start = time.perf_counter()
    data, _, delay, controller, redrawn = record(ctid, modes, seed, samples, snr, h, variant,
                                                 any_system)
    keys, structures = candidates(ctid, modes, variant)
    options = ctid.StructureScanOptions()
    if controller is not None:
        options.identification.controller = controller
    if variant.delay:
        options.identification.delay_scan_samples = ctid.DelayRange(min=SCANNED_DELAYS[0],
                                                            max=SCANNED_DELAYS[1])
    scan = ctid.scan_structures(data, structures, options)
    truth = (modes, int(variant.integrator), delay)

    def key_of(i):
        d = round(scan.fits[i].transfer_function.input_delay / h)
        return keys[i] + (d,)

    chosen = key_of(scan.recommended) if scan.recommended >= 0 else None
    true_index = keys.index(truth[:2])
    true_fit = scan.fits[true_index]
    # "Over-parameterised": more modes, or more integrators, than the truth, none fewer.
    over = [i for i, (k, l) in enumerate(keys)
            if k >= truth[0] and l >= truth[1] and (k, l) != truth[:2]]
    tolerance = resolution(samples)
    worse = strictly = 0
    for i in over:
        fit = scan.fits[i]
        if fit.usable and true_fit.usable:
            strictly += fit.validation_error > true_fit.validation_error
            worse += fit.validation_error > (1 + tolerance) * true_fit.validation_error
    return Run(modes, seed, chosen, truth, worse, strictly, redrawn,
               time.perf_counter() - start)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modes", default="1:6")
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--snr", type=float, default=20.0)
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--integrator", action="store_true")
    parser.add_argument("--scan-integrators", action="store_true")
    parser.add_argument("--delay", action="store_true")
    parser.add_argument("--closed-loop", action="store_true")
    parser.add_argument("--any-system", action="store_true",
                        help="keep every drawn system, also those whose order the data do not "
                             "define (see record())")
    parser.add_argument("--json")
    args = parser.parse_args()
    import ctid

    variant = Variant(args.integrator, args.scan_integrators, args.delay, args.closed_loop)
    low, high = (int(x) for x in args.modes.split(":"))
    rows, total, right, bad_over, strictly_over = [], 0, 0, 0, 0
    started = time.perf_counter()
    for modes in range(low, high + 1):
        runs = [scan_once(ctid, modes, seed, args.samples, args.snr, variant=variant,
                          any_system=args.any_system)
                for seed in range(args.first_seed, args.first_seed + args.seeds)]
        hits = sum(r.right for r in runs)
        misses = {r.seed: r.chosen for r in runs if not r.right}
        total += len(runs)
        right += hits
        bad_over += sum(r.worse for r in runs)
        strictly_over += sum(r.strictly_worse for r in runs)
        seconds = sum(r.seconds for r in runs)
        redrawn = sum(r.redrawn for r in runs)
        rows.append({"modes": modes, "seeds": len(runs), "true_structure_recommended": hits,
                     "systems_set_aside": redrawn,
                     "truths": {r.seed: r.truth for r in runs},
                     "misses": misses, "seconds": seconds,
                     "worse_overfits": {r.seed: r.worse for r in runs if r.worse}})
        print(f"K = {modes}: true structure recommended in {hits}/{len(runs)}"
              f" ({seconds / len(runs):.1f} s per scan, {redrawn} systems set aside);"
              f" misses (seed: chosen (modes, integrators, delay) vs true): "
              f"{ {r.seed: (r.chosen, r.truth) for r in runs if not r.right} }; seeds with usable "
              f"over-fits worse by more than the tolerance: "
              f"{ {r.seed: r.worse for r in runs if r.worse} }", flush=True)
    print(f"{variant.name()}: {right}/{total} = {100 * right / total:.1f} % at {args.snr} dB "
          f"in {time.perf_counter() - started:.0f} s; usable over-parameterised fits with a "
          f"held-out error above the true structure's by more than the tolerance: {bad_over} "
          f"(at all: {strictly_over})")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"variant": variant.name(), "snr_db": args.snr, "samples": args.samples,
                       "rows": rows, "rate": right / total, "bad_overfits": bad_over,
                       "strictly_worse_overfits": strictly_over}, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
