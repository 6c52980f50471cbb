"""Issue 33: the command line of the Dask runner, ``python3 -m ctid.batch --scheduler``, on a
scheduler and a worker that the test starts as processes. Its documents must be the serial
``ctid batch``'s byte for byte; a scheduler that cannot be reached must be one line and exit 1
within a bounded time, with nothing written. Three records of a few tenths of a second each
keep the test within seconds."""

import json
import os
import pathlib
import signal
import socket
import subprocess
import sys
import time

import pytest

distributed = pytest.importorskip("distributed")

ROOT = pathlib.Path(__file__).resolve().parents[2]
ONE_MODE = {"type": "additive_model", "input_delay": 0.0, "submodels": [
    {"denominator_ascending": [1.0, 0.04, 0.04], "numerator_ascending": [2.0]}]}


def _documents(folder):
    """name -> bytes of every record document (results and errors) in a batch folder."""
    return {p.name: p.read_bytes() for p in pathlib.Path(folder).glob("*.json")
            if p.name not in ("summary.json", "timings.json")}


def _module_command(*args):
    """`python3 -m ctid.batch ARGS` with the package this test imports."""
    import ctid
    package_parent = str(pathlib.Path(ctid.__file__).resolve().parents[1])
    paths = [package_parent, str(ROOT / "python"), os.environ.get("PYTHONPATH", "")]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in paths if p))
    return [sys.executable, "-m", "ctid.batch", *map(str, args)], env


@pytest.fixture(scope="module")
def records(cli, tmp_path_factory):
    """Three seeded records, their manifest (one record names a missing file, so that an error
    document is compared too) and the serial batch's documents."""
    root = tmp_path_factory.mktemp("scheduler_cli")
    (root / "one.json").write_text(json.dumps(ONE_MODE))
    entries = []
    for k in range(3):
        name = f"r{k}"
        subprocess.run([str(cli), "simulate", "-m", str(root / "one.json"), "-e", "prbs", "-n",
                        "2000", "-T", "0.01", "--seed", str(k + 1), "--snr", "30",
                        "--noise-seed", str(k + 1), "-o", str(root / f"{name}.csv"), "-q"],
                       check=True)
        entries.append({"name": name, "data": f"{name}.csv"})
    entries.append({"name": "missing", "data": "missing.csv"})
    manifest = root / "manifest.json"
    manifest.write_text(json.dumps({"spec": {"modes": 1}, "records": entries}))
    serial = root / "serial"
    completed = subprocess.run([str(cli), "batch", str(manifest), "--out", str(serial), "-q"],
                               capture_output=True, text=True)
    assert completed.returncode == 0, completed.stderr  # a failed record is in the summary
    documents = _documents(serial)
    assert sorted(documents) == ["missing.error.json", "r0.json", "r1.json", "r2.json"]
    return {"manifest": manifest, "documents": documents}


@pytest.fixture
def scheduler_address(tmp_path):
    """A scheduler and one single-thread worker started as processes; their process groups
    are ended at teardown."""
    scheduler_file = tmp_path / "scheduler.json"
    started = []

    def start(*args):
        process = subprocess.Popen([sys.executable, *args], stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL, start_new_session=True)
        started.append(process)
        return process

    try:
        start("-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
              "--no-dashboard", "--scheduler-file", str(scheduler_file))
        deadline = time.monotonic() + 30
        while not scheduler_file.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert scheduler_file.exists(), "the scheduler did not start within 30 s"
        start("-m", "distributed.cli.dask_worker", "--scheduler-file", str(scheduler_file),
              "--nworkers", "1", "--nthreads", "1", "--no-dashboard", "--death-timeout", "20")
        yield json.loads(scheduler_file.read_text())["address"]
    finally:
        for process in started:
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGKILL)
            process.wait()


def test_the_module_on_a_scheduler_writes_the_serial_batchs_documents(cli, records,
                                                                       scheduler_address,
                                                                       tmp_path):
    out = tmp_path / "out"
    command, env = _module_command(records["manifest"], "--out", out, "--scheduler",
                                   scheduler_address, "--ctid", cli, "--quiet")
    completed = subprocess.run(command, env=env, capture_output=True, text=True, timeout=120)
    assert completed.returncode == 0, completed.stderr  # as the serial batch's
    assert _documents(out) == records["documents"]
    rows = json.loads((out / "summary.json").read_text())["records"]
    assert [(row["name"], row["status"]) for row in rows] == [
        ("r0", "ok"), ("r1", "ok"), ("r2", "ok"), ("missing", "failed")]
    assert sorted(p.name for p in out.iterdir() if ".tmp" in p.name) == []


def _closed_port():
    """A local TCP port nothing listens on (bound, then released)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_a_scheduler_that_cannot_be_reached_is_one_line_in_bounded_time(cli, records,
                                                                        tmp_path):
    address = f"tcp://127.0.0.1:{_closed_port()}"
    out = tmp_path / "out"
    command, env = _module_command(records["manifest"], "--out", out, "--scheduler", address,
                                   "--connect-timeout", "2", "--ctid", cli)
    started = time.monotonic()
    completed = subprocess.run(command, env=env, capture_output=True, text=True, timeout=60)
    elapsed = time.monotonic() - started
    assert completed.returncode == 1, completed.stderr
    lines = completed.stderr.strip().splitlines()
    assert len(lines) == 1, completed.stderr
    assert lines[0].startswith(f"ctid.batch: error: cannot reach the Dask scheduler at {address}")
    assert completed.stdout == ""
    assert elapsed < 20, f"{elapsed:.1f} s to give up on a 2 s timeout"
    assert not out.exists() or list(out.iterdir()) == []  # nothing planned was written


def test_a_timeout_that_is_not_a_positive_number_is_refused(cli, records, tmp_path):
    for bad in ("0", "-1", "nan"):
        command, env = _module_command(records["manifest"], "--out", tmp_path / "out",
                                       "--scheduler", "tcp://127.0.0.1:1",
                                       "--connect-timeout", bad, "--ctid", cli)
        completed = subprocess.run(command, env=env, capture_output=True, text=True,
                                   timeout=60)
        assert completed.returncode == 2, completed.stderr
        assert f"--connect-timeout is {float(bad)}" in completed.stderr
        assert not (tmp_path / "out").exists()
