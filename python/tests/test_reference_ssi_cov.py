"""The NumPy/SciPy reference of SSI-cov (benchmarks/reference_ssi_cov.py, the other side of
benchmarks/ssi_cov_benchmark.py) is the same estimator as ctid's: on a short seeded record of
the benchmark's 8-mass chain it finds, order by order, as many poles as ctid.oma and the same
frequencies and damping ratios to rounding (one SVD each: LAPACK's and Eigen's)."""

import pathlib
import sys

import numpy as np

import ctid

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "benchmarks"))
import reference_ssi_cov  # noqa: E402
import ssi_cov_benchmark  # noqa: E402


def test_reference_poles_match_oma_order_by_order():
    y, true_hz, _ = ssi_cov_benchmark.chain_record(20000, seed=3)
    h, p, order = ssi_cov_benchmark.H, 40, 32
    ours = ctid.oma(y, h, max_order=order, block_rows=p, uncertainty_blocks=0)
    theirs = dict(reference_ssi_cov.ssi_cov(y, h, p, order))
    assert len(ours.modes) == len(true_hz)
    assert sorted(theirs) == list(range(2, order + 1, 2))
    for n, poles in theirs.items():
        mine = [s for s in ours.stabilisation if s.order == n]
        assert len(mine) == len(poles), n
        for s, (f, zeta, _) in zip(mine, poles):
            assert abs(s.frequency_hz - f) <= 1e-9 * f, (n, s.frequency_hz, f)
            assert abs(s.damping_ratio - zeta) <= 1e-6 * zeta, (n, s.damping_ratio, zeta)
