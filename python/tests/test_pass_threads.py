"""Threads inside one fit (decision 0068): ``threads=`` of the refined IV options changes how
a pass is split over the submodels, never the estimate. From Python as from C++: the same
parameters and covariance to the bit with one thread and with several, and ``threads`` is an
option like the others (a negative count is refused by name)."""

import numpy as np
import pytest

import ctid

H = 0.05


def _record():
    modes = [([1.0, 0.25, 0.5], [3.0]), ([1.0, 0.03, 0.1], [0.4]), ([1.0, 0.01, 0.03], [0.2])]
    model = ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial(a), ctid.Polynomial(b))
                                for a, b in modes])
    u = ctid.white_noise(9000, 1.0, 5)
    y = ctid.simulate(model, u, H) + ctid.white_noise(len(u), 0.05, 6)
    start = ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial([1.0, a[1] * 1.05, a[2]]),
                                              ctid.Polynomial(b)) for a, b in modes])
    return ctid.SampledData(H, u, y), start


def test_one_thread_and_three_give_the_same_bits():
    data, start = _record()
    fits = [ctid.additive_srivc(data, [ctid.SubmodelOrder(2, 0)] * 3, initial_model=start,
                                threads=threads) for threads in (1, 3)]
    assert fits[0].iterations > 1
    assert np.array_equal(np.asarray(fits[0].parameters), np.asarray(fits[1].parameters))
    assert np.array_equal(np.asarray(fits[0].covariance), np.asarray(fits[1].covariance))


def test_a_negative_thread_count_is_refused_by_name():
    data, start = _record()
    with pytest.raises(ValueError, match="threads"):
        ctid.additive_srivc(data, [ctid.SubmodelOrder(2, 0)] * 3, initial_model=start,
                            threads=-1)
