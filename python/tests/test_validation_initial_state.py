"""validate_model with ValidationOptions: the estimated initial state, the scored window and
the comparison figure of several models (issue 12)."""

import numpy as np
import pytest

import ctid

H = 0.05

# A lightly damped mode (omega_n = 2 rad/s, zeta = 0.05) beside a first-order one.
MODEL = ctid.AdditiveModel([
    ctid.Submodel(ctid.Polynomial([1.0, 0.05, 0.25]), ctid.Polynomial([2.0])),
    ctid.Submodel(ctid.Polynomial([1.0, 0.5]), ctid.Polynomial([1.0])),
])


def cut_record(start=600, length=1500):
    """A record cut out of a longer noise-free run: it starts mid-motion."""
    u = ctid.white_noise(start + length, 1.0, 5)
    y = ctid.model_output(MODEL, u, H)
    return ctid.SampledData(H, u[start:], y[start:], start_time=start * H)


def test_estimated_state_recovers_a_record_that_starts_mid_motion():
    data = cut_record()
    estimate = ctid.validate_model(
        MODEL, data, ctid.ValidationOptions(initial_state=ctid.InitialState.estimate))
    assert estimate.fit_percent >= 99.9999
    assert estimate.fit_percent == estimate.fit_estimated_state
    assert estimate.states == 3 and estimate.initial_state_rank == 3
    zero = ctid.validate_model(MODEL, data, ctid.ValidationOptions())
    assert zero.fit_percent == zero.fit_zero_state
    assert zero.fit_estimated_state == estimate.fit_estimated_state
    assert zero.fit_percent < 95.0
    # The old call is the same as the default options.
    assert ctid.validate_model(MODEL, data).fit_percent == zero.fit_percent
    # The free response found is what separates the cut record from a simulation from rest.
    rest = ctid.model_output(MODEL, data.input, H)
    output = ctid.validation_output(
        MODEL, data, ctid.ValidationOptions(initial_state=ctid.InitialState.estimate))
    np.testing.assert_allclose(output, data.output, atol=1e-8 * np.abs(data.output).max())
    free = np.asarray(data.output) - rest
    assert estimate.free_response_rms == pytest.approx(np.sqrt(np.mean(free ** 2)), rel=1e-6)


def test_window_is_scored_on_the_record_time_axis():
    data = cut_record()  # t = 30 to 104.95 s
    options = ctid.ValidationOptions(window_start=40.0, window_end=70.0, max_lag=4)
    report = ctid.validate_model(MODEL, data, options)
    assert report.window_samples == 601
    assert report.window_start == pytest.approx(40.0) and report.window_end == pytest.approx(70.0)
    rest = ctid.model_output(MODEL, data.input, H)
    k = slice(200, 801)
    y = np.asarray(data.output)[k]
    assert report.fit_zero_state == pytest.approx(ctid.fit_percent(y, rest[k]), abs=1e-12)
    assert report.mean_squared_error == pytest.approx(np.mean((y - rest[k]) ** 2), rel=1e-12)
    assert ctid.options_from_json("ValidationOptions", {"window_start": 40.0, "window_end": 70.0,
                                                        "max_lag": 4}) == options


def test_a_window_outside_the_record_names_the_window_and_the_record():
    data = cut_record()
    with pytest.raises(ctid.InvalidArgument, match=r"window \[20, 50\] s is not inside the "
                       r"record \(1500 samples of 0\.05 s, t = 30 to 104\.95 s\)"):
        ctid.validate_model(MODEL, data, ctid.ValidationOptions(window_start=20.0,
                                                                window_end=50.0))
    with pytest.raises(ValueError, match="window_end"):
        ctid.ValidationOptions(window_start=50.0, window_end=40.0).validate()


def test_compare_draws_several_models_with_their_fits(tmp_path):
    pytest.importorskip("matplotlib")
    from ctid import plotting

    data = cut_record()
    slow_only = ctid.AdditiveModel([ctid.Submodel(ctid.Polynomial([1.0, 0.05, 0.25]),
                                                  ctid.Polynomial([2.0]))])
    options = ctid.ValidationOptions(initial_state=ctid.InitialState.estimate,
                                     window_start=40.0)
    figure = plotting.compare(data, [MODEL, slow_only], labels=["true", "one mode"],
                              options=options, filename=str(tmp_path / "compare.png"))
    legend = [text.get_text() for text in figure.axes[0].get_legend().get_texts()]
    assert legend[0] == "measured"
    assert legend[1] == "true: fit 100.00 %"
    fit = ctid.validate_model(slow_only, data, options).fit_percent
    assert fit < 99.0
    assert legend[2] == f"one mode: fit {fit:.2f} %"
    assert "scored window" in legend
    assert (tmp_path / "compare.png").stat().st_size > 10000
