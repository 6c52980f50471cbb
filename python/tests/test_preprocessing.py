"""Preprocessing on SampledData and the time-stamp rule, as the C++ library does them."""

import pathlib

import numpy as np
import pytest

import ctid

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _dryer():
    table = np.loadtxt(ROOT / "data" / "daisy_dryer_ljung" / "dryer.csv", delimiter=",",
                       skiprows=1)
    return ctid.SampledData.from_time_stamps(table[:, 0], table[:, 1], table[:, 2])


def test_detrend_mean_removes_the_dryer_means_and_records_them():
    data = _dryer()
    raw = ctid.preprocess(data)
    assert any("output mean 4.8901" in w for w in raw.record.warnings)
    done = data.preprocess(detrend=ctid.Detrend.mean)
    assert abs(done.data.output.mean()) < 1e-12
    assert done.record.output_offset == pytest.approx(data.output.mean(), rel=1e-14)
    assert done.record.warnings == []
    assert "means removed (u 5, y 4.89" in done.record.summary()
    by_object = ctid.preprocess(data, ctid.PreprocessingOptions(detrend=ctid.Detrend.mean))
    np.testing.assert_array_equal(by_object.data.output, done.data.output)


def test_the_estimation_trend_travels_to_the_validation_record():
    data = _dryer()
    estimation = data.segment(0, 600).preprocess(detrend=ctid.Detrend.linear)
    validation = data.segment(600, 400)
    removed = ctid.remove_trend(validation, estimation.record)
    t = np.arange(400) * validation.sample_time
    rec = estimation.record
    np.testing.assert_allclose(removed.output,
                               validation.output - rec.output_offset - rec.output_slope * t,
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(removed.input,
                               validation.input - rec.input_offset - rec.input_slope * t,
                               rtol=0, atol=1e-12)
    back = ctid.add_output_trend(removed.output, validation.sample_time, rec)
    np.testing.assert_allclose(back, validation.output, rtol=0, atol=1e-12)
    # On the estimation record itself it is preprocess's own detrending, bit for bit.
    same = ctid.remove_trend(data.segment(0, 600), rec)
    np.testing.assert_array_equal(same.output, estimation.data.output)


def test_ranges_decimation_and_scaling():
    data = _dryer()
    p = data.preprocess(first_row=100, end_row=500, decimate=2, input_scale=2.0)
    assert len(p.data) == 200
    assert p.data.sample_time == pytest.approx(0.16)
    assert p.data.start_time == pytest.approx(8.0)
    assert p.record.first_row == 100 and p.record.end_row == 500
    t = data.preprocess(start_time=8.0, end_time=40.0)
    assert (t.record.first_row, t.record.end_row) == (100, 500)


def test_bad_preprocessing_is_a_value_error_naming_what_is_wrong():
    data = _dryer()
    with pytest.raises(ValueError, match="rows 3:4 keeps 1 sample; detrend mean needs at least 2"):
        data.preprocess(first_row=3, end_row=4, detrend=ctid.Detrend.mean)
    with pytest.raises(ValueError, match="PreprocessingOptions.decimate is 0"):
        data.preprocess(decimate=0)
    with pytest.raises(TypeError):
        data.preprocess(detrnd=ctid.Detrend.mean)


def test_stamps_printed_to_five_digits_are_uniform():
    h = 1.0 / 1024.0
    stamps = np.array([float(f"{k * h:.5g}") for k in range(5000)])
    check = ctid.check_time_stamps(stamps)
    assert check.worst_sample is None
    assert check.digits == 5
    stamps[2500] += 0.3 * h
    assert ctid.check_time_stamps(stamps).worst_sample == 2500
