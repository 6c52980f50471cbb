"""ctid.study on a dask.distributed LocalCluster (two worker processes on the loopback address,
no other network): the records and the MSE table equal the serial ctid.run_study bit for bit,
whatever the chunk size; one run replays alone; the CLI's route (python -m ctid.distributed)
writes the same records as JSON (docs/distributed.md)."""

import json
import math
import os
import pickle
import subprocess
import sys

import numpy as np
import pytest

import ctid
import ctid.distributed as distributed

distributed_module = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def cluster():
    from dask.distributed import LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address=None)
    yield cluster
    cluster.close()


@pytest.fixture(scope="module")
def client(cluster):
    from dask.distributed import Client

    client = Client(cluster)
    yield client
    client.close()


OPEN_LOOP = dict(kind=ctid.StudyKind.open_loop, runs=24, sizes=2, min_samples=300,
                 max_samples=600, seed=11, threads=1, compute_covariance=False)
CLOSED_LOOP = dict(kind=ctid.StudyKind.closed_loop, runs=40, sizes=3, min_samples=150,
                   max_samples=600, seed=5, threads=1)


@pytest.fixture(scope="module", params=["open_loop", "closed_loop"])
def serial(request):
    keywords = OPEN_LOOP if request.param == "open_loop" else CLOSED_LOOP
    options = ctid.StudyOptions(**keywords)
    return options, ctid.run_study(options)


def assert_identical_records(got, expected):
    assert len(got) == len(expected)
    for a, b in zip(got, expected):
        key = (a.size_index, a.run_index, a.estimator)
        assert key == (b.size_index, b.run_index, b.estimator)
        assert (a.samples, a.seed, a.termination, a.iterations, a.valid, a.error) == (
            b.samples, b.seed, b.termination, b.iterations, b.valid, b.error), key
        for name in ("estimate", "standard_error"):
            x, y = getattr(a, name), getattr(b, name)
            assert x.shape == y.shape, (key, name)
            assert np.array_equal(np.isnan(x), np.isnan(y)), (key, name)
            finite = ~np.isnan(x)
            assert (x[finite] == y[finite]).all(), (key, name)


def same_value(a, b):
    """== for numbers, except that NaN matches NaN (the bound classes' == compares scalar
    fields with Python's ==, where NaN != NaN: an MseRow without covariance is not == itself)."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def assert_identical_rows(got, expected):
    assert len(got) == len(expected)
    for a, b in zip(got, expected):
        for name in type(a).fields:
            assert same_value(getattr(a, name), getattr(b, name)), (a, b, name)


def assert_identical_results(got, expected):
    assert_identical_records(got.records, expected.records)
    assert_identical_rows(got.mse, expected.mse)
    assert got.sample_sizes == expected.sample_sizes
    assert got.parameter_names == expected.parameter_names
    assert (got.true_parameters == expected.true_parameters).all()
    assert got.options == expected.options


def test_cluster_study_equals_serial_bit_for_bit(serial, client):
    options, expected = serial
    got = ctid.study(options, client=client, chunk_runs=7)
    assert_identical_results(got, expected)


def test_the_small_studies_exercise_nans_and_several_estimators(serial):
    options, expected = serial
    assert len(options.active_estimators()) >= 2
    assert len(expected.records) == options.sizes * options.runs * len(
        options.active_estimators())
    if not options.compute_covariance:
        assert all(np.isnan(r.standard_error).all() for r in expected.records)
        assert all(math.isnan(row.predicted_mean_squared_error) for row in expected.mse)
    assert any(r.valid for r in expected.records)


def test_chunk_size_does_not_change_the_result(serial, client):
    options, expected = serial
    one_run_each = ctid.study(options, client=client, chunk_runs=1)
    whole_sizes = ctid.study(options, client=client, chunk_runs=options.runs + 5)
    assert_identical_results(one_run_each, expected)
    assert_identical_results(whole_sizes, expected)


def test_one_run_replayed_alone_equals_its_records(serial):
    options, expected = serial
    size_index, run_index = options.sizes - 1, options.runs // 2
    replay = ctid.run_study_case(options, size_index, run_index)
    in_study = [r for r in expected.records
                if (r.size_index, r.run_index) == (size_index, run_index)]
    assert_identical_records(replay, in_study)
    assert replay[0].seed == ctid.run_seed(options.seed, size_index, run_index)


def test_one_task_replayed_alone_equals_its_records(serial):
    options, expected = serial
    chunk = distributed.study_chunks(options, 7)[1]
    text = json.dumps(ctid.options_to_json(options))
    replay = distributed.run_study_chunk(text, *chunk)
    size_index, first, end = chunk
    in_study = [r for r in expected.records
                if r.size_index == size_index and first <= r.run_index < end]
    assert_identical_records(replay, in_study)


def test_progress_counts_every_case_once(client):
    options = ctid.StudyOptions(**dict(CLOSED_LOOP, runs=6, sizes=2))
    seen = []
    ctid.study(options, client=client, chunk_runs=4, progress=lambda done, total: seen.append(
        (done, total)))
    assert seen[-1] == (12, 12)
    assert [done for done, _ in seen] == sorted(done for done, _ in seen)
    assert len(seen) == 4  # chunks of 4 + 2 runs at each of two sizes


def test_serial_path_and_keywords(serial):
    options, expected = serial
    keywords = OPEN_LOOP if options.kind == ctid.StudyKind.open_loop else CLOSED_LOOP
    assert_identical_results(ctid.study(**keywords), expected)
    with pytest.raises(TypeError, match="not both"):
        ctid.study(options, runs=3)
    with pytest.raises(ValueError, match="chunk_runs"):
        ctid.study(options, chunk_runs=0)


def test_address_string_and_environment_variable(cluster, monkeypatch):
    options = ctid.StudyOptions(**dict(CLOSED_LOOP, runs=5, sizes=1))
    expected = ctid.run_study(options)
    assert ctid.study(options, client=cluster.scheduler_address) == expected
    assert ctid.study(options, client=cluster) == expected
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", cluster.scheduler_address)
    assert ctid.study(options, client="env") == expected
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS")
    with pytest.raises(ValueError, match="DASK_SCHEDULER_ADDRESS"):
        ctid.study(options, client="env")


def test_records_and_options_pickle_bit_for_bit(serial):
    options, expected = serial
    assert pickle.loads(pickle.dumps(options)) == options
    again = pickle.loads(pickle.dumps(expected))
    assert_identical_results(again, expected)
    negative_nan = -np.abs(np.float64("nan"))
    assert math.copysign(1.0, negative_nan) < 0
    assert distributed._json_double(negative_nan) == "-nan"


def test_records_out_of_order_are_refused(serial):
    options, expected = serial
    records = list(expected.records)
    records[0], records[1] = records[1], records[0]
    with pytest.raises(ctid.InvalidArgument, match=r"records\[0\]"):
        ctid.study_result_from_records(options, records)
    with pytest.raises(ctid.InvalidArgument, match="records"):
        ctid.study_result_from_records(options, records[:-1])


def test_command_line_route_writes_the_serial_records(cluster, tmp_path):
    options = ctid.StudyOptions(**dict(CLOSED_LOOP, runs=6, sizes=2))
    expected = ctid.run_study(options)
    (tmp_path / "options.json").write_text(json.dumps(ctid.options_to_json(options)))
    out = tmp_path / "records.json"
    status = distributed.main(["study", str(tmp_path / "options.json"), "--scheduler",
                               cluster.scheduler_address, "--out", str(out), "--chunk-runs", "5",
                               "--quiet"])
    assert status == 0
    document = json.loads(out.read_text())
    assert document["type"] == "study_records"
    assert document["records"] == [distributed.record_to_json(r) for r in expected.records]
    first = document["records"][0]
    assert np.array(first["estimate"], dtype=float).tolist() == expected.records[0].estimate.tolist()


def test_command_line_route_refuses_bad_input(tmp_path, capsys):
    (tmp_path / "bad.json").write_text('{"runs": 0}')
    status = distributed.main(["study", str(tmp_path / "bad.json"), "--scheduler", "env",
                               "--out", str(tmp_path / "r.json")])
    assert status == 2
    assert "runs" in capsys.readouterr().err
    assert not (tmp_path / "r.json").exists()


def test_import_ctid_does_not_import_dask():
    code = "import sys, ctid; print('dask' in sys.modules or 'distributed' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=dict(os.environ), check=True).stdout
    assert out.strip() == "False"


CLI_STUDY = ["study", "closed-loop", "--runs", "8", "--sizes", "2", "--min-samples", "300",
             "--max-samples", "600", "--seed", "3", "--no-plot", "-q"]


def test_cli_scheduler_writes_the_files_of_the_local_study(cli, cluster, tmp_path):
    local = subprocess.run([str(cli), *CLI_STUDY, "-o", str(tmp_path / "local"), "-j", "1"],
                           capture_output=True, text=True)
    assert local.returncode == 0, local.stderr
    remote = subprocess.run([str(cli), *CLI_STUDY, "-o", str(tmp_path / "dask"), "--scheduler",
                             cluster.scheduler_address], capture_output=True, text=True)
    assert remote.returncode == 0, remote.stderr
    for name in ("runs.csv", "mse.csv", "trends.csv", "summary.json"):
        assert (tmp_path / "dask" / name).read_bytes() == (tmp_path / "local" / name).read_bytes()


def test_cli_scheduler_env_needs_the_variable(cli, tmp_path):
    environment = {k: v for k, v in os.environ.items() if k != "DASK_SCHEDULER_ADDRESS"}
    run = subprocess.run([str(cli), *CLI_STUDY, "-o", str(tmp_path), "--scheduler", "env"],
                         capture_output=True, text=True, env=environment)
    assert run.returncode == 2
    assert "DASK_SCHEDULER_ADDRESS is not set" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "runs.csv").exists()
