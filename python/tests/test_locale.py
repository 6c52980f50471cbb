"""Issue 33: LC_NUMERIC set to a comma locale. Inside Python after
``locale.setlocale(locale.LC_NUMERIC, "de_DE.UTF-8")``, and for the ``ctid`` command line run
with ``LC_ALL=de_DE.UTF-8``, every number ctid reads or writes (CSV, JSON documents, universal
files, model texts and messages) keeps its dot, and every result is the C locale's bit for bit.
A comma locale comes from the Debian package ``locales`` (scripts/setup.sh makes de_DE.UTF-8);
without one the tests are skipped, saying so."""

import contextlib
import json
import locale
import os
import pathlib
import subprocess

import numpy as np
import pytest

import ctid

COMMA_LOCALES = ("de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "fr_FR.utf8", "nl_NL.UTF-8",
                 "it_IT.UTF-8", "es_ES.UTF-8")
H = 0.05  # not a binary fraction: its 17 digits are 0.050000000000000003


@contextlib.contextmanager
def numeric_locale(name):
    saved = locale.setlocale(locale.LC_NUMERIC)
    locale.setlocale(locale.LC_NUMERIC, name)
    try:
        yield
    finally:
        locale.setlocale(locale.LC_NUMERIC, saved)


def _find_comma_locale():
    for name in COMMA_LOCALES:
        try:
            with numeric_locale(name):
                if locale.localeconv()["decimal_point"] == ",":
                    return name
        except locale.Error:
            continue
    return None


@pytest.fixture(scope="module")
def comma():
    name = _find_comma_locale()
    if name is None:
        pytest.skip("no comma locale is installed (scripts/setup.sh makes de_DE.UTF-8 from "
                    "the Debian package locales)")
    return name


def _bits(array):
    return np.ascontiguousarray(np.asarray(array, dtype=float)).tobytes().hex()


def _everything(folder):
    """What ctid reads and writes on one seeded record, as bytes and text to compare."""
    folder = pathlib.Path(folder)
    folder.mkdir()
    g = ctid.TransferFunction([4.0], [4.0, 0.8, 1.0])
    u = ctid.white_noise(400, 1.0, 11)
    y = ctid.simulate(g, u, H) + ctid.white_noise(400, 0.01, 12)
    data = ctid.SampledData(H, u, y)
    out = {}
    ctid.write_csv(folder / "d.csv", data)
    out["csv"] = (folder / "d.csv").read_bytes()
    back = ctid.read_csv(folder / "d.csv")
    out["csv read"] = (float.hex(back.sample_time), _bits(back.input), _bits(back.output))
    result = ctid.srivc(back, ctid.SubmodelOrder(2, 0), max_iterations=30)
    out["srivc"] = ctid.result_to_json(result)
    ctid.write_result(folder / "r.json", result)
    out["result file"] = (folder / "r.json").read_bytes()
    out["result read"] = ctid.result_to_json(ctid.read_result(folder / "r.json"))
    model = result.model
    out["model"] = ctid.model_to_json(model)
    ctid.write_model(folder / "m.json", model)
    out["model file"] = (folder / "m.json").read_bytes()
    out["model read"] = ctid.model_to_json(ctid.read_model(folder / "m.json"))
    out["model text"] = (str(g), repr(g), str(model))
    frequencies = np.linspace(0.5, 5.0, 7)
    response = ctid.frequency_response(g, frequencies).reshape(-1, 1, 1)
    frf = ctid.mimo_frf(frequencies, response)
    ctid.write_uff58(folder / "f.uff", frf)
    out["uff"] = (folder / "f.uff").read_bytes()
    frf_back = ctid.read_mimo_frf(folder / "f.uff")
    out["uff read"] = (_bits(frf_back.frequencies), _bits(np.asarray(frf_back.response).real),
                       _bits(np.asarray(frf_back.response).imag))
    ctid.write_mimo_frf_csv(folder / "f.csv", frf)
    out["frf csv"] = (folder / "f.csv").read_bytes()
    # A message with a number: a CSV whose decimal fractions cannot be read as numbers.
    (folder / "bad.csv").write_text("t,u,y\n0,1.5,0.25\n0.05,1.5,x0.5\n")
    with pytest.raises(ctid.InvalidArgument) as error:
        ctid.read_csv(folder / "bad.csv")
    out["message"] = str(error.value).replace(str(folder), "FOLDER")
    return out


def test_python_under_a_comma_locale_reads_and_writes_dots_bit_for_bit(comma, tmp_path):
    expected = _everything(tmp_path / "c")
    assert b"0.050000000000000003," in expected["csv"]  # the test's premise: dots, 17 digits
    with numeric_locale(comma):
        assert locale.localeconv()["decimal_point"] == ","
        assert locale.format_string("%.2f", 0.5) == "0,50"  # the locale really is in force
        got = _everything(tmp_path / "comma")
    for key in expected:
        assert got[key] == expected[key], key
    # Nothing came out with a decimal comma: every CSV row keeps its three fields.
    rows = got["csv"].decode().splitlines()
    assert all(len(row.split(",")) == 3 for row in rows[1:]), rows[:3]
    assert "0.8" in got["model text"][0], got["model text"]
    assert "E-01" in got["uff"].decode() or "E+00" in got["uff"].decode()


def test_the_cli_under_a_comma_locale_writes_the_c_locales_bytes(cli, comma, tmp_path):
    (tmp_path / "g.json").write_text(json.dumps({
        "type": "additive_model", "input_delay": 0.0, "submodels": [
            {"denominator_ascending": [1.0, 0.2, 0.25], "numerator_ascending": [0.5]}]}))

    def run(folder, env_locale):
        folder = tmp_path / folder
        folder.mkdir()
        env = dict(os.environ, LC_ALL=env_locale, LC_NUMERIC=env_locale, LANG=env_locale)
        for args in (["simulate", "-m", tmp_path / "g.json", "-e", "prbs", "-n", "600", "-T",
                      "0.05", "--seed", "3", "--snr", "30", "--noise-seed", "4", "-o",
                      folder / "d.csv", "-q"],
                     ["fit", folder / "d.csv", "--modes", "1", "-o", folder / "r.json", "-q"],
                     ["frf", folder / "d.csv", "-o", folder / "f.csv", "-q"]):
            completed = subprocess.run([str(cli), *map(str, args)], env=env,
                                       capture_output=True, text=True)
            assert completed.returncode == 0, completed.stderr
        bad = subprocess.run([str(cli), "fit", str(folder / "d.csv"), "--time", "0,5:1.5"],
                             env=env, capture_output=True, text=True)
        assert bad.returncode == 2, bad.stderr
        files = {p.name: p.read_bytes().replace(str(folder).encode(), b"F")
                 for p in folder.iterdir()}
        return files, bad.stderr.replace(str(folder), "F")

    expected_files, expected_message = run("c", "C")
    files, message = run("comma", comma)
    assert files == expected_files
    assert message == expected_message
    assert message.startswith("ctid fit: error: ") and message.count("\n") == 1, message
    assert b"0.05" in files["d.csv"]
