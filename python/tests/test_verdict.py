"""The quality verdict reaches Python: every estimate has `verdict.usable`, `reasons` and
`advice`; an over-parameterised fit of a noisy two-mode record is not usable and says why,
the true structure on the same record is usable (decision 0007)."""

import ctid

H = 0.05
N = 2000
MODES = [ctid.SubmodelOrder(2, 0)] * 2
# Section 6.2, eq. (46): 3/(0.25p^2 + 0.25p + 1) + 1/(0.025p^2 + 0.01p + 1).
TRUTH = ctid.AdditiveModel.from_parameters(MODES, [0.25, 0.25, 3.0, 0.01, 0.025, 1.0])


def noisy_record():
    u = ctid.white_noise(N, 1.0, 7)
    y = ctid.simulate(TRUTH, u, H) + ctid.white_noise(N, 0.5, 8)
    return ctid.SampledData(H, u, y)


def test_over_parameterised_fit_is_not_usable_and_says_why():
    data = noisy_record()
    estimate = ctid.identify(data, ctid.ModelStructure.unfactored(8, 7)).estimate
    verdict = estimate.verdict
    assert isinstance(verdict, ctid.Verdict)
    assert verdict.usable is False
    assert len(verdict.reasons) >= 1
    assert verdict.advice
    assert verdict.summary().startswith("no usable model: ")
    assert "Try: " in verdict.summary()


def test_true_structure_is_usable_and_at_least_as_good_as_its_start():
    estimate = ctid.identify(noisy_record(), ctid.ModelStructure.modes(2)).estimate
    assert estimate.verdict.usable is True
    assert list(estimate.verdict.reasons) == []
    assert estimate.verdict.summary() == ""
    assert estimate.fit_percent >= estimate.start_fit_percent - 1.0
    assert estimate.reciprocal_condition > 1e-12


def test_delay_scan_reports_usability_per_delay():
    result = ctid.identify(noisy_record(), ctid.ModelStructure.modes(2),
                           delay_scan_samples=ctid.DelayRange(min=0, max=2))
    scan = result.delay_scan
    assert list(scan.delays) == [0, 1, 2]
    assert len(scan.usable) == 3
    assert result.estimate.input_delay_samples == 0
    assert scan.choice_clear is True
