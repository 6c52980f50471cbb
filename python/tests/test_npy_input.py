"""Records saved with np.save are read as the CSV of the same numbers (decision 0022): the
ctid command line fits the same model from both, bit for bit, and ctid.read_mimo_data gives
the same arrays; float32 and integer arrays are read as doubles; a Fortran-order array is
refused with one line naming the file."""

import subprocess

import numpy as np
import pytest

import ctid

H = 0.05


@pytest.fixture(scope="module")
def record():
    """t, u, y of a resonant second-order system under a multisine, with a little noise."""
    g = ctid.TransferFunction([4.0], [4.0, 0.8, 1.0])
    u = ctid.multisine(period_length=512, sample_time=H, max_frequency=4.0, periods=4, seed=3)
    y = ctid.simulate(g, u.signal, H) + ctid.white_noise(len(u.signal), 0.01, 5)
    t = H * np.arange(len(y))
    return np.column_stack([t, u.signal, y])


def run(cli, folder, *args):
    return subprocess.run([str(cli), *map(str, args)], cwd=folder, capture_output=True, text=True)


def write_csv(path, array):
    np.savetxt(path, array, delimiter=",", header="t,u,y", comments="", fmt="%.17g")


def fit(cli, folder, data, model, *columns):
    done = run(cli, folder, "fit", data, "--poles", "2", "--zeros", "0", "-q", "--model-output",
               model, *columns)
    assert done.returncode == 0, done.stderr
    return (folder / model).read_text()


INDEX_COLUMNS = ("--time-column", "0", "--input-column", "1", "--output-column", "2")


def test_fit_from_np_save_equals_fit_from_csv(cli, record, tmp_path):
    write_csv(tmp_path / "d.csv", record)
    np.save(tmp_path / "d.npy", record)
    from_csv = fit(cli, tmp_path, "d.csv", "c.json")
    assert fit(cli, tmp_path, "d.npy", "n.json", *INDEX_COLUMNS) == from_csv
    # The version 2.0 format (np.lib.format) reads the same.
    with open(tmp_path / "v2.npy", "wb") as f:
        np.lib.format.write_array(f, record, version=(2, 0))
    assert fit(cli, tmp_path, "v2.npy", "v.json", *INDEX_COLUMNS) == from_csv


def test_float32_and_integer_arrays_read_as_their_doubles(cli, record, tmp_path):
    # float32 stamps are not uniform to the CSV rule's tolerance: u and y alone, with -T.
    narrow = record[:, 1:].astype(np.float32)
    np.savetxt(tmp_path / "f.csv", narrow.astype(np.float64), delimiter=",", header="u,y",
               comments="", fmt="%.17g")
    np.save(tmp_path / "f.npy", narrow)
    assert fit(cli, tmp_path, "f.npy", "n.json", "-T", H, "--input-column", "0",
               "--output-column", "1") == fit(cli, tmp_path, "f.csv", "c.json", "-T", H)

    # Integers: stamps in samples (h = 1 s), a +-1 input, an output in thousandths.
    table = np.column_stack([np.arange(len(record)), np.where(record[:, 1] >= 0, 1, -1),
                             np.round(1000 * record[:, 2])]).astype(np.int64)
    write_csv(tmp_path / "i.csv", table.astype(np.float64))
    np.save(tmp_path / "i.npy", table)
    read_npy = ctid.read_mimo_data(tmp_path / "i.npy", time="0", inputs=["1"], outputs=["2"])
    read_csv = ctid.read_mimo_data(tmp_path / "i.csv", time="t", inputs=["u"], outputs=["y"])
    assert np.array_equal(read_npy.inputs, read_csv.inputs)
    assert np.array_equal(read_npy.outputs, read_csv.outputs)
    assert read_npy.sample_time == read_csv.sample_time == 1.0


def test_fortran_order_and_text_files_are_refused_with_one_line(cli, record, tmp_path):
    np.save(tmp_path / "f.npy", np.asfortranarray(record))
    done = run(cli, tmp_path, "fit", "f.npy", *INDEX_COLUMNS, "--poles", "2", "--zeros", "0", "-q")
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1
    assert "f.npy: the array is in Fortran order (column-major)" in done.stderr
    write_csv(tmp_path / "text.npy", record[:10])
    done = run(cli, tmp_path, "fit", "text.npy", *INDEX_COLUMNS, "--poles", "2", "--zeros", "0", "-q")
    assert done.returncode == 2
    assert "text.npy: not a .npy file" in done.stderr
