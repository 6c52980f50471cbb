"""ctid on a Dask cluster: the Monte Carlo studies of González et al., Section 6, run case by
case on dask.distributed workers (docs/distributed.md).

    result = ctid.study(kind=ctid.StudyKind.closed_loop, runs=300, client=client)

Run r at size j of a study is a pure function of (options, j, r): ``ctid.run_study_case(options,
j, r)`` computes its records from the seed ``ctid.run_seed(options.seed, j, r)`` alone. A task
here is a chunk of consecutive runs at one size; each calls run_study_case on its worker and
returns the records (they pickle bit for bit). The client puts them back in the study's order
(size, run, estimator) and assembles the StudyResult with ``ctid.study_result_from_records``,
the function ``ctid.run_study`` assembles its own with. So the result is identical to the serial
one (every field equal, every double the same, NaNs in the same places) whatever the cluster,
the number of workers or the chunk size, and any task, or any single run, can be replayed alone.

Dask (Debian's python3-dask and python3-distributed) is imported only inside the functions that
need it: ``import ctid`` never does.

Command line (used by ``ctid study --scheduler ADDRESS``; also usable directly):

    /usr/bin/python3 -m ctid.distributed study OPTIONS.json --scheduler ADDRESS --out RECORDS.json
                                         [--chunk-runs N] [--quiet]

OPTIONS.json is a StudyOptions object as ctid.options_to_json writes it; ADDRESS a scheduler
address (tcp://host:8786) or ``env`` for $DASK_SCHEDULER_ADDRESS. RECORDS.json gets
{"type": "study_records", "version": 1, "records": [...]}: every record's fields, in the
study's order, finite doubles as JSON numbers (shortest text that reads back to the same
double) and non-finite ones as the strings "nan", "-nan", "inf", "-inf". Exit status 0 on
success, 2 for bad usage or input (one line on stderr), 1 otherwise.
"""

from __future__ import annotations

import math
import os
import sys

SCHEDULER_ENVIRONMENT_VARIABLE = "DASK_SCHEDULER_ADDRESS"
DEFAULT_CHUNK_RUNS = 25
RECORDS_DOCUMENT_TYPE = "study_records"


def client_from_address(address=None, **client_keywords):
    """A dask.distributed Client connected to the scheduler at ``address`` (``tcp://host:8786``,
    or anything dask.distributed.Client takes). ``None`` or ``"env"`` reads the address from
    $DASK_SCHEDULER_ADDRESS (ValueError if it is unset or empty). Further keywords go to
    Client (e.g. ``timeout="10s"``). The caller closes the client."""
    from dask.distributed import Client

    if address is None or address == "env":
        address = os.environ.get(SCHEDULER_ENVIRONMENT_VARIABLE, "").strip()
        if not address:
            raise ValueError(f"no scheduler address: {SCHEDULER_ENVIRONMENT_VARIABLE} is not set "
                             "(give an address such as tcp://host:8786)")
    return Client(address, **client_keywords)


def _study_options(function, options, option_keywords):
    from . import _ctid

    if options is not None and option_keywords:
        raise TypeError(f"{function}() takes either options=... or keyword options, not both")
    if options is None:
        options = _ctid.StudyOptions(**option_keywords)
    elif not isinstance(options, _ctid.StudyOptions):
        raise TypeError(f"{function}(): options must be a ctid.StudyOptions, not "
                        f"{type(options).__name__}")
    options.validate()
    return options


def study_chunks(options, chunk_runs=DEFAULT_CHUNK_RUNS):
    """The tasks of a study: (size_index, first_run, end_run) for runs [first_run, end_run) at
    one sample size, chunk_runs runs each (the last of a size may have fewer), in the study's
    order."""
    if isinstance(chunk_runs, bool) or not isinstance(chunk_runs, int) or chunk_runs < 1:
        raise ValueError(f"chunk_runs is {chunk_runs!r}; it must be an integer >= 1")
    return [(size_index, first, min(first + chunk_runs, options.runs))
            for size_index in range(options.sizes)
            for first in range(0, options.runs, chunk_runs)]


def run_study_chunk(options_json, size_index, first_run, end_run):
    """The records of runs [first_run, end_run) at size ``size_index`` (what one task computes
    on a worker): run_study_case for each run, in order. ``options_json`` is the StudyOptions as
    JSON text (ctid.options_to_json), so the task's key is the same for the same work."""
    import json

    from . import _ctid, options_from_json

    options = options_from_json("StudyOptions", json.loads(options_json))
    records = []
    for run_index in range(first_run, end_run):
        records.extend(_ctid.run_study_case(options, size_index, run_index))
    return records


def study(options=None, *, client=None, chunk_runs=DEFAULT_CHUNK_RUNS, progress=None,
          **option_keywords):
    """A Section 6 study, its cases run on a Dask cluster: the same StudyResult as
    ``ctid.run_study(options)`` (every field equal, every double identical, NaNs in the same
    places; note that the bound classes' ``==`` takes NaN != NaN in scalar fields, e.g. the
    predicted MSE of a study without covariance).

    options / option_keywords: a ctid.StudyOptions, or its fields as keywords (not both).
    client: None runs ``ctid.run_study(options)`` in this process (options.threads threads);
        a dask.distributed Client runs the cases on its cluster (options.threads is not used
        there: each task runs one case at a time, a worker runs as many tasks as it has
        threads); a cluster object (LocalCluster, dask-jobqueue's SLURMCluster, ...) or a
        string, a scheduler address with ``"env"`` meaning $DASK_SCHEDULER_ADDRESS, is
        connected to for this call and the connection closed afterwards.
    chunk_runs: runs per task (consecutive runs at one sample size). It changes the task count
        and overhead, never the result.
    progress: called as progress(finished_cases, total_cases) from this thread as tasks finish
        (with client=None only once, at the end).

    A failing task (e.g. a worker that cannot import ctid) raises its exception here after the
    other tasks are cancelled. Every task, and every run, is replayable alone:
    ``ctid.run_study_case(options, j, r)`` returns the records of run r at size j that the
    result holds.
    """
    from . import _ctid, options_to_json

    options = _study_options("study", options, option_keywords)
    chunks = study_chunks(options, chunk_runs)
    total = options.sizes * options.runs
    if client is None:
        result = _ctid.run_study(options)
        if progress is not None:
            progress(total, total)
        return result

    owned = None
    if isinstance(client, str):
        client = owned = client_from_address(client)
    elif not hasattr(client, "submit") and hasattr(client, "scheduler_address"):
        from dask.distributed import Client

        client = owned = Client(client)  # a cluster object (LocalCluster, SLURMCluster, ...)
    try:
        import json

        from dask.distributed import as_completed

        options_json = json.dumps(options_to_json(options), allow_nan=False)
        # Largest sizes first (the study's last chunks), as run_study hands out its cases: the
        # long runs start early and the workers finish together.
        futures = {}
        for chunk in reversed(chunks):
            futures[chunk] = client.submit(run_study_chunk, options_json, *chunk, pure=True)
        try:
            if progress is not None:
                finished = 0
                runs_of = {future.key: chunk[2] - chunk[1] for chunk, future in futures.items()}
                for future in as_completed(list(futures.values())):
                    if future.status == "error":
                        future.result()  # raises the task's exception
                    finished += runs_of[future.key]
                    progress(finished, total)
            gathered = client.gather([futures[chunk] for chunk in chunks])
        except BaseException:
            client.cancel(list(futures.values()))
            raise
        records = [record for chunk_records in gathered for record in chunk_records]
        return _ctid.study_result_from_records(options, records)
    finally:
        if owned is not None:
            owned.close()


# --- JSON of records (the CLI's route) -----------------------------------------------------


def _json_double(value):
    value = float(value)
    if math.isfinite(value):
        return value
    if math.isnan(value):
        return "-nan" if math.copysign(1.0, value) < 0 else "nan"
    return "inf" if value > 0 else "-inf"


def record_to_json(record):
    """A StudyRecord as a JSON-ready dict of its fields (enumerations by name, doubles as
    _json_double: finite ones as numbers, others as "nan", "-nan", "inf", "-inf")."""
    document = {}
    for name in type(record).fields:
        value = getattr(record, name)
        if hasattr(value, "shape"):
            document[name] = [_json_double(x) for x in value]
        elif hasattr(type(value), "__members__"):
            document[name] = value.name
        elif isinstance(value, float):
            document[name] = _json_double(value)
        else:
            document[name] = value
    return document


def records_document(records):
    """The study_records document of ``records`` (see the module's docstring)."""
    return {"type": RECORDS_DOCUMENT_TYPE, "version": 1,
            "records": [record_to_json(record) for record in records]}


def _write_text_atomically(path, text):
    temporary = f"{path}.tmp{os.getpid()}"
    try:
        with open(temporary, "w", encoding="utf-8") as out:
            out.write(text)
        os.replace(temporary, path)
    except BaseException:
        if os.path.exists(temporary):
            os.remove(temporary)
        raise


class _UsageError(Exception):
    pass


def _parse_arguments(arguments):
    import argparse

    class Parser(argparse.ArgumentParser):
        def error(self, message):
            raise _UsageError(message)

    parser = Parser(prog="python3 -m ctid.distributed",
                    description="Runs a ctid study on a Dask cluster (docs/distributed.md).")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("study", help="Run a Section 6 study; write its records as JSON.")
    run.add_argument("options", help="StudyOptions as JSON (ctid.options_to_json), a file")
    run.add_argument("--scheduler", required=True,
                     help="Scheduler address (tcp://host:8786), or env for "
                          f"${SCHEDULER_ENVIRONMENT_VARIABLE}")
    run.add_argument("--out", required=True, help="Where to write the study_records JSON")
    run.add_argument("--chunk-runs", type=int, default=DEFAULT_CHUNK_RUNS,
                     help=f"Runs per task (default {DEFAULT_CHUNK_RUNS})")
    run.add_argument("--quiet", "-q", action="store_true", help="No progress on stderr")
    return parser.parse_args(arguments)


def main(arguments=None):
    import json

    from . import InvalidArgument, options_from_json

    try:
        arguments = _parse_arguments(sys.argv[1:] if arguments is None else arguments)
        if arguments.chunk_runs < 1:
            raise _UsageError(f"--chunk-runs is {arguments.chunk_runs}; it must be >= 1")
        try:
            with open(arguments.options, encoding="utf-8") as source:
                text = source.read()
        except OSError as error:
            raise _UsageError(f"cannot read {arguments.options}: {error.strerror}") from None
        options = options_from_json("StudyOptions", text)
    except (_UsageError, InvalidArgument, ValueError) as error:
        print(f"python3 -m ctid.distributed: {error}", file=sys.stderr)
        return 2

    def report(finished, total):
        print(f"\rctid study: case {finished}/{total} ({100 * finished // total} %) on Dask",
              end="", file=sys.stderr, flush=True)

    try:
        client = client_from_address(arguments.scheduler, timeout="30s")
    except ValueError as error:
        print(f"python3 -m ctid.distributed: {error}", file=sys.stderr)
        return 2
    except Exception as error:  # OSError, TimeoutError: no scheduler there
        print(f"python3 -m ctid.distributed: cannot reach the Dask scheduler at "
              f"{arguments.scheduler}: {error}", file=sys.stderr)
        return 1
    try:
        show = not arguments.quiet and sys.stderr.isatty()
        result = study(options, client=client, chunk_runs=arguments.chunk_runs,
                       progress=report if show else None)
        if show:
            print("\r\033[K", end="", file=sys.stderr, flush=True)
        _write_text_atomically(arguments.out, json.dumps(records_document(result.records)))
    except Exception as error:
        print(f"python3 -m ctid.distributed: {type(error).__name__}: {error}", file=sys.stderr)
        return 1
    finally:
        client.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
