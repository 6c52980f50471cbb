"""The NumPy/SciPy reference of the additive SRIVC iteration (benchmarks/reference_srivc.py,
the other side of benchmarks/ratio_table.py) is the same iteration as ctid's: from the same
start on a short noisy Section 6.1 record it takes as many iterations and lands on the same
parameters to rounding (its filters, exact ZOH/FOH from rest, are ctid's)."""

import pathlib
import sys

import numpy as np

import ctid

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "benchmarks"))
import reference_srivc  # noqa: E402

H = 0.05


def test_reference_iteration_matches_additive_srivc():
    # Section 6.1's four modes (examples/models/gonzalez_6_1_open_loop.json).
    modes = [([1.0, 0.25067682743407205, 0.5013536548681441], [3.0]),
             ([1.0, 0.029975719667069665, 0.09991906555689889], [0.4]),
             ([1.0, 0.01020353042152585, 0.030010383592723084], [0.2]),
             ([1.0, 0.009994992508753115, 0.009994992508753115], [0.05])]
    model = ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial(a), ctid.Polynomial(b))
                                for a, b in modes])
    u = ctid.multisine(period_length=1024, sample_time=H, max_frequency=3.0, periods=4,
                       seed=2).signal
    y = ctid.simulate(model, u, H) + ctid.white_noise(len(u), 0.05, 3)
    start = [([1.0, a[1] * 1.15, a[2] * 0.96], [b[0] * 1.1]) for a, b in modes]
    initial = ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial(a), ctid.Polynomial(b))
                                  for a, b in start])
    ours = ctid.additive_srivc(ctid.SampledData(H, u, y), [ctid.SubmodelOrder(2, 0)] * 4,
                               initial_model=initial, compute_covariance=False)
    theirs = reference_srivc.additive_srivc(u, y, H, start)
    assert theirs["converged"]
    assert theirs["iterations"] == ours.iterations
    expected = np.concatenate([np.r_[s["denominator_ascending"][1:], s["numerator_ascending"]]
                               for s in theirs["submodels"]])
    np.testing.assert_allclose(np.asarray(ours.parameters), expected, rtol=1e-10)
