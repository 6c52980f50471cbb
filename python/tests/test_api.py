"""The public surface: docstrings everywhere, keyword options checked, C++ errors mapped to
ValueError / RuntimeError with the C++ message, NumPy in and out."""

import inspect

import numpy as np
import pytest

import ctid
import ctid.plot
import ctid.plotting


def public_names(module):
    return [n for n in dir(module) if not n.startswith("_")]


def test_every_public_function_and_class_has_a_docstring():
    missing = []
    for name in public_names(ctid):
        obj = getattr(ctid, name)
        if inspect.ismodule(obj) or name == "annotations":
            continue
        doc = getattr(obj, "__doc__", None)
        if not doc or not doc.strip():
            missing.append(name)
            continue
        if inspect.isclass(obj):
            for member_name, member in vars(obj).items():
                if member_name.startswith("_"):
                    continue
                if hasattr(obj, "__members__") and member_name in ("name", "value"):
                    continue  # pybind11's own enum accessors
                if isinstance(member, (int, float, str, tuple)):
                    continue  # enum values and the `fields` tuple
                member_doc = getattr(member, "__doc__", None)
                if type(member).__name__ == type(obj).__name__:
                    continue  # enum members are instances of the enum
                if not member_doc or not member_doc.strip():
                    missing.append(f"{name}.{member_name}")
    for module in (ctid.plotting, ctid.plot):
        for name in getattr(module, "__all__", public_names(module)):
            obj = getattr(module, name)
            if inspect.isfunction(obj) and obj.__module__ == module.__name__:
                if not (obj.__doc__ or "").strip():
                    missing.append(f"{module.__name__}.{name}")
    assert not missing, "missing docstrings: " + ", ".join(missing)


def test_the_package_reaches_every_layer():
    for name in ["Polynomial", "TransferFunction", "AdditiveModel", "SampledData",
                 "simulate", "simulate_closed_loop", "multisine", "prbs", "colored_noise",
                 "simulate_delayed", "frequency_response", "periodic_frf", "welch_frf",
                 "resonance_peaks", "srivc", "clsrivc", "additive_srivc", "additive_clsrivc",
                 "srivc_delay_scan", "initial_additive_model", "validate_model",
                 "build_feedback_regression", "estimate_closed_loop_batch", "run_study",
                 "run_study_case", "log_spaced_sizes"]:
        assert hasattr(ctid, name), name


@pytest.mark.parametrize("options_class", [
    ctid.RefinedIvOptions, ctid.MultisineOptions, ctid.PrbsOptions, ctid.PeriodicFrfOptions,
    ctid.WelchOptions, ctid.PeakOptions, ctid.InitializationOptions, ctid.StudyOptions,
    ctid.BatchLeastSquaresOptions, ctid.RecursiveLeastSquaresOptions,
    ctid.FeedbackRegressorOptions, ctid.DelayedSimulationOptions])
def test_options_reject_unknown_keywords(options_class):
    with pytest.raises(TypeError, match="unexpected keyword argument 'bogus'; valid keywords: "
                       + options_class.fields[0]):
        options_class(bogus=1)
    first = options_class.fields[0]
    default = getattr(options_class(), first)
    assert getattr(options_class(**{first: default}), first) == default
    assert repr(options_class()).startswith(options_class.__name__ + "(")


def test_functions_reject_unknown_keywords(experiment):
    with pytest.raises(TypeError, match=r"srivc\(\) got an unexpected keyword argument "
                                        r"'max_iter'; valid keywords: max_iterations"):
        ctid.srivc(experiment["data"], ctid.SubmodelOrder(2, 0), max_iter=3)
    with pytest.raises(TypeError, match="either options=... or keyword options"):
        ctid.welch_frf(experiment["data"], options=ctid.WelchOptions(), overlap=0.2)
    with pytest.raises(TypeError, match=r"multisine\(\) got an unexpected keyword"):
        ctid.multisine(period=3)


def test_invalid_argument_is_a_value_error_with_the_cpp_message(experiment):
    data = experiment["data"]
    with pytest.raises(ValueError) as info:
        ctid.periodic_frf(data, period_length=250)
    assert str(info.value) == ("periodic_frf: the record length 1024 is not a multiple of "
                               "period_length 250")
    assert isinstance(info.value, ctid.InvalidArgument)
    with pytest.raises(ValueError, match=r"^WelchOptions.overlap is 1; it must be in \[0, 1\)$"):
        ctid.welch_frf(data, overlap=1.0)
    with pytest.raises(ValueError, match="PeriodicFrfOptions.period_length is 2; it must be >= 4"):
        ctid.PeriodicFrfOptions(period_length=2).validate()
    with pytest.raises(ValueError):
        ctid.SampledData(0.0, np.ones(4), np.ones(4))


def test_a_nan_coefficient_is_a_value_error_naming_it():
    # Issue 33: a list the implicit Polynomial conversion refused gave pybind's TypeError.
    import math
    with pytest.raises(ValueError, match="coefficient 0 .* is nan; coefficients must be finite"):
        ctid.TransferFunction([1.0], [math.nan, 1.0])
    with pytest.raises(ValueError, match="is inf; coefficients must be finite"):
        ctid.DiscreteTransferFunction([1.0], [1.0, math.inf], 0.1)
    assert ctid.TransferFunction([2.0], [1.0, 1.0]).dc_gain() == 2.0


def test_computation_error_is_a_runtime_error():
    assert issubclass(ctid.ComputationError, RuntimeError)
    assert issubclass(ctid.InvalidArgument, ValueError)


def test_numpy_in_and_out(experiment):
    g = experiment["g"]
    w = np.array([0.5, 1.0, 2.0])
    response = ctid.frequency_response(g, w)
    assert isinstance(response, np.ndarray) and response.dtype == complex
    expected = 4.0 / (4.0 + 0.8j * w - w**2)
    np.testing.assert_allclose(response, expected, rtol=1e-14)
    assert isinstance(experiment["data"].output, np.ndarray)
    # Polynomials take plain lists, ascending.
    p = ctid.Polynomial([1.0, 2.0, 3.0])
    assert p(2.0) == 1.0 + 4.0 + 12.0


def test_initial_conditions_are_estimated_for_a_record_that_starts_mid_motion():
    # 4 / (4 + 0.8 p + p^2) = 1 / (1 + 0.2 p + 0.25 p^2); the record is cut after 200 samples.
    h = 0.05
    g = ctid.TransferFunction([4.0], [4.0, 0.8, 1.0])
    u = ctid.white_noise(1200, 1.0, 3)
    y = ctid.simulate(g, u, h)
    data = ctid.SampledData(h, u[200:], y[200:])
    truth = np.array([0.2, 0.25, 1.0])
    order = ctid.SubmodelOrder(2, 0)
    r = ctid.srivc(data, order, initial_conditions=ctid.InitialConditions.estimate)
    assert r.converged()
    np.testing.assert_allclose(r.parameters, truth, rtol=1e-9)
    assert r.initial_conditions.shape == (2,)  # free response and its derivative at t = 0
    zero = ctid.srivc(data, order)  # default: at rest
    assert np.max(np.abs(zero.parameters - truth) / truth) > 1e-4
    assert zero.initial_conditions.size == 0


def test_complex_or_text_samples_are_refused_naming_the_argument():
    # NumPy would cast complex samples to real with only a warning: the record refuses them.
    u = np.ones(100)
    y = np.ones(100)
    with pytest.raises(ctid.InvalidArgument, match="SampledData: input has complex values"):
        ctid.SampledData(0.1, u + 0j, y)
    with pytest.raises(ctid.InvalidArgument, match="SampledData: reference has complex values"):
        ctid.SampledData(0.1, u, y, reference=1j * u)
    with pytest.raises(ctid.InvalidArgument, match="MimoData: outputs has complex values"):
        ctid.MimoData(0.1, np.ones((100, 2)), np.ones((100, 1)) * 1j)
    with pytest.raises(ctid.InvalidArgument, match="from_time_stamps: output has complex"):
        ctid.SampledData.from_time_stamps(np.arange(100) * 0.1, u, y * 1j)
    with pytest.raises(ctid.InvalidArgument, match="input must be numbers"):
        ctid.SampledData(0.1, ["1"] * 100, y)
    # Real arrays, lists and the SISO-to-MIMO conversion are untouched.
    record = ctid.SampledData(sample_time=0.1, input=list(u), output=y.astype(np.float32))
    assert len(ctid.MimoData(record)) == 100
