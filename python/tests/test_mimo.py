"""MimoData, its CSV reader and writer, and the MIMO FRF from Python: NumPy in and out, the
1 x 1 case equal to the SISO estimate, a noise-free two-input system recovered, errors with
the C++ message."""

import numpy as np
import pytest

import ctid

H = 0.05


def _mode(gain, wn, zeta):
    """gain wn^2 / (s^2 + 2 zeta wn s + wn^2) as an additive model (A anti-monic)."""
    return ctid.AdditiveModel([ctid.Submodel([1.0, 2 * zeta / wn, 1 / wn**2], [gain])])


def _record(samples=16384, seed=1):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((samples, 2))
    g = [
        [_mode(1.0, 2.0, 0.5), _mode(-0.5, 4.0, 0.4)],
        [_mode(0.8, 3.0, 0.6), _mode(0.3, 5.0, 0.5)],
    ]
    y = np.column_stack(
        [sum(ctid.simulate(g[j][i], u[:, i], H) for i in range(2)) for j in range(2)]
    )
    return ctid.MimoData(H, u, y).with_names(["f1", "f2"], ["a1", "a2"]), g


def test_mimo_data_from_numpy():
    data, _ = _record(256)
    assert len(data) == 256 and data.input_count == 2 and data.output_count == 2
    assert data.inputs.shape == (256, 2) and data.outputs.shape == (256, 2)
    assert data.input_names == ["f1", "f2"] and data.output_names == ["a1", "a2"]
    assert data.references is None and not data.has_references()
    siso = data.channel(1, 0)
    np.testing.assert_array_equal(siso.input, data.inputs[:, 1])
    np.testing.assert_array_equal(siso.output, data.outputs[:, 0])
    assert "f1, f2" in repr(data)
    with pytest.raises(ValueError, match="named twice"):
        data.with_names(["a", "b"], ["a", "c"])
    with pytest.raises(ValueError, match="equal lengths"):
        ctid.MimoData(H, np.zeros((10, 2)), np.zeros((9, 1)))


def test_csv_round_trip_and_column_errors(tmp_path):
    data, _ = _record(64)
    ctid.write_mimo_data(tmp_path / "m.csv", data)
    back = ctid.read_mimo_data(tmp_path / "m.csv", inputs=["f1:f2"], outputs=["a2", "a1"])
    np.testing.assert_array_equal(back.inputs, data.inputs)
    np.testing.assert_array_equal(back.outputs[:, 0], data.outputs[:, 1])
    assert back.output_names == ["a2", "a1"]
    columns = ctid.MimoCsvColumns(inputs=["f1"], outputs=["a1:a3"])
    with pytest.raises(ValueError, match=r"m.csv: output column 'a3' not found .*columns are t,"):
        ctid.read_mimo_data(tmp_path / "m.csv", columns)
    with pytest.raises(ValueError, match="is named twice"):
        ctid.read_mimo_data(tmp_path / "m.csv", inputs=["f1"], outputs=["f1"])
    with pytest.raises(TypeError, match="unexpected keyword"):
        ctid.read_mimo_data(tmp_path / "m.csv", input=["f1"])


def test_one_by_one_equals_the_siso_welch_estimate():
    data, _ = _record(8192)
    siso = ctid.welch_frf(data.channel(0, 1), segment_length=512)
    mimo = ctid.welch_frf(ctid.MimoData(data.channel(0, 1)), segment_length=512)
    assert mimo.response.shape == (256, 1, 1)
    np.testing.assert_allclose(mimo.response[:, 0, 0], siso.response, rtol=1e-12)
    np.testing.assert_allclose(mimo.coherence[:, 0], siso.coherence, atol=1e-12)
    m = siso.averages
    np.testing.assert_allclose(mimo.variance[:, 0, 0], siso.variance * m / (m - 1), rtol=1e-9)


def test_two_inputs_recovered_and_summarised():
    data, g = _record(32768)
    frf = ctid.welch_frf(data, ctid.WelchOptions(segment_length=1024))
    assert frf.response.shape == (512, 2, 2) and frf.variance.shape == (512, 2, 2)
    assert frf.coherence.shape == (512, 2) and frf.input_level.shape == (512, 2)
    band = frf.frequencies < 10.0
    w = frf.frequencies[band]
    truth = np.array(
        [[ctid.sampled_frequency_response(g[j][i], w, H) for i in range(2)] for j in range(2)]
    )
    error = np.abs(np.moveaxis(frf.response[band], 0, -1) - truth) / np.abs(truth)
    assert error.max() < 0.1  # the leakage of a random input, acting as noise
    assert np.median(error) < 0.01
    assert frf.coherence[band].min() > 0.99
    assert frf.input_condition.max() < 2.0
    assert not frf.inputs_correlated(3)
    one = frf.channel(1, 0)
    np.testing.assert_array_equal(one.response, frf.response[:, 0, 1])
    summary = ctid.summed_power_frf(frf)
    frobenius = np.sqrt((np.abs(frf.response) ** 2).sum(axis=(1, 2)))
    np.testing.assert_allclose(summary.response.real, frobenius)
    assert isinstance(ctid.resonance_peaks(summary), list)  # well damped: no 3-dB peak
    kept = ctid.excited_lines(frf, 0.95)
    assert 0 < len(kept.lines) < len(frf.lines)
    assert (kept.input_level.min(axis=1) > 0.95).all()


def test_hadamard_experiments_from_python():
    ms = ctid.MultisineOptions(
        period_length=256, sample_time=H, max_frequency=3.0, periods=4, seed=3
    )
    s1 = ctid.multisine(ms).signal
    ms.seed = 4
    s2 = ctid.multisine(ms).signal
    g = _mode(1.0, 2.0, 0.5)
    experiments = []
    for sign in (1.0, -1.0):
        u = np.column_stack([s1, sign * s2])
        y = ctid.simulate(g, u[:, 0], H) + 0.5 * ctid.simulate(g, u[:, 1], H)
        experiments.append(ctid.MimoData(H, u, y[:, None]))
    frf = ctid.periodic_frf(experiments, period_length=256, transient_periods=2)
    assert frf.response.shape[1:] == (1, 2)
    np.testing.assert_allclose(frf.response[:, 0, 1], 0.5 * frf.response[:, 0, 0], rtol=1e-9)
    np.testing.assert_allclose(frf.input_condition, 1.0, atol=1e-9)
    with pytest.raises(ValueError, match="at least one experiment per input"):
        ctid.periodic_frf(experiments[:1], period_length=256)


def test_orthogonal_multisines_give_a_well_conditioned_frf():
    o = ctid.orthogonal_multisines(
        3, period_length=512, sample_time=H, max_frequency=3.0, periods=3, seed=2
    )
    assert len(o.experiments) == 4 and o.experiments[0].shape == (1536, 3)
    g = _mode(1.0, 2.0, 0.5)
    records = [
        ctid.MimoData(H, u, ctid.simulate(g, u.sum(axis=1), H)[:, None]) for u in o.experiments
    ]
    # One 25.6-s period of transient: what is left of e^{-t} is 1e-11.
    frf = ctid.periodic_frf(records, period_length=512, transient_periods=1)
    assert frf.lines == o.lines
    np.testing.assert_allclose(frf.input_condition, 1.0, atol=1e-9)
    np.testing.assert_allclose(frf.response[:, 0, 0], frf.response[:, 0, 2], rtol=1e-8)


def test_frf_matrix_figure_from_the_result_and_from_the_cli_document(tmp_path):
    import ctid.plot
    from ctid import plotting

    data, _ = _record(4096)
    frf = ctid.welch_frf(data, segment_length=256)
    figure = plotting.frf_matrix(frf, filename=tmp_path / "m.png")
    assert (tmp_path / "m.png").stat().st_size > 0
    top, bottom = figure.axes
    drawn = {line.get_label(): line for line in top.get_lines()}
    assert sorted(drawn) == ["a1/f1", "a1/f2", "a2/f1", "a2/f2"]
    np.testing.assert_allclose(drawn["a2/f1"].get_xdata(), frf.frequencies / (2 * np.pi))
    np.testing.assert_allclose(
        drawn["a2/f1"].get_ydata(), 20 * np.log10(np.abs(frf.response[:, 1, 0]))
    )
    assert [line.get_label() for line in bottom.get_lines()] == ["coherence a1", "coherence a2"]
    ctid.write_result(str(tmp_path / "m.json"), frf)  # the mimo_frf document of ctid frf
    again = ctid.plot.run("frf_matrix", str(tmp_path / "m.json"), str(tmp_path / "n.png"))
    np.testing.assert_allclose(again.axes[0].get_lines()[0].get_ydata(),
                               top.get_lines()[0].get_ydata())
    with pytest.raises(ValueError, match="no channel a3/f1"):
        plotting.frf_matrix(frf, channels=[("a3", "f1")])


def test_preprocessing_every_channel_alike():
    data, _ = _record(1024)
    p = ctid.preprocess(data, detrend=ctid.Detrend.mean, decimate=2)
    assert p.data.inputs.shape == (512, 2) and p.data.output_names == ["a1", "a2"]
    one = ctid.preprocess(data.channel(1, 0), detrend=ctid.Detrend.mean, decimate=2)
    np.testing.assert_array_equal(p.data.inputs[:, 1], one.data.input)
    assert p.input_offsets[1] == one.record.input_offset


def test_known_input_delays_from_python_and_through_the_model_document():
    h = 0.05
    shapes = [[1.0, 0.5, -0.3], [-0.4, 1.0, 0.6]]
    participation = [[1.0, 0.6], [-0.5, 0.8]]
    submodels = []
    for i, w in enumerate((1.4, 4.0)):
        submodels.append(ctid.MimoSubmodel(
            ctid.Polynomial([1.0, 0.1 / w, 1.0 / w**2]),
            [ctid.Polynomial([shapes[i][j] * participation[i][k]])
             for j in range(3) for k in range(2)]))
    truth = ctid.MimoAdditiveModel(2, 3, submodels, np.zeros((0, 0)), np.array([0.0, 2.5 * h]))
    u = np.column_stack([ctid.white_noise(2000, 1.0, 5 + k) for k in range(2)])
    y = np.zeros((2000, 3))
    for j in range(3):
        for k in range(2):
            y[:, j] += ctid.model_output(truth.channel(j, k), u[:, k], h)
    options = ctid.MimoRefinedIvOptions(input_delays_samples=[0.0, 2.5])
    r = ctid.mimo_srivc(ctid.MimoData(h, u, y), [ctid.SubmodelOrder(2, 0, 0)] * 2,
                        options=options)
    assert r.converged(), r.message
    assert np.allclose(r.model.input_delays, [0.0, 2.5 * h], rtol=0, atol=1e-15)
    for i in range(2):
        assert np.allclose(r.model.submodels[i].a.coefficients,
                           truth.submodels[i].a.coefficients, rtol=1e-9)
    # The model document keeps the delays (docs/formats.md), and ctid.plot reads them back.
    from ctid import plot
    document = {"type": "mimo_additive_model", "inputs": 2, "outputs": 3,
                "submodels": [{"denominator_ascending": list(s.a.coefficients),
                               "numerators_ascending": [list(b.coefficients) for b in s.b]}
                              for s in r.model.submodels],
                "input_delays": list(r.model.input_delays)}
    back = plot.mimo_model_from_json(document)
    assert np.array_equal(back.input_delays, r.model.input_delays)
    with pytest.raises(ValueError, match="input_delays_samples has 1 entries but the data have 2"):
        ctid.mimo_srivc(ctid.MimoData(h, u, y), [ctid.SubmodelOrder(2, 0, 0)] * 2,
                        options=ctid.MimoRefinedIvOptions(input_delays_samples=[1.0]))
