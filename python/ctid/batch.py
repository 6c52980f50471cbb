"""Many ``ctid fit`` runs, locally or on a Dask cluster: the Python twin of ``ctid batch``.

    fit_many(records, spec=None, *, out_dir, client=None, jobs=None,
             ctid_executable=None, retry_failed=False, force=False,
             output_only=False) -> list[dict]

    /usr/bin/python3 -m ctid.batch MANIFEST --out DIR [--scheduler ADDRESS] [--jobs N]
                                   [--spec SPEC.json] [--glob PATTERN] [--retry-failed]
                                   [--force] [--strict] [--quiet] [--output-only]

With ``output_only`` (``--output-only``) every record runs ``ctid oma`` instead of ``ctid fit``,
the spec holding oma's flags (decision 0061); everything else is the same.

The manifest is read in one place, ctid's C++ command line, which this package holds
(decision 0052): ``ctid batch ... --plan``, run inside this process, gives the records' ``ctid
fit`` argument vectors. Each record then runs as its own process, ``python3 -m ctid fit ...``
(the same commands, bytes and exit statuses as the ``ctid`` binary, and a crash on one file
never ends the batch): one after another (``jobs=1``), on a local thread pool (``jobs>1``,
default every core), or as one Dask task per record (``client``, a ``distributed.Client``), the
worker reading the record itself. Workers therefore need this package and the files at the same
paths as the client (a shared file system) and run in the client's working directory, so
relative paths in the manifest mean the same everywhere. No ``ctid`` binary is needed. A record
that fails leaves ``OUT/<name>.error.json`` with its message; nothing a record does stops the
batch. A Dask cluster that loses its scheduler midway raises ``ClusterLost``
(``python3 -m ctid.batch``: one error line, exit 1); the finished records are kept and the next
run fits the rest. ``ctid batch ... --summarize``, also run inside this process, then writes
``summary.csv`` and ``summary.json``, whose rows are returned. The documents are the bytes a
single ``ctid fit DATA FLAGS -o OUT/<name>.json`` writes (docs/batch.md).

The records run ``python3 -m ctid fit`` with the interpreter running the record, unless an
executable is named: the ``ctid_executable`` argument, else ``$CTID_EXECUTABLE`` (``ctid batch
--scheduler`` sets it to itself).
"""

from __future__ import annotations

import argparse
import concurrent.futures
import itertools
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time
import uuid

__all__ = ["ClusterLost", "fit_many", "find_executable", "plan", "run_task"]

_SUMMARY_ROWS = "summary.json"
_TIMINGS = "timings.json"
_TEMPORARY_COUNTER = itertools.count()


class ClusterLost(ConnectionError):
    """The Dask cluster stopped running the batch (its scheduler lost, the tasks cancelled):
    the finished records are kept and running the batch again fits the rest."""


def find_executable(ctid_executable=None):
    """The ``ctid`` executable the records run: the ``ctid_executable`` argument, else
    ``$CTID_EXECUTABLE``; None when neither is given, meaning ``python3 -m ctid`` (this
    package's own command line). A named file that is not an executable raises
    FileNotFoundError naming where the name came from."""
    for label, given in (("ctid_executable", ctid_executable),
                         ("$CTID_EXECUTABLE", os.environ.get("CTID_EXECUTABLE"))):
        if given is None or given == "":
            continue
        path = pathlib.Path(given)
        if path.is_file() and os.access(path, os.X_OK):
            return str(path)
        # An explicit choice is not silently replaced.
        raise FileNotFoundError(f"the ctid command line was not found: {label} {path} is not "
                                "an executable file")
    return None


def _record_command(executable):
    """The argument vector before a record's ``fit ...`` words, and the environment to run it
    in: the named executable, or this interpreter with this package first on its path."""
    if executable is not None:
        return [executable], None
    package_parent = str(pathlib.Path(__file__).resolve().parents[1])
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [package_parent] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    return [sys.executable, "-m", "ctid"], env


def _invalid(message):
    try:
        from ctid import InvalidArgument
    except ImportError:  # the package's extension is not built: a plain ValueError
        InvalidArgument = ValueError
    return InvalidArgument(message)


def _last_line(text):
    lines = [line for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else ""


def _manifest_path(path, index):
    """A record's data path as the JSON manifest holds it: absolute, and text. A path whose
    bytes are not UTF-8 cannot be JSON text (ctid's reader refuses the surrogate escapes
    json.dumps would write), so it is refused here, naming the ways that do take it."""
    text = os.path.abspath(os.fsdecode(os.fspath(path)))
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        shown = os.fsencode(text).decode("utf-8", "backslashreplace")
        raise _invalid(f"record {index + 1}: data path '{shown}' is not UTF-8, which a list of "
                       "records (sent as a JSON manifest) cannot hold; give a CSV manifest "
                       "file or a glob pattern that names it") from None
    return text


def _source_arguments(records, spec, scratch, glob=False):
    """The ``ctid batch`` arguments naming the records: a manifest, or --glob, and --spec.
    A string that names no file and holds a wildcard is a glob pattern (``glob`` forces it)."""
    args = []
    if isinstance(records, (str, os.PathLike)):
        text = os.fspath(records)
        if glob or (not os.path.exists(text) and any(c in text for c in "*?[")):
            args += ["--glob", text]
        else:
            args.append(text)
    else:
        records = list(records)
        entries = []
        for record in records:
            if not isinstance(record, dict):
                raise _invalid(f"a record is a dict with 'data' and fit flags, not {record!r}")
            entry = dict(record)
            # The manifest is written in a scratch folder: relative paths are the caller's.
            data = entry.get("data")
            if isinstance(data, (str, bytes, os.PathLike)):
                entry["data"] = _manifest_path(data, len(entries))
            elif isinstance(data, (list, tuple)):
                entry["data"] = [_manifest_path(d, len(entries)) for d in data]
            entries.append(entry)
        manifest = pathlib.Path(scratch) / "manifest.json"
        manifest.write_text(json.dumps({"records": entries}))
        args.append(str(manifest))
    if spec is not None:
        if isinstance(spec, dict):
            spec_file = pathlib.Path(scratch) / "spec.json"
            spec_file.write_text(json.dumps(spec))
            args += ["--spec", str(spec_file)]
        else:
            args += ["--spec", os.fspath(spec)]
    return args


def _run_batch_command(args):
    """``ctid batch ARGS`` (--plan or --summarize) run inside this process (decision 0052)."""
    from . import _ctid

    status, out, err = _ctid._command_line_captured(
        ["batch", *[os.fsencode(arg) for arg in args]])
    completed = subprocess.CompletedProcess(["batch", *args], status,
                                            out.decode("utf-8", "surrogateescape"),
                                            err.decode("utf-8", "replace"))
    if completed.returncode == 2:
        raise _invalid(_last_line(completed.stderr))
    if completed.returncode not in (0, 1, 3) or (completed.returncode == 1 and
                                                  "ctid batch: error:" in completed.stderr):
        raise RuntimeError(_last_line(completed.stderr) or
                           f"ctid batch ended with exit status {completed.returncode}")
    return completed


def plan(records, spec=None, *, out_dir, retry_failed=False, force=False, output_only=False):
    """The tasks of a batch as ``ctid batch ... --plan`` gives them: dicts with name, data,
    args (after the executable), output, error_output and done (finished before)."""
    with tempfile.TemporaryDirectory(prefix="ctid-batch-") as scratch:
        args = _source_arguments(records, spec, scratch)
        args += ["--out", os.fspath(out_dir), "--plan"]
        if retry_failed:
            args.append("--retry-failed")
        if force:
            args.append("--force")
        if output_only:
            args.append("--output-only")
        completed = _run_batch_command(args)
    return _tasks_of(completed.stdout)


def _tasks_of(plan_text):
    """The tasks of a ``--plan`` document. A path that is not UTF-8 is escaped (\\xHH) in the
    document and also given in hex under "bytes": the task takes the exact path, as a str that
    os.fsencode turns back into those bytes (decision 0042)."""
    tasks = json.loads(plan_text)
    for task in tasks:
        exact = task.pop("bytes", None)
        if exact is not None:
            task["args"] = [os.fsdecode(bytes.fromhex(word)) for word in exact["args"]]
            task["output"] = os.fsdecode(bytes.fromhex(exact["output"]))
            task["error_output"] = os.fsdecode(bytes.fromhex(exact["error_output"]))
    return tasks


def _failure_message(stderr, exit_status, command="ctid fit"):
    """The message of a failed record (`command`: "ctid fit" or "ctid oma"), worded as ctid
    batch words it (batch_command.cc)."""
    last = ""
    error_line = ""
    for line in stderr.split("\n"):
        line = line.rstrip("\r")
        if line:
            last = line
        if line.startswith(f"{command}: error: "):
            error_line = line
    if error_line:
        return error_line
    if exit_status > 128:
        return (f"{command} was ended by signal {exit_status - 128}" +
                (f" ({last})" if last else ""))
    if last:
        return last
    return f"{command} ended with exit status {exit_status} and no message"


def _write_json_atomically(path, value):
    path = pathlib.Path(path)
    # Named as ctid's own temporaries, "<file>.tmp-<pid>-<n>": the leftover of a worker killed
    # mid-write is removed by the next `ctid batch` run on the folder (io::write_text_file).
    temporary = path.with_name(f"{path.name}.tmp-{os.getpid()}-{next(_TEMPORARY_COUNTER)}")
    try:
        temporary.write_text(json.dumps(value, indent=2, sort_keys=True, ensure_ascii=False) +
                             "\n", encoding="utf-8")
        os.replace(temporary, path)
    finally:
        if temporary.exists():
            temporary.unlink()


def _child_dies_with_parent():
    """A preexec_fn giving the ``ctid fit`` child SIGTERM when the thread that started it ends,
    as ``ctid batch`` does (batch_command.cc): a Dask worker killed mid-record takes its fit
    with it (ctid removes its temporary on SIGTERM) instead of leaving an orphan that races the
    record's rerun on another worker. None where prctl is not available."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        prctl = libc.prctl
    except (OSError, AttributeError):
        return None
    parent = os.getpid()

    def preexec():
        prctl(1, 15)  # PR_SET_PDEATHSIG, SIGTERM
        if os.getppid() != parent:  # the parent ended before prctl
            os._exit(127)

    return preexec


def run_task(task, executable=None, cwd=None):
    """Runs one record's ``ctid fit`` (in `cwd`) with `executable`, or ``python3 -m ctid``
    when it is None, and returns {"name", "seconds", "error"}:
    error None when the fit wrote its document, else the error document, which is also written
    to the task's error_output when possible. Never raises."""
    start = time.monotonic()
    error = None
    try:
        workdir = pathlib.Path(cwd) if cwd is not None else pathlib.Path.cwd()
        error_output = workdir / task["error_output"]
        if error_output.exists():
            error_output.unlink()  # a retried or forced record
        command, env = _record_command(executable)
        completed = subprocess.run([*command, *task["args"]], cwd=workdir, env=env,
                                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                   text=True, errors="replace",
                                   preexec_fn=_child_dies_with_parent())
        status = completed.returncode if completed.returncode >= 0 else 128 - completed.returncode
        wrote = (workdir / task["output"]).exists()
        if status not in (0, 3) or not wrote:
            record_command = f"ctid {task['args'][0]}"  # fit, or oma for output-only records
            message = (_failure_message(completed.stderr, status, record_command)
                       if wrote or status != 0 else f"{record_command} wrote no result document")
            error = {"type": "ctid_batch_error", "record": task["name"], "message": message,
                     "exit_status": status}
    except Exception as exc:  # noqa: BLE001 - a record's failure never stops the batch
        error = {"type": "ctid_batch_error", "record": task.get("name", "?"),
                 "message": f"ctid.batch: {type(exc).__name__}: {exc}", "exit_status": 1}
    seconds = time.monotonic() - start
    if error is not None:
        try:
            _write_json_atomically(pathlib.Path(cwd or ".") / task["error_output"], error)
            written = True
        except Exception:  # noqa: BLE001 - the client writes it instead
            written = False
        error = dict(error, written=written)
    return {"name": task.get("name"), "seconds": seconds, "error": error}


def _record_outcomes(outcomes, tasks, out_dir):
    """Error documents the workers could not write, and the records' times (timings.json,
    which the summary's seconds column reads)."""
    by_name = {task["name"]: task for task in tasks}
    for outcome in outcomes:
        error = outcome.get("error")
        if error is not None and not error.get("written", False):
            document = {key: value for key, value in error.items() if key != "written"}
            _write_json_atomically(by_name[outcome["name"]]["error_output"], document)
    timings_file = pathlib.Path(out_dir) / _TIMINGS
    timings = {}
    if timings_file.exists():
        try:
            timings = json.loads(timings_file.read_text())
        except (OSError, ValueError):
            timings = {}
    if not isinstance(timings, dict):
        timings = {}
    for outcome in outcomes:
        if outcome["seconds"] == outcome["seconds"]:  # NaN (a failed Dask task) is not JSON
            timings[outcome["name"]] = outcome["seconds"]
    if outcomes:
        _write_json_atomically(timings_file, timings)


def _is_cluster_loss(exc, future):
    """True when a Dask future failed because the cluster stopped running it (scheduler lost,
    task cancelled, connection closed), not because of its record: run_task never raises, so
    the only record-made failure is KilledWorker (the record's task ended every worker that
    tried it)."""
    if type(exc).__name__ == "KilledWorker":
        return False
    return (getattr(future, "status", None) == "cancelled" or
            isinstance(exc, (concurrent.futures.CancelledError, OSError, TimeoutError)) or
            type(exc).__name__ in ("CancelledError", "CommClosedError", "FutureCancelledError"))


def _run_on_dask(tasks, executable, cwd, client):
    """The outcomes of the records the cluster finished, and the ClusterLost error naming the
    others when the cluster stopped running them (None when every record ran)."""
    keys = [f"ctid-fit-{task['name']}-{uuid.uuid4().hex[:8]}" for task in tasks]
    futures = client.map(run_task, tasks, [executable] * len(tasks), [cwd] * len(tasks),
                         key=keys, pure=False)
    outcomes = []
    lost = []
    for task, future in zip(tasks, futures):
        try:
            outcomes.append(future.result())
        except Exception as exc:  # noqa: BLE001 - a worker or the scheduler lost mid-task
            if _is_cluster_loss(exc, future):
                lost.append((task, exc))
                continue
            outcomes.append({"name": task["name"], "seconds": float("nan"), "error": {
                "type": "ctid_batch_error", "record": task["name"],
                "message": f"ctid.batch: the Dask task failed: {type(exc).__name__}: {exc}",
                "exit_status": 1, "written": False}})
    if not lost:
        return outcomes, None
    try:
        address = client.scheduler.address
    except AttributeError:
        address = "?"
    reason = f"{type(lost[0][1]).__name__}: {lost[0][1]}".rstrip(": ")
    connected = getattr(client, "status", "running") == "running"
    what = ("the Dask tasks were cancelled" if connected else
            f"the connection to the Dask scheduler at {address} was lost")
    return outcomes, ClusterLost(
        f"{what} ({reason}) with {len(lost)} of {len(tasks)} records not done; the "
        f"{len(outcomes)} finished are kept: run the batch again to fit the rest")


def _run_all(tasks, executable, client, jobs):
    """The records' outcomes, and a ClusterLost error when a Dask cluster stopped midway."""
    cwd = os.getcwd()
    if client is not None:
        return _run_on_dask(tasks, executable, cwd, client)
    workers = jobs if jobs is not None and jobs > 0 else (os.cpu_count() or 1)
    if workers == 1:
        return [run_task(task, executable, cwd) for task in tasks], None
    with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(lambda task: run_task(task, executable, cwd), tasks)), None


def _batch(records, spec, out_dir, client, jobs, ctid_executable, retry_failed, force, strict,
           glob=False, output_only=False):
    executable = find_executable(ctid_executable)
    out_dir = os.fspath(out_dir)
    # The same rules as `ctid batch`, said before any work: a file is not a folder, and a job
    # count is at least 1 (issue 33).
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise ValueError(f"out_dir {out_dir!r} is a file, not a folder; name a folder for the "
                         "results")
    if jobs is not None and (isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1):
        raise ValueError(f"jobs is {jobs!r}; give a whole number of at least 1 (or None for "
                         "every core)")
    with tempfile.TemporaryDirectory(prefix="ctid-batch-") as scratch:
        source = _source_arguments(records, spec, scratch, glob)
        if output_only:  # the records run ctid oma, and the spec is checked against its flags
            source.append("--output-only")
        flags = (["--retry-failed"] if retry_failed else []) + (["--force"] if force else [])
        planned = _tasks_of(_run_batch_command([*source, "--out", out_dir, "--plan", *flags]).stdout)
        os.makedirs(out_dir, exist_ok=True)
        pending = [task for task in planned if not task["done"]]
        outcomes, lost = _run_all(pending, executable, client, jobs)
        _record_outcomes(outcomes, pending, out_dir)
        if lost is not None:  # the finished records are recorded; the rest stay to be run
            raise lost
        summarize = [*source, "--out", out_dir, "--summarize", "--quiet"]
        if strict:
            summarize.append("--strict")
        completed = _run_batch_command(summarize)
    rows = json.loads((pathlib.Path(out_dir) / _SUMMARY_ROWS).read_text())["records"]
    return rows, completed.returncode


def fit_many(records, spec=None, *, out_dir, client=None, jobs=None, ctid_executable=None,
             retry_failed=False, force=False, output_only=False):
    """Fits every record with ``ctid fit`` and returns the summary rows (dicts: name, data,
    status ok | no_usable_model | failed, usable, fit_percent, estimator, modes, seconds,
    message).

    records: a manifest file (JSON or CSV, as ``ctid batch`` reads), a glob pattern, or a list
    of dicts {"name" (optional), "data": path, fit flags...}; relative paths are the current
    directory's. spec: fit flags shared by every record (a dict or a JSON file). client: a
    ``distributed.Client`` to run the records on; else ``jobs`` local threads (default every
    core; 1 runs them one after another). Finished records in out_dir are skipped unless
    ``force``; failed ones are run again with ``retry_failed``. output_only: records without a
    measured input; each runs ``ctid oma`` with oma's flags (the estimator column is the
    method, the modes are the output-only modes).

    A worker lost mid-record is Dask's to handle (the record runs again elsewhere; its fit
    ends with the worker). A cluster that stops running the batch (its scheduler lost) raises
    ClusterLost (a ConnectionError) once the finished records are recorded; the others have no
    document, so calling fit_many again fits only them.
    """
    rows, _ = _batch(records, spec, out_dir, client, jobs, ctid_executable, retry_failed, force,
                     strict=False, output_only=output_only)
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="python3 -m ctid.batch",
        description="Run ctid fit on the records of a manifest, locally or on a Dask cluster.")
    parser.add_argument("manifest", nargs="?", help="manifest (JSON or CSV)")
    parser.add_argument("--glob", help="fit every file matching this pattern with --spec")
    parser.add_argument("--spec", help="JSON object of ctid fit flags shared by every record")
    parser.add_argument("--out", "-o", required=True, help="folder for the results")
    parser.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://host:8786")
    parser.add_argument("--connect-timeout", type=float, default=30.0, metavar="SECONDS",
                        help="how long to try to reach --scheduler before giving up (default 30)")
    parser.add_argument("--jobs", "-j", type=int, default=None,
                        help="local threads when no scheduler is given (default: every core)")
    parser.add_argument("--retry-failed", action="store_true")
    parser.add_argument("--force", action="store_true")
    parser.add_argument("--strict", action="store_true")
    parser.add_argument("--quiet", "-q", action="store_true")
    parser.add_argument("--output-only", action="store_true",
                        help="records without a measured input: each runs ctid oma")
    parser.add_argument("--ctid", dest="ctid_executable",
                        help="a ctid executable for the records (default: python3 -m ctid)")
    options = parser.parse_args(argv)
    if (options.manifest is None) == (options.glob is None):
        print("ctid.batch: error: give a manifest or --glob PATTERN, not both", file=sys.stderr)
        return 2
    if not options.connect_timeout > 0:  # also refuses nan
        print(f"ctid.batch: error: --connect-timeout is {options.connect_timeout}; give a "
              "number of seconds above 0", file=sys.stderr)
        return 2
    records = options.manifest if options.manifest is not None else options.glob
    client = None
    try:
        if options.scheduler:
            try:
                from distributed import Client
            except ImportError:
                print("ctid.batch: error: --scheduler needs the Python package distributed "
                      "(dask.distributed)", file=sys.stderr)
                return 1
            try:
                client = Client(options.scheduler, timeout=f"{options.connect_timeout}s")
            except Exception as exc:  # noqa: BLE001 - one line, exit 1
                print(f"ctid.batch: error: cannot reach the Dask scheduler at "
                      f"{options.scheduler}: {exc}", file=sys.stderr)
                return 1
        rows, status = _batch(records, options.spec, options.out, client, options.jobs,
                              options.ctid_executable, options.retry_failed, options.force,
                              options.strict, glob=options.glob is not None,
                              output_only=options.output_only)
    except ValueError as exc:
        print(f"ctid.batch: error: {exc}", file=sys.stderr)
        return 2
    except (OSError, RuntimeError) as exc:
        print(f"ctid.batch: error: {exc}", file=sys.stderr)
        return 1
    finally:
        if client is not None:
            client.close()
    if not options.quiet:
        counts = {status_name: sum(1 for row in rows if row["status"] == status_name)
                  for status_name in ("ok", "no_usable_model", "failed")}
        where = "on " + options.scheduler if options.scheduler else "locally"
        print(f"ctid batch: {counts['ok']} ok, {counts['no_usable_model']} no usable model, "
              f"{counts['failed']} failed ({where}); summary in "
              f"{os.path.join(options.out, 'summary.csv')}")
    return status


if __name__ == "__main__":
    sys.exit(main())
