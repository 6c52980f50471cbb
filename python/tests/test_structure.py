"""Choosing the structure and the start from Python: scan_structures recommends the true
number of modes of a noise-free record, the automatic start is an option of identify, and the
peaks of a measured Frf are searched on its excited lines with their coherence."""

import math

import numpy as np
import pytest

import ctid

H = 0.05
N = 1500
MODES = [ctid.SubmodelOrder(2, 0)] * 2
# Section 6.2, eq. (46): 3/(0.25p^2 + 0.25p + 1) + 1/(0.025p^2 + 0.01p + 1).
TRUTH = ctid.AdditiveModel.from_parameters(MODES, [0.25, 0.25, 3.0, 0.01, 0.025, 1.0])


def _record(seed):
    u = np.random.default_rng(seed).standard_normal(N)
    return ctid.SampledData(H, u, ctid.simulate(TRUTH, u, H))


def test_scan_recommends_two_modes_on_a_noise_free_record():
    scan = ctid.scan_structures(_record(1), [ctid.ModelStructure.modes(k) for k in (1, 2, 3)],
                                validation_fraction=0.25)
    assert scan.recommended == 1, scan.rule
    assert scan.validation_samples == N // 4
    best = scan.fits[1]
    assert best.usable and best.validation_fit > 99.999
    assert scan.fits[0].validation_fit < best.validation_fit - 1.0
    assert all(p.fit in (0, 1, 2) for p in scan.stabilisation)


def test_scan_result_reads_back_with_every_fit(tmp_path):
    # A structure_scan_result document (ctid structure -o, write_result) reads back as the
    # scan, the estimates' transfer functions included, bit for bit.
    scan = ctid.scan_structures(_record(4), [ctid.ModelStructure.modes(k) for k in (1, 2)])
    ctid.write_result(tmp_path / "scan.json", scan)
    back = ctid.read_result(tmp_path / "scan.json")
    assert isinstance(back, ctid.StructureScanResult)
    assert ctid.result_to_json(back) == ctid.result_to_json(scan)
    assert back.recommended == scan.recommended == 1
    g, h = back.fits[1].transfer_function, scan.fits[1].transfer_function
    np.testing.assert_array_equal(g.denominator.coefficients, h.denominator.coefficients)
    np.testing.assert_array_equal(g.numerator.coefficients, h.numerator.coefficients)
    assert [f.structure.orders[0].n for f in back.fits] == [2, 2]
    assert "structure_scan_result" in ctid.result_document_types()


def test_start_methods_reach_the_same_noise_free_model_or_say_why_not():
    data = _record(2)
    fits = [ctid.identify(data, ctid.ModelStructure.modes(2),
                          refined_iv=ctid.RefinedIvOptions(start=method))
            for method in (ctid.StartMethod.auto, ctid.StartMethod.lssvf)]
    for r in fits:
        assert r.estimate.termination == ctid.Termination.converged
        np.testing.assert_allclose(r.estimate.parameters, fits[0].estimate.parameters,
                                   rtol=1e-7)
    # The well-damped first mode (zeta = 0.25) is no peak on a 128-sample Welch grid: the FRF
    # start alone says so instead of guessing.
    with pytest.raises(ctid.InvalidArgument, match="fewer resonance peaks than the 2 pole"):
        ctid.identify(data, ctid.ModelStructure.modes(2),
                      refined_iv=ctid.RefinedIvOptions(start=ctid.StartMethod.frf))


def test_peaks_of_a_measured_frf_carry_their_coherence():
    data = _record(3)
    frf = ctid.welch_frf(data, segment_length=256)
    assert len(frf.input_level) == len(frf.frequencies)
    assert max(frf.input_level) == 1.0
    # The lightly damped mode, w_n = 6.32 rad/s, is the one peak (the other, zeta = 0.25, is
    # no peak at this resolution); its coherence is reported, below 1 from window leakage.
    (peak,) = ctid.resonance_peaks(frf, max_peaks=2)
    assert abs(peak.frequency - math.sqrt(40.0)) < 0.3
    assert 0.5 < peak.coherence < 1.0
    assert not math.isnan(peak.input_level)
    assert ctid.resonance_peaks(frf, min_coherence=0.99) == []
    excited = ctid.excited_lines(frf, 0.5)
    assert len(excited.lines) <= len(frf.lines)


def _campaign():
    import importlib.util
    import pathlib

    spec = importlib.util.spec_from_file_location(
        "structure_campaign", pathlib.Path(__file__).resolve().parents[2] /
        "scripts" / "structure_campaign.py")
    campaign = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(campaign)
    return campaign


def _allowed_misses(runs, rate=0.95, alpha=0.05):
    """The most misses in `runs` seeded runs that a scan right in `rate` of runs would reach
    with probability at least `alpha`: more misses than this are evidence (at level alpha)
    that the rate is below `rate`. 24 runs: 3; 12 runs: 2; 8 runs: 2; 6 runs: 1."""
    def tail(m):  # P(X > m), X ~ Binomial(runs, 1 - rate)
        return sum(math.comb(runs, k) * (1 - rate) ** k * rate ** (runs - k)
                   for k in range(m + 1, runs + 1))
    return next(m for m in range(runs + 1) if tail(m) < alpha)


def _check_campaign(variant, modes, seeds):
    # Issue 11 (decision 0016): at 20 dB the scan recommends the true structure in >= 95 % of
    # seeded runs of systems whose order the data define (scripts/structure_campaign.py; the
    # full campaign, 20 seeds per K, is in the decision), and no usable over-parameterised fit
    # scores a held-out error above the true structure's by more than the scan's tolerance.
    campaign = _campaign()
    runs = [campaign.scan_once(ctid, k, seed, variant=variant) for k in modes for seed in seeds]
    misses = {(r.modes, r.seed): r.chosen for r in runs if not r.right}
    assert sum(r.worse for r in runs) == 0
    assert len(misses) <= _allowed_misses(len(runs)), misses
    return runs


def test_allowed_misses_is_the_binomial_bound():
    assert [_allowed_misses(n) for n in (6, 8, 12, 24, 120)] == [1, 2, 2, 3, 10]


def test_seeded_campaign_recommends_the_true_number_of_modes():
    runs = _check_campaign(_campaign().Variant(), range(1, 7), range(4))
    assert sum(r.right for r in runs) >= math.ceil(0.95 * len(runs))


def test_seeded_campaign_finds_the_integrator_and_the_modes():
    # Candidates with and without an integrator, K-2..K+2 modes each.
    _check_campaign(_campaign().Variant(integrator=True, scan_integrators=True), range(1, 7),
                    range(2))


def _contains(outer, inner):
    """Unfactored structures: more poles and zeros contain fewer (the extra leading
    coefficients at zero)."""
    (o,), (i,) = outer.orders, inner.orders
    return o.n >= i.n and o.m >= i.m and o.integrators == i.integrators


def test_no_usable_fit_is_worse_than_a_structure_it_contains():
    # Decision 0016's two nested rules as a property, on the measured PT326 heater (first
    # order with a 5-sample delay) scanned over 1-4 poles as in examples/pt326.py: no usable
    # fit matches the estimation data, or predicts the held-out data, worse than a usable fit
    # of a structure it contains by more than the noise tolerance 2 sqrt(2 / N_v). Here the
    # third- and fourth-order fits predict the held-out 30 % worse than the first order does:
    # over-fitted, not usable, and the reason says so. (An earlier form of this test replayed
    # a delay-campaign fit that stopped short of its optimum; the per-block stopping rule and
    # the rescaled instrument cascade of issue 16 let that fit converge.)
    import os
    path = os.path.join(os.path.dirname(__file__), "..", "..", "data", "contsid_aerothermal_pt326",
                        "pt326_est.csv")
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    with open(path) as f:
        names = f.readline().strip().split(",")
    h = float(np.round(np.mean(np.diff(table[:, 0])), 9))
    data = ctid.SampledData(h, table[:, names.index("u_heater_voltage")],
                            table[:, names.index("y_outlet_temperature")])
    options = ctid.StructureScanOptions()
    options.identification.refined_iv.input_delay_samples = 5
    candidates = [ctid.ModelStructure.unfactored(n, n - 1) for n in range(1, 5)]
    scan = ctid.scan_structures(data, candidates, options)
    tolerance = 2 * math.sqrt(2 / scan.validation_samples)
    for i, fit in enumerate(scan.fits):
        if not fit.usable:
            continue
        for j, other in enumerate(scan.fits):
            if j != i and other.usable and _contains(fit.structure, other.structure):
                assert fit.validation_error <= (1 + tolerance) * other.validation_error, (i, j)
    assert scan.fits[0].usable and scan.recommended == 0
    for fit in scan.fits[2:]:
        assert not fit.usable
        assert "over-fitted" in fit.reasons[-1], fit.reasons
        assert fit.validation_error > (1 + tolerance) * scan.fits[0].validation_error


def test_seeded_campaign_finds_the_modes_and_the_delay():
    # Every candidate scans the whole delays 0-8; right means the true delay as well.
    _check_campaign(_campaign().Variant(delay=True), range(1, 5), range(2))


def test_seeded_campaign_finds_the_modes_in_closed_loop():
    # A proportional controller with a 6 dB gain margin, known to the scan.
    _check_campaign(_campaign().Variant(closed_loop=True), range(1, 7), range(2))
