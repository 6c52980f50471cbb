"""The modal model fitted to an FRF matrix from Python (ctid.frf_matrix_fit, issue 13): modes
from a noise-free two-input, three-output FRF given as NumPy arrays, the same through a
universal file and a CSV table, options as keywords, the result document read back, and bad
input as one clear error."""

import numpy as np
import pytest

import ctid


def two_modes():
    shapes = [[1.0, 0.5, -0.3], [-0.4, 1.0, 0.6]]
    participation = [[1.0, 0.6], [-0.5, 0.8]]
    submodels = []
    for i, w in enumerate((1.4, 4.0)):
        b = [ctid.Polynomial([shapes[i][j] * participation[i][k]])
             for j in range(3) for k in range(2)]
        submodels.append(ctid.MimoSubmodel(ctid.Polynomial([1.0, 0.1 / w, 1 / w ** 2]), b))
    return ctid.MimoAdditiveModel(2, 3, submodels)


def frf_of(model, frequencies, **names):
    return ctid.mimo_frf(frequencies, ctid.mimo_frequency_response(model, frequencies), **names)


def test_modes_from_arrays_files_and_documents(tmp_path):
    truth = two_modes()
    w = 2 * np.pi * np.linspace(0.01, 1.6, 160)
    frf = frf_of(truth, w, input_names=["101+X", "102+X"], output_names=["1+Z", "2+Z", "3+Z"])
    assert frf.response.shape == (160, 3, 2)
    r = ctid.frf_matrix_fit(frf, [ctid.SubmodelOrder(2, 1)] * 2, max_iterations=50)
    assert r.converged(), r.message
    assert r.verdict.usable
    assert [m.natural_frequency for m in r.modes] == pytest.approx([1.4, 4.0], rel=1e-9)
    assert [m.damping_ratio for m in r.modes] == pytest.approx([0.05, 0.05], rel=1e-9)
    psi = np.array([-0.4, 1.0, 0.6])
    assert ctid.modal_assurance(r.modes[1].shape, psi) == pytest.approx(1.0, abs=1e-9)
    assert r.fit_percent.shape == (3, 2)
    assert np.all(r.fit_percent > 99.999)
    # The same FRF through a universal file and a CSV table.
    ctid.write_uff58(str(tmp_path / "h.uff"), frf)
    ctid.write_mimo_frf_csv(str(tmp_path / "h.csv"), frf)
    for name in ("h.uff", "h.csv"):
        back = ctid.read_mimo_frf(str(tmp_path / name))
        assert back.output_names == ["1+Z", "2+Z", "3+Z"]
        again = ctid.frf_matrix_fit(back, [ctid.SubmodelOrder(2, 1)] * 2)
        assert [m.natural_frequency for m in again.modes] == pytest.approx([1.4, 4.0], rel=1e-8)
    path = tmp_path / "r.json"
    ctid.write_result(str(path), r)
    read = ctid.read_result(str(path))
    assert isinstance(read, ctid.FrfMatrixFitResult)
    assert np.array_equal(read.covariance, r.covariance)
    assert "frf_matrix_fit_result" in ctid.result_document_types()


def test_standard_errors_and_options():
    truth = two_modes()
    w = np.linspace(0.05, 10.0, 300)
    g = ctid.mimo_frequency_response(truth, w)
    rng = np.random.default_rng(4)
    noisy = g + 0.01 * (rng.standard_normal(g.shape) + 1j * rng.standard_normal(g.shape))
    options = ctid.FrfMatrixFitOptions(max_frequency=8.0)
    r = ctid.frf_matrix_fit(ctid.mimo_frf(w, noisy), [ctid.SubmodelOrder(2, 0)] * 2,
                            options=options)
    assert r.lines == int(np.sum(w <= 8.0))
    for mode, true_w in zip(r.modes, (1.4, 4.0)):
        assert 0 < mode.natural_frequency_se < 0.01
        assert abs(mode.natural_frequency - true_w) < 5 * mode.natural_frequency_se


def test_identify_is_the_front_door_of_frf_matrix_fit():
    # ctid.identify on a MimoFrf runs what `ctid fit-frf` runs: frf_matrix_fit, bit for bit,
    # with its options and start given as FrfIdentificationOptions (decision 0044).
    truth = two_modes()
    frf = frf_of(truth, 2 * np.pi * np.linspace(0.01, 1.6, 160))
    orders = [ctid.SubmodelOrder(2, 1)] * 2
    direct = ctid.frf_matrix_fit(frf, orders, max_iterations=50)
    front = ctid.identify(frf, orders, frf_fit=ctid.FrfMatrixFitOptions(max_iterations=50))
    assert isinstance(front, ctid.FrfMatrixFitResult)
    assert front.converged(), front.message
    assert front.message == direct.message
    assert np.array_equal(front.fit_percent, direct.fit_percent)
    assert np.array_equal(front.covariance, direct.covariance)
    started = ctid.identify(frf, orders, ctid.FrfIdentificationOptions(
        frf_fit=ctid.FrfMatrixFitOptions(max_iterations=2), initial_model=truth))
    expected = ctid.frf_matrix_fit(frf, orders, truth, max_iterations=2)
    assert started.iterations == expected.iterations
    assert np.array_equal(started.fit_percent, expected.fit_percent)
    with pytest.raises(ctid.InvalidArgument, match="n = 1 or 2"):
        ctid.identify(frf, [ctid.SubmodelOrder(4, 0)])


def test_bad_input_is_one_clear_error():
    w = np.linspace(0.05, 10.0, 50)
    frf = frf_of(two_modes(), w)
    with pytest.raises(ctid.InvalidArgument, match="n = 1 or 2"):
        ctid.frf_matrix_fit(frf, [ctid.SubmodelOrder(4, 0)])
    with pytest.raises(ctid.InvalidArgument, match="tolerance"):
        ctid.frf_matrix_fit(frf, [ctid.SubmodelOrder(2, 0)], tolerance=2.0)
    with pytest.raises(ctid.InvalidArgument, match="40 frequencies but 50 response"):
        ctid.mimo_frf(w[:40], ctid.mimo_frequency_response(two_modes(), w))
    with pytest.raises(TypeError):
        ctid.frf_matrix_fit(frf, [ctid.SubmodelOrder(2, 0)], no_such_option=1)


def test_figures_of_the_time_domain_fit_draw_an_frf_fit(tmp_path):
    # plotting's MIMO figures take the model and the modes, whichever fit produced them.
    import matplotlib

    matplotlib.use("Agg")
    from ctid import plotting

    truth = two_modes()
    frf = frf_of(truth, np.linspace(0.05, 10.0, 200))
    r = ctid.frf_matrix_fit(frf, [ctid.SubmodelOrder(2, 1)] * 2)
    plotting.frf_matrix_overlay(r.model, frf, filename=str(tmp_path / "overlay.png"))
    plotting.mode_shapes(r.modes, output_names=frf.output_names,
                         filename=str(tmp_path / "shapes.png"))
    plotting.mac_matrix(r.modes, filename=str(tmp_path / "mac.png"))
    for name in ("overlay.png", "shapes.png", "mac.png"):
        assert (tmp_path / name).stat().st_size > 0
