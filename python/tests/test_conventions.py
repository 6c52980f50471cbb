"""The printed forms of docs/conventions.md ("What ctid prints") reach Python's repr: models in
s, highest power first, integrators apart from A, numbers to 6 significant digits in %g form,
and messages that count submodels from 1 with numbers in their shortest form."""

import pytest

import ctid


def test_models_print_in_s_highest_power_first():
    integrating = ctid.Submodel(ctid.Polynomial([1.0, 0.0224, 0.000224]), ctid.Polynomial([2.0]), 1)
    mode = ctid.Submodel(ctid.Polynomial([1.0, 0.25, 0.25]), ctid.Polynomial([3.0]), 0)
    assert repr(integrating) == "(2) / (s (0.000224 s^2 + 0.0224 s + 1))"
    model = ctid.AdditiveModel([mode, integrating], 0.1)
    assert repr(model) == ("(3) / (0.25 s^2 + 0.25 s + 1) + (2) / (s (0.000224 s^2 + 0.0224 s + 1))"
                           ", input delay 0.1 s")
    assert repr(ctid.Polynomial([1.0, -1.0, 2.0])) == "Polynomial(2 s^2 - s + 1)"
    g = ctid.TransferFunction(ctid.Polynomial([1.0 / 3.0]), ctid.Polynomial([1.0, 2.0 / 3.0]), 0.05)
    assert repr(g) == "(0.333333) / (0.666667 s + 1) * exp(-0.05 s)"


def test_numbers_in_reprs_have_six_significant_digits():
    assert repr(ctid.ModalParameters(2.000486123, 0.0006483, 0.9)) == \
        "ModalParameters(natural_frequency=2.00049, damping_ratio=0.0006483, gain=0.9)"


def test_messages_count_submodels_from_one():
    with pytest.raises(ctid.InvalidArgument, match="submodel 2: denominator A must be anti-monic"):
        ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial([1.0, 0.5]), ctid.Polynomial([1.0]), 0),
                            ctid.Submodel(ctid.Polynomial([2.0, 0.5]), ctid.Polynomial([1.0]), 0)])
