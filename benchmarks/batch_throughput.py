#!/usr/bin/env python3
"""Issue 17's throughput table: records per second of a batch of `ctid fit` runs, serial
(`ctid batch --jobs 1`), on local threads (`ctid batch --jobs W`) and on a W-worker Dask
LocalCluster (`ctid.batch.fit_many(..., client=...)`, one process per worker, one thread
each, loopback), with the scaling efficiency = speed-up over serial / workers.

The records are `ctid simulate` runs of two systems (one mode; two modes), N samples each,
fitted with a mix of structures (--modes 1, --modes 2, unfactored 2/1, --detrend linear), as
in python/tests/test_batch.py. Every run starts from an empty output folder; the time
includes writing the documents and the summary (and, for Dask, shipping the tasks, not
starting the cluster). The Dask documents are checked to equal the serial ones.

Usage (from the source tree, after a build):
    PYTHONPATH=build/python /usr/bin/python3 benchmarks/batch_throughput.py \
        [--build build] [--records 200] [--samples 2000] [--workers 2] [--repeat 2]
"""

import argparse
import json
import pathlib
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]

ONE_MODE = {"type": "additive_model", "input_delay": 0.0, "submodels": [
    {"denominator_ascending": [1.0, 0.04, 0.04], "numerator_ascending": [2.0]}]}
TWO_MODES = {"type": "additive_model", "input_delay": 0.0, "submodels": [
    {"denominator_ascending": [1.0, 0.04, 0.04], "numerator_ascending": [2.0]},
    {"denominator_ascending": [1.0, 0.01, 0.0025], "numerator_ascending": [1.0]}]}


def make_records(cli, folder, records, samples):
    (folder / "one.json").write_text(json.dumps(ONE_MODE))
    (folder / "two.json").write_text(json.dumps(TWO_MODES))
    entries = []
    for k in range(records):
        kind = k % 4
        name = f"r{k:04d}"
        subprocess.run([cli, "simulate", "-m", str(folder / ("two.json" if kind == 1 else
                                                             "one.json")),
                        "-e", "prbs", "-n", str(samples), "-T", "0.01", "--seed", str(k + 1),
                        "--snr", "30", "--noise-seed", str(k + 1), "-o",
                        str(folder / f"{name}.csv"), "-q"], check=True)
        entry = {"name": name, "data": f"{name}.csv"}
        if kind == 1:
            entry["modes"] = 2
        elif kind == 2:
            entry.update({"modes": None, "poles": 2, "zeros": 1})
        elif kind == 3:
            entry["detrend"] = "linear"
        entries.append(entry)
    manifest = folder / "manifest.json"
    manifest.write_text(json.dumps({"spec": {"modes": 1}, "records": entries}))
    return manifest


def documents(folder):
    return {p.name: p.read_bytes() for p in folder.glob("*.json")
            if p.name not in ("summary.json", "timings.json")}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", default=str(ROOT / "build"))
    parser.add_argument("--records", type=int, default=200)
    parser.add_argument("--samples", type=int, default=2000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=2)
    options = parser.parse_args()
    cli = str(pathlib.Path(options.build) / "apps" / "ctid" / "ctid")
    import ctid.batch
    from distributed import Client, LocalCluster

    with tempfile.TemporaryDirectory(prefix="ctid-batch-bench-") as scratch:
        scratch = pathlib.Path(scratch)
        manifest = make_records(cli, scratch, options.records, options.samples)

        def cli_run(jobs):
            def run(attempt):
                out = scratch / f"cli-{jobs}-{attempt}"
                start = time.perf_counter()
                subprocess.run([cli, "batch", str(manifest), "--out", str(out), "--jobs",
                                str(jobs), "-q"], check=True)
                return time.perf_counter() - start
            return run

        with LocalCluster(n_workers=options.workers, threads_per_worker=1, processes=True,
                          host="127.0.0.1", dashboard_address=None) as cluster, \
                Client(cluster) as client:
            def dask_run(attempt):
                out = scratch / f"dask-{attempt}"
                start = time.perf_counter()
                ctid.batch.fit_many(manifest, out_dir=out, client=client, ctid_executable=cli)
                return time.perf_counter() - start
            # The runners take turns, so a change in the machine's load hits them alike.
            times = {"serial": [], "threads": [], "dask": []}
            for attempt in range(options.repeat):
                times["serial"].append(cli_run(1)(attempt))
                times["threads"].append(cli_run(options.workers)(attempt))
                times["dask"].append(dask_run(attempt))
            serial, threads, dask = (min(times[k]) for k in ("serial", "threads", "dask"))
        if documents(scratch / "dask-0") != documents(scratch / "cli-1-0"):
            print("error: the Dask documents differ from the serial ones", file=sys.stderr)
            return 1

    n = options.records
    w = options.workers
    print(f"{n} records of N = {options.samples} samples (1 mode, 2 modes, unfactored 2/1, "
          f"detrend), best of {options.repeat}, runners taking turns; {w} workers")
    print("| runner | workers | seconds | records/s | speed-up | scaling efficiency |")
    print("|---|---|---|---|---|---|")
    for label, workers, seconds in (("ctid batch --jobs 1", 1, serial),
                                    (f"ctid batch --jobs {w}", w, threads),
                                    ("fit_many, Dask LocalCluster", w, dask)):
        speed_up = serial / seconds
        print(f"| {label} | {workers} | {seconds:.2f} | {n / seconds:.1f} | {speed_up:.2f} | "
              f"{speed_up / workers:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
