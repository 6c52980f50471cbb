"""The batch acceptance of issue 17: 200 simulated records of mixed structures, 10 of them
corrupted, fitted by ``ctid batch``, by ``ctid.batch.fit_many`` on threads and on a two-worker
Dask LocalCluster, and through ``ctid batch --scheduler``. Every good record's document must be
the bytes of its single ``ctid fit``, every bad record's message must reach the summary, a batch
killed midway must finish only the rest, and the Dask run must equal the serial one."""

import json
import os
import pathlib
import signal
import subprocess
import time

import pytest

import ctid.batch

ONE_MODE = {"type": "additive_model", "input_delay": 0.0, "submodels": [
    {"denominator_ascending": [1.0, 0.04, 0.04], "numerator_ascending": [2.0]}]}
TWO_MODES = {"type": "additive_model", "input_delay": 0.0, "submodels": [
    {"denominator_ascending": [1.0, 0.04, 0.04], "numerator_ascending": [2.0]},
    {"denominator_ascending": [1.0, 0.01, 0.0025], "numerator_ascending": [1.0]}]}

RECORDS = 200
CORRUPTED = {  # name -> file content: ten ways a record can be broken
    "bad_nan": "t,u,y\n0,1,0\n0.01,1,nan\n0.02,1,0.5\n",
    "bad_inf": "t,u,y\n0,1,0\n0.01,inf,0.1\n0.02,1,0.5\n",
    "bad_column": "t,u,z\n0,1,0\n0.01,1,0.2\n0.02,1,0.5\n",
    "bad_text": "t,u,y\n0,1,0\n0.01,one,0.2\n0.02,1,0.5\n",
    "bad_empty": "",
    "bad_header_only": "t,u,y\n",
    "bad_binary": "\x89PNG\r\n\x1a\n\x00\x01\x02\x03",
    "bad_ragged": "t,u,y\n0,1,0\n0.01,1\n0.02,1,0.5\n",
    "bad_time": "t,u,y\n0,1,0\n0.01,1,0.2\n0.5,1,0.5\n0.51,1,0.4\n",
}  # and one truncated copy of a good record, made in the fixture


def _run(cli, *args, check=True):
    completed = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True)
    if check:
        assert completed.returncode == 0, completed.stderr
    return completed


def _documents(folder):
    """name -> bytes of every record document (results and errors) in a batch folder."""
    return {p.name: p.read_bytes() for p in pathlib.Path(folder).glob("*.json")
            if p.name not in ("summary.json", "timings.json")}


def _without_seconds(rows):
    return [{key: value for key, value in row.items() if key != "seconds"} for row in rows]


@pytest.fixture(scope="module")
def batch(cli, tmp_path_factory):
    """The records, their manifest and the serial run (`ctid batch --jobs 1`)."""
    root = tmp_path_factory.mktemp("batch")
    records = root / "records"
    records.mkdir()
    (root / "one.json").write_text(json.dumps(ONE_MODE))
    (root / "two.json").write_text(json.dumps(TWO_MODES))
    entries = []
    good = RECORDS - len(CORRUPTED) - 1
    for k in range(good):
        kind = k % 4
        model = "two.json" if kind == 1 else "one.json"
        name = f"r{k:03d}"
        _run(cli, "simulate", "-m", root / model, "-e", "prbs", "-n", 1000, "-T", 0.01,
             "--seed", k + 1, "--snr", 30, "--noise-seed", k + 1, "-o", records / f"{name}.csv",
             "-q")
        entry = {"name": name, "data": f"records/{name}.csv"}
        if kind == 1:
            entry["modes"] = 2  # two modes
        elif kind == 2:
            entry.update({"modes": None, "poles": 2, "zeros": 1})  # unfactored 2/1
        elif kind == 3:
            entry["detrend"] = "linear"
        entries.append(entry)
    for name, content in CORRUPTED.items():
        (records / f"{name}.csv").write_bytes(content.encode("latin-1"))
        entries.append({"name": name, "data": f"records/{name}.csv"})
    (records / "bad_truncated.csv").write_bytes((records / "r000.csv").read_bytes()[:150])
    entries.append({"name": "bad_truncated", "data": "records/bad_truncated.csv"})
    manifest = root / "manifest.json"
    manifest.write_text(json.dumps({"spec": {"modes": 1}, "records": entries}, indent=1))
    serial = root / "serial"
    completed = _run(cli, "batch", manifest, "--out", serial, "--jobs", 1)
    return {"root": root, "manifest": manifest, "serial": serial, "names": [e["name"] for e in
            entries], "bad": list(CORRUPTED) + ["bad_truncated"], "stdout": completed.stdout}


@pytest.fixture(scope="module")
def dask_client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       host="127.0.0.1", dashboard_address=None)
    client = distributed.Client(cluster)
    yield client
    client.close()
    cluster.close()


def test_every_record_has_a_document_and_bad_ones_their_message(batch):
    assert batch["stdout"] == (f"ctid batch: {RECORDS - 10} ok, 0 no usable model, 10 failed; "
                               f"summary in {batch['serial'] / 'summary.csv'}\n")
    rows = json.loads((batch["serial"] / "summary.json").read_text())["records"]
    assert [row["name"] for row in rows] == batch["names"]
    by_name = {row["name"]: row for row in rows}
    for name in batch["bad"]:
        assert by_name[name]["status"] == "failed", name
        assert by_name[name]["message"].startswith("ctid fit: error: "), by_name[name]
        error = json.loads((batch["serial"] / f"{name}.error.json").read_text())
        assert error["message"] == by_name[name]["message"]
    assert "is not finite" in by_name["bad_nan"]["message"]
    assert "no column 'y'" in by_name["bad_column"]["message"]
    for name in batch["names"]:
        if name not in batch["bad"]:
            assert by_name[name]["status"] == "ok", by_name[name]
            assert by_name[name]["fit_percent"] > 80.0
    # The two-mode records (kind 1) carry both modes, with standard errors, in the summary.
    assert len(by_name["r001"]["modes"]) == 2
    assert by_name["r001"]["modes"][1]["frequency_hz"] == pytest.approx(20 / (2 * 3.14159265),
                                                                        rel=0.01)
    assert by_name["r001"]["modes"][1]["frequency_se_hz"] > 0
    assert by_name["r002"]["estimator"] == "srivc"
    header = (batch["serial"] / "summary.csv").read_text().splitlines()[0]
    assert header.endswith("mode2_damping,mode2_damping_se,seconds,message")


def test_good_documents_equal_their_single_fit(cli, batch, tmp_path):
    plan = json.loads(_run(cli, "batch", batch["manifest"], "--out", batch["serial"],
                           "--plan").stdout)
    assert all(task["done"] for task in plan)
    good = [task for task in plan if task["name"] not in batch["bad"]]
    for task in good[::9]:  # 21 records, every kind
        args = [tmp_path / f"{task['name']}.json" if word == task["output"] else word
                for word in task["args"]]
        single = _run(cli, *args, check=False)
        assert single.returncode == 0, single.stderr
        assert (tmp_path / f"{task['name']}.json").read_bytes() == \
            pathlib.Path(task["output"]).read_bytes(), task["name"]


def test_a_killed_batch_finishes_only_the_rest(cli, batch, tmp_path):
    out = tmp_path / "killed"
    process = subprocess.Popen([str(cli), "batch", str(batch["manifest"]), "--out", str(out),
                                "--jobs", "1", "-q"])
    deadline = time.monotonic() + 60
    while len(_documents(out)) < 40 and time.monotonic() < deadline:
        time.sleep(0.02)
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    before = {p.name: p.stat().st_mtime_ns for p in out.glob("*.json")
              if p.name not in ("summary.json", "timings.json")}
    assert 40 <= len(before) < RECORDS, "the batch was not killed midway"
    for name in before:  # documents are written whole (temporary + rename)
        json.loads((out / name).read_text())
    plan = json.loads(_run(cli, "batch", batch["manifest"], "--out", out, "--plan").stdout)
    assert sum(not task["done"] for task in plan) == RECORDS - len(before)

    time.sleep(0.05)  # beyond the file system's time stamp resolution
    _run(cli, "batch", batch["manifest"], "--out", out, "--jobs", 2, "-q")
    for name, mtime in before.items():
        assert (out / name).stat().st_mtime_ns == mtime, f"{name} was fitted again"
    assert _documents(out) == _documents(batch["serial"])


def test_fit_many_on_dask_equals_the_serial_batch(batch, dask_client, tmp_path):
    out = tmp_path / "dask"
    rows = ctid.batch.fit_many(batch["manifest"], out_dir=out, client=dask_client)
    assert [row["name"] for row in rows] == batch["names"]
    assert _documents(out) == _documents(batch["serial"])
    serial_rows = json.loads((batch["serial"] / "summary.json").read_text())["records"]
    assert _without_seconds(rows) == _without_seconds(serial_rows)
    assert all(isinstance(row["seconds"], float) for row in rows)


def test_the_scheduler_flag_runs_the_batch_on_the_cluster(cli, batch, dask_client, tmp_path):
    out = tmp_path / "scheduler"
    address = dask_client.scheduler.address
    completed = _run(cli, "batch", batch["manifest"], "--out", out, "--scheduler", address)
    assert f"on {address}" in completed.stdout
    assert _documents(out) == _documents(batch["serial"])


def test_fit_many_needs_no_ctid_binary(batch, tmp_path, monkeypatch):
    """Issue 32: the records run as python3 -m ctid fit, the package's own command line, so a
    machine with the package and no ctid binary anywhere gives the serial batch's bytes."""
    for variable in ("CTID_EXECUTABLE", "CTID_BUILD_DIR"):
        monkeypatch.delenv(variable, raising=False)
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    assert ctid.batch.find_executable() is None
    manifest = tmp_path / "some.json"
    original = json.loads(pathlib.Path(batch["manifest"]).read_text())
    records = original["records"]
    chosen = [dict(r, data=str(pathlib.Path(batch["root"]) / r["data"])) for r in records[:3]]
    chosen.append(next(dict(r, data=str(pathlib.Path(batch["root"]) / r["data"]))
                       for r in records if r["name"] == "bad_nan"))
    manifest.write_text(json.dumps({"spec": original.get("spec", {}), "records": chosen}))
    rows = ctid.batch.fit_many(manifest, out_dir=tmp_path / "no-binary", jobs=2)
    assert [row["status"] for row in rows] == ["ok", "ok", "ok", "failed"], rows
    assert "is not finite" in rows[3]["message"]
    serial = _documents(batch["serial"])
    for name, content in _documents(tmp_path / "no-binary").items():
        assert content == serial[name], name


def test_python_m_ctid_is_the_command_line(cli, batch, tmp_path):
    """python3 -m ctid ARGS runs the commands of the binary: the same document bytes, the same
    message and exit status for bad usage."""
    import sys
    data = pathlib.Path(batch["root"]) / "records" / "r001.csv"
    outputs = {}
    for label, command in (("binary", [str(cli)]), ("package", [sys.executable, "-m", "ctid"])):
        out = tmp_path / f"{label}.json"
        done = subprocess.run([*command, "fit", str(data), "--modes", "2", "-o", str(out), "-q"],
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        outputs[label] = out.read_bytes()
        bad = subprocess.run([*command, "fit", str(data), "--mdoes", "2"], capture_output=True,
                             text=True)
        outputs[label + " usage"] = (bad.returncode, bad.stderr)
    assert outputs["binary"] == outputs["package"]
    assert outputs["binary usage"] == outputs["package usage"]
    assert outputs["binary usage"][0] == 2 and "--modes" in outputs["binary usage"][1]
    # Its batch runs the records with python3 -m ctid (there is no ctid binary to start).
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"modes": 1}))
    out = tmp_path / "batch"
    done = subprocess.run([sys.executable, "-m", "ctid", "batch", "--glob",
                           str(pathlib.Path(batch["root"]) / "records" / "r00[04].csv"),
                           "--spec", str(spec), "--out", str(out), "-q"],
                          capture_output=True, text=True,
                          env=dict(os.environ, PATH=str(tmp_path / "empty")))
    assert done.returncode == 0, done.stderr
    serial = _documents(batch["serial"])
    assert _documents(out) == {name: serial[name] for name in ("r000.json", "r004.json")}


def test_fit_many_with_record_dicts_on_threads(cli, batch, tmp_path, monkeypatch):
    monkeypatch.chdir(batch["root"])
    records = [{"data": "records/r000.csv"}, {"name": "two", "data": "records/r001.csv",
                                              "modes": 2},
               {"data": "records/bad_nan.csv"}]
    rows = ctid.batch.fit_many(records, {"modes": 1}, out_dir=tmp_path / "dicts", jobs=2,
                               ctid_executable=cli)
    assert [row["status"] for row in rows] == ["ok", "ok", "failed"]
    assert "is not finite" in rows[2]["message"]
    # Relative paths are the caller's: the records were fitted from absolute paths.
    document = json.loads((tmp_path / "dicts" / "two.json").read_text())
    assert document["data"]["file"] == str(batch["root"] / "records" / "r001.csv")
    serial = json.loads((batch["serial"] / "r001.json").read_text())
    assert document["parameters"] == serial["parameters"]


def test_a_bad_manifest_is_one_clear_error(batch, tmp_path):
    manifest = tmp_path / "typo.json"
    manifest.write_text(json.dumps({"spec": {"mdoes": 1}, "records": [{"data": "x.csv"}]}))
    with pytest.raises(ValueError, match="field 'mdoes' is not a ctid fit flag; did you mean"):
        ctid.batch.fit_many(manifest, out_dir=tmp_path / "out", jobs=1)
    with pytest.raises(FileNotFoundError, match="ctid_executable"):
        ctid.batch.find_executable(tmp_path / "no-such-ctid")


def test_a_file_as_out_dir_and_a_bad_job_count_are_clear_errors(batch, tmp_path):
    # Issue 33: a raw FileExistsError, and jobs=-1 accepted where `ctid batch -j -1` is not.
    a_file = tmp_path / "results"
    a_file.write_text("keep")
    with pytest.raises(ValueError, match="is a file, not a folder"):
        ctid.batch.fit_many(batch["manifest"], out_dir=a_file, jobs=1)
    assert a_file.read_text() == "keep"
    for jobs in (-1, 0, 1.5, True):
        with pytest.raises(ValueError, match="give a whole number of at least 1"):
            ctid.batch.fit_many(batch["manifest"], out_dir=tmp_path / "out", jobs=jobs)
    assert not (tmp_path / "out").exists()


def test_a_task_that_cannot_run_becomes_its_error_document(tmp_path):
    task = {"name": "x", "args": ["fit", "x.csv"], "output": str(tmp_path / "x.json"),
            "error_output": str(tmp_path / "x.error.json")}
    outcome = ctid.batch.run_task(task, str(tmp_path / "no-such-ctid"), cwd=tmp_path)
    assert outcome["name"] == "x" and outcome["error"]["written"]
    error = json.loads((tmp_path / "x.error.json").read_text())
    assert error["record"] == "x" and error["exit_status"] == 1
    assert "no-such-ctid" in error["message"]


def test_python_m_ctid_batch_with_a_glob(cli, batch, tmp_path):
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"modes": 1}))
    out = tmp_path / "glob"
    completed = subprocess.run(
        [os.sys.executable, "-m", "ctid.batch", "--glob", str(batch["root"] / "records" /
                                                             "r00[0-3].csv"),
         "--spec", str(spec), "--out", str(out), "--jobs", "2", "--ctid", str(cli)],
        capture_output=True, text=True)
    assert completed.returncode == 0, completed.stderr
    assert completed.stdout == (f"ctid batch: 4 ok, 0 no usable model, 0 failed (locally); "
                                f"summary in {out / 'summary.csv'}\n")
    assert sorted(_documents(out)) == ["r000.json", "r001.json", "r002.json", "r003.json"]
    assert _documents(out)["r000.json"] == (batch["serial"] / "r000.json").read_bytes()
