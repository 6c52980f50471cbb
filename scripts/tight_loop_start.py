#!/usr/bin/env python3
"""The hard closed-loop start case of decision 0011, measured: the Section 6.2 plant under
u = 0.33 (r - y) (0.9 dB of gain margin), output noise (q + 0.5)/(q - 0.85) e with var e = 0.04,
N = 4000, white reference; the records of tests/refined_iv/closed_loop_start_test.cc.

For each seed, the additive CLSRIVC and the unfactored CLSRIVC (4 poles, 2 zeros) are fitted
from the data alone (the automatic start) and from the true system, and the additive one also
from the partial-fraction split of the unfactored fit from the data. Each end is classed
against the truth start's end: `same` (converged, the same transfer function within --match
relative, whatever the order of the submodels), `lower`
or `higher` output error (mean squared y - G u). A `lower` end is a stationary point the truth
start does not reach and that fits the record better: the record has several, and the truth's
is not singled out by the estimator's own criterion. Usage:

    PYTHONPATH=build/python /usr/bin/python3 scripts/tight_loop_start.py [--seeds 1:41]
        [--match 1e-6]

Prints one line per seed and a tally per estimator; exit status 0 always (a measurement).
"""

import argparse

import numpy as np

H = 0.05
SAMPLES = 4000


def loop_record(ctid, truth, controller, seed):
    noise_filter = ctid.DiscreteTransferFunction(ctid.Polynomial([0.5, 1.0]),
                                                 ctid.Polynomial([-0.85, 1.0]), H)
    r = ctid.white_noise(SAMPLES, 1.0, seed)
    v = ctid.colored_noise(noise_filter, SAMPLES, 0.04, 1000 + seed)
    loop = ctid.simulate_closed_loop(truth, controller, r, v)  # as the C++ test simulates it
    return ctid.SampledData(H, loop.input, loop.output, r)


def options(ctid, start=None):
    o = ctid.RefinedIvOptions()
    o.compute_covariance = False
    if start is not None:
        o.initial_model = start
    return o


def coefficients(fit):
    """The transfer function's coefficients: the same model, whatever its submodels' order."""
    g = fit.transfer_function
    return np.concatenate([g.numerator.coefficients, g.denominator.coefficients])


def classify(fit, reference, match):
    if (fit.converged() and reference.converged() and
            np.linalg.norm(coefficients(fit) - coefficients(reference)) <=
            match * np.linalg.norm(coefficients(reference))):
        return "same"
    return "lower" if fit.mean_squared_error < reference.mean_squared_error else "higher"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="1:41", help="A:B, seeds A..B-1")
    parser.add_argument("--match", type=float, default=1e-6)
    args = parser.parse_args()
    import ctid

    truth = ctid.AdditiveModel([
        ctid.Submodel(ctid.Polynomial([1.0, 0.25, 0.25]), ctid.Polynomial([3.0]), 0),
        ctid.Submodel(ctid.Polynomial([1.0, 0.01, 0.025]), ctid.Polynomial([1.0]), 0)])
    controller = ctid.DiscreteTransferFunction(ctid.Polynomial([0.33]), ctid.Polynomial([1.0]), H)
    orders = truth.orders()
    g = truth.to_transfer_function()
    unfactored_truth = ctid.AdditiveModel([ctid.Submodel(g.denominator, g.numerator, 0)])
    unfactored_order = ctid.SubmodelOrder(4, 2, 0)
    first, last = (int(x) for x in args.seeds.split(":"))
    tally = {}
    for seed in range(first, last):
        data = loop_record(ctid, truth, controller, seed)
        additive_truth = ctid.additive_clsrivc(data, controller, orders, options(ctid, truth))
        additive = ctid.additive_clsrivc(data, controller, orders, options(ctid))
        unfactored_from_truth = ctid.clsrivc(data, controller, unfactored_order,
                                             options(ctid, unfactored_truth))
        unfactored = ctid.clsrivc(data, controller, unfactored_order, options(ctid))
        try:
            split = ctid.AdditiveModel.from_transfer_function(unfactored.transfer_function)
            via = ctid.additive_clsrivc(data, controller, orders, options(ctid, split))
        except (ValueError, RuntimeError):
            via = None
        ends = {"additive": classify(additive, additive_truth, args.match),
                "unfactored": classify(unfactored, unfactored_from_truth, args.match),
                "additive via split": classify(via, additive_truth, args.match) if via else "failed"}
        for name, end in ends.items():
            tally.setdefault(name, {}).setdefault(end, []).append(seed)
        print(f"seed {seed}: " + ", ".join(f"{k} {v}" for k, v in ends.items()), flush=True)
    for name, ends in tally.items():
        counts = ", ".join(f"{k} {len(v)}" for k, v in sorted(ends.items()))
        others = "; ".join(f"{k}: {v}" for k, v in sorted(ends.items()) if k != "same")
        print(f"{name}: {counts} of {last - first}" + (f" ({others})" if others else ""))


if __name__ == "__main__":
    main()
