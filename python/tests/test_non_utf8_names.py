"""Issue 33: file and folder names whose bytes are not UTF-8 (b"caf\\xe9.csv", a Latin-1 name),
given to ``ctid fit``, ``validate``, ``oma`` and ``batch`` and to the Python functions that
take paths. Each must read and write the files under their exact names; a JSON document or a
message that echoes such a name holds it with the bytes that are not UTF-8 written \\xHH
(decision 0042), never bytes that are not UTF-8 (nlohmann::json refused to write them:
"internal error: [json.exception.type_error.316]", and Python could not decode a message and
raised the exception without one)."""

import json
import os
import shutil
import subprocess

import numpy as np
import pytest

import ctid

MODEL = {"type": "transfer_function", "numerator_ascending": [4.0],
         "denominator_ascending": [4.0, 0.8, 1.0]}
DATA = b"caf\xe9.csv"  # Latin-1 "café": \xe9 starts no UTF-8 sequence here
FOLDER = b"r\xe9sultats\xff"
ESCAPED_DATA = "caf\\xe9.csv"
ESCAPED_FOLDER = "r\\xe9sultats\\xff"


def _is_utf8(data):
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return False
    return True


@pytest.fixture
def folder(cli, tmp_path):
    """A folder holding the model, a noise-free record under a Latin-1 name, a folder with a
    name that is not UTF-8, and the same record under an ASCII name for comparison."""
    (tmp_path / "m.json").write_text(json.dumps(MODEL))
    subprocess.run([str(cli), "simulate", "-m", "m.json", "-e", "prbs", "-n", "600", "-T",
                    "0.05", "-o", "good.csv", "-q"], cwd=tmp_path, check=True)
    root = os.fsencode(tmp_path)
    shutil.copyfile(os.path.join(root, b"good.csv"), os.path.join(root, DATA))
    os.mkdir(os.path.join(root, FOLDER))
    return root


def _run(cli, folder, *args):
    return subprocess.run([os.fsencode(cli), *args], cwd=folder, capture_output=True)


FIT = [b"--poles", b"2", b"--zeros", b"0", b"-q"]


def test_fit_reads_and_writes_under_the_exact_names_and_escapes_them_in_json(cli, folder):
    output = FOLDER + b"/fit\xe9.json"
    done = _run(cli, folder, b"fit", DATA, *FIT, b"-o", output, b"--model-output",
                b"mod\xe9.json")
    assert done.returncode == 0, done.stderr
    assert done.stderr == b""
    reference = _run(cli, folder, b"fit", b"good.csv", *FIT, b"-o", b"reference.json")
    assert reference.returncode == 0, reference.stderr
    written = open(os.path.join(folder, output), "rb").read()
    assert _is_utf8(written)
    document = json.loads(written)
    assert document["data"]["file"] == ESCAPED_DATA
    # The same fit as the ASCII-named copy of the record: only the name differs.
    expected = json.loads(open(os.path.join(folder, b"reference.json"), "rb").read())
    expected["data"]["file"] = ESCAPED_DATA
    document.pop("provenance", None)
    expected.pop("provenance", None)
    assert document == expected
    # Documents read back, by the command line and by Python, under their exact names.
    model = ctid.read_model(os.path.join(folder, b"mod\xe9.json"))
    assert json.loads(ctid.model_to_json(model)) == document["model"]
    again = _run(cli, folder, b"validate", output, DATA, b"-q")
    assert again.returncode == 0, again.stderr


def test_validate_writes_its_document_into_a_folder_named_in_latin1(cli, folder):
    output = FOLDER + b"/valid\xe9.json"
    done = _run(cli, folder, b"validate", b"m.json", DATA, b"-o", output, b"-q")
    assert done.returncode == 0, done.stderr
    written = open(os.path.join(folder, output), "rb").read()
    assert _is_utf8(written)
    assert ESCAPED_DATA in json.loads(written)["data"]["file"]


def test_oma_reads_a_latin1_named_record(cli, folder):
    rng = np.random.default_rng(4)
    y = np.cumsum(rng.standard_normal((3000, 3)), axis=0) * 0.01 + rng.standard_normal(
        (3000, 3))
    table = "t,a,b,c\n" + "".join(f"{k * 0.01!r},{r[0]!r},{r[1]!r},{r[2]!r}\n"
                                  for k, r in enumerate(y))
    name = b"oma\xe9.csv"
    with open(os.path.join(folder, name), "w") as f:
        f.write(table)
    output = FOLDER + b"/oma\xe9.json"
    done = _run(cli, folder, b"oma", name, b"--output-columns", b"a:c", b"--max-order", b"12",
                b"-o", output)
    assert done.returncode in (0, 3), done.stderr  # 3: no mode in this record, said on stdout
    written = open(os.path.join(folder, output), "rb").read()
    assert _is_utf8(written)
    assert json.loads(written)["data"]["file"] == "oma\\xe9.csv"


def test_a_missing_latin1_file_is_one_escaped_line(cli, folder):
    done = _run(cli, folder, b"fit", b"absent\xe9.csv", *FIT, b"-o", b"r.json")
    assert done.returncode == 2
    line = done.stderr.decode("utf-8")  # decodes: the message holds no byte that is not UTF-8
    assert line.count("\n") == 1
    assert "absent\\xe9.csv" in line
    assert not os.path.exists(os.path.join(folder, b"r.json"))


def test_an_output_that_exists_is_named_escaped(cli, folder):
    done = _run(cli, folder, b"fit", DATA, *FIT, b"-o", DATA)
    assert done.returncode == 2
    assert ESCAPED_DATA in done.stderr.decode("utf-8")
    assert open(os.path.join(folder, DATA), "rb").read() == open(
        os.path.join(folder, b"good.csv"), "rb").read()  # the record is untouched


def test_batch_runs_latin1_records_and_writes_utf8_summaries(cli, folder):
    shutil.copyfile(os.path.join(folder, DATA), os.path.join(folder, FOLDER, b"na\xefve.csv"))
    manifest = b"name,data\nlatin,caf\xe9.csv\n,r\xe9sultats\xff/na\xefve.csv\n"
    with open(os.path.join(folder, b"m\xe9.csv"), "wb") as f:
        f.write(manifest)
    out = b"out\xe9"
    with open(os.path.join(folder, b"spec.json"), "w") as f:
        f.write(json.dumps({"poles": 2, "zeros": 0}))
    done = _run(cli, folder, b"batch", b"m\xe9.csv", b"--spec", b"spec.json", b"--out", out,
                b"-q")
    summary_bytes = open(os.path.join(folder, out, b"summary.json"), "rb").read()
    assert _is_utf8(summary_bytes), summary_bytes[:200]
    rows = json.loads(summary_bytes)["records"]
    assert [row["name"] for row in rows] == ["latin", "na_ve"]
    assert rows[0]["data"] == ESCAPED_DATA
    assert rows[1]["data"] == ESCAPED_FOLDER + "/na\\xefve.csv"
    assert done.returncode == 0, done.stderr
    assert [row["status"] for row in rows] == ["ok", "ok"]
    assert sorted(os.listdir(os.path.join(folder, out))) == [
        b"latin.json", b"na_ve.json", b"summary.csv", b"summary.json", b"timings.json"]
    for name in (b"latin.json", b"na_ve.json"):
        assert _is_utf8(open(os.path.join(folder, out, name), "rb").read())
    plan = _run(cli, folder, b"batch", b"m\xe9.csv", b"--spec", b"spec.json", b"--out", out,
                b"--plan")
    assert plan.returncode == 0, plan.stderr
    assert [task["done"] for task in json.loads(plan.stdout.decode("utf-8"))] == [True, True]


def test_python_functions_take_bytes_and_surrogate_escaped_paths(folder):
    record = ctid.read_csv(os.path.join(folder, DATA))
    same = ctid.read_csv(os.fsdecode(os.path.join(folder, DATA)))  # str with \udce9
    assert np.array_equal(record.output, same.output)
    written = os.path.join(folder, FOLDER, b"copie\xe9.csv")
    ctid.write_csv(written, record)
    assert np.array_equal(ctid.read_csv(written).output, record.output)
    model = ctid.TransferFunction([4.0], [4.0, 0.8, 1.0])
    ctid.write_model(os.path.join(folder, FOLDER, b"mod\xe8le.json"), model)
    assert ctid.model_to_json(ctid.read_model(os.path.join(folder, FOLDER, b"mod\xe8le.json"))) \
        == ctid.model_to_json(model)


def test_a_python_error_naming_a_latin1_file_keeps_its_message(folder):
    missing = os.path.join(folder, b"absent\xe9.csv")
    with pytest.raises(Exception) as raised:
        ctid.read_csv(missing)
    assert "absent\\xe9.csv" in str(raised.value), repr(raised.value)
    with pytest.raises(Exception) as raised:
        ctid.write_csv(os.path.join(folder, DATA), ctid.read_csv(os.path.join(folder, DATA)))
    assert ESCAPED_DATA in str(raised.value), repr(raised.value)


def test_fit_many_runs_a_record_whose_path_is_not_utf8(cli, folder):
    """The plan escapes the path, and gives it in hex for the runner, which must fit the file
    (it used to run ctid fit on the escaped text: "File does not exist: caf\\xe9.csv")."""
    import ctid.batch
    with open(os.path.join(folder, b"spec.json"), "w") as f:
        f.write(json.dumps({"poles": 2, "zeros": 0}))
    out = os.fsdecode(os.path.join(folder, b"many"))
    rows = ctid.batch.fit_many(os.fsdecode(os.path.join(folder, b"caf\xe9.cs*")),
                               spec=os.fsdecode(os.path.join(folder, b"spec.json")),
                               out_dir=out, jobs=1, ctid_executable=cli)
    assert [(row["name"], row["status"]) for row in rows] == [("caf_", "ok")], rows
    assert rows[0]["data"].endswith(ESCAPED_DATA)
    tasks = ctid.batch.plan(os.fsdecode(os.path.join(folder, b"caf\xe9.cs*")),
                            spec=os.fsdecode(os.path.join(folder, b"spec.json")),
                            out_dir=out)
    assert os.fsencode(tasks[0]["args"][1]) == os.path.join(folder, DATA)
    assert tasks[0]["done"]


def test_summaries_on_stdout_name_the_file_escaped(cli, folder):
    fitted = _run(cli, folder, b"fit", DATA, b"--poles", b"2", b"--zeros", b"0")
    assert fitted.returncode == 0, fitted.stderr
    validated = _run(cli, folder, b"validate", b"m.json", DATA)
    assert validated.returncode == 0, validated.stderr
    for done in (fitted, validated):
        text = done.stdout.decode("utf-8")  # decodes: no byte that is not UTF-8
        assert f"on {ESCAPED_DATA} (N = 600" in text, text


def test_fit_many_on_a_list_of_records_refuses_a_path_that_is_not_utf8_by_name(cli, folder):
    """A list of records travels as a JSON manifest, which cannot hold such a path: one clear
    ValueError naming it and the ways that work (it was ctid's "malformed JSON ... surrogate"
    for a str path and a TypeError for a bytes path), and nothing written."""
    import ctid.batch
    out = os.fsdecode(os.path.join(folder, b"listed"))
    for path in (os.path.join(folder, DATA), os.fsdecode(os.path.join(folder, DATA))):
        with pytest.raises(ValueError) as raised:
            ctid.batch.fit_many([{"data": os.path.join(folder, b"good.csv")}, {"data": path}],
                                spec={"poles": 2, "zeros": 0}, out_dir=out, jobs=1,
                                ctid_executable=cli)
        message = str(raised.value)
        assert "record 2: data path '" in message and ESCAPED_DATA + "' is not UTF-8" in message
        assert "CSV manifest" in message
        assert not os.path.exists(out)
    rows = ctid.batch.fit_many([{"data": os.path.join(folder, b"good.csv")}],
                               spec={"poles": 2, "zeros": 0}, out_dir=out, jobs=1,
                               ctid_executable=cli)  # a bytes path that is UTF-8 is taken
    assert [row["status"] for row in rows] == ["ok"]
