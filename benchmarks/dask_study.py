"""Throughput of a ctid study run serially, on local threads and on Dask (docs/distributed.md).

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/dask_study.py
        [--kind closed-loop] [--runs 2000] [--sizes 2] [--min-samples 500] [--max-samples 1000]
        [--workers 2] [--chunk-runs 25] [--scheduler ADDRESS]

Runs the same study three times: ctid.run_study with one thread (serial), ctid.run_study with
--workers threads, and ctid.study on a Dask cluster (a LocalCluster of --workers processes with
one thread each on 127.0.0.1, started before the clock and stopped after; or the scheduler at
--scheduler, whose workers are counted). Prints runs/s (a run is one Monte Carlo case: every
estimator on one data set), the speed-up over serial and the scaling efficiency (speed-up /
workers), the CPU seconds each mode used (this process, plus the workers' for Dask: on a
shared machine the wall times say little, the CPU times say what the work and the overhead
cost), then whether every record and MSE row of the three runs is identical to the serial
one (IDENTICAL or DIFFERENT; exit status 1 if DIFFERENT).
"""

import argparse
import math
import os
import sys
import time

import numpy as np

import ctid


def identical(a, b):
    """Every record (estimates and standard errors bit for bit, NaNs in the same places) and
    every MSE row of two StudyResults."""
    if len(a.records) != len(b.records) or len(a.mse) != len(b.mse):
        return False
    for x, y in zip(a.records, b.records):
        for name in type(x).fields:
            u, v = getattr(x, name), getattr(y, name)
            if hasattr(u, "shape"):
                if u.shape != v.shape or u.tobytes() != v.tobytes():
                    return False
            elif u != v:
                return False
    for x, y in zip(a.mse, b.mse):
        for name in type(x).fields:
            u, v = getattr(x, name), getattr(y, name)
            both_nan = isinstance(u, float) and isinstance(v, float) and math.isnan(u) and \
                math.isnan(v)
            if not both_nan and u != v:
                return False
    return a.sample_sizes == b.sample_sizes and np.array_equal(a.true_parameters,
                                                                b.true_parameters)


def timed(function):
    """function(), its wall time and the CPU time of this process during it."""
    start, cpu = time.perf_counter(), time.process_time()
    value = function()
    return value, time.perf_counter() - start, time.process_time() - cpu


def worker_cpu_seconds(client):
    """CPU seconds used so far by each worker process (user + system)."""
    return client.run(time.process_time)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", choices=["open-loop", "closed-loop"], default="closed-loop")
    parser.add_argument("--runs", type=int, default=2000)
    parser.add_argument("--sizes", type=int, default=2)
    parser.add_argument("--min-samples", type=int, default=500)
    parser.add_argument("--max-samples", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--chunk-runs", type=int, default=25)
    parser.add_argument("--scheduler", help="use this Dask scheduler instead of a LocalCluster")
    arguments = parser.parse_args()

    kind = ctid.StudyKind.open_loop if arguments.kind == "open-loop" else ctid.StudyKind.closed_loop
    options = ctid.StudyOptions.paper(kind)
    options.runs = arguments.runs
    options.sizes = arguments.sizes
    options.min_samples = arguments.min_samples
    options.max_samples = arguments.max_samples
    options.seed = arguments.seed
    options.validate()
    cases = options.runs * options.sizes
    sizes = ctid.log_spaced_sizes(options.min_samples, options.max_samples, options.sizes)
    print(f"ctid study {arguments.kind}: {options.sizes} sizes x {options.runs} runs = {cases} "
          f"runs, N = {sizes}, estimators {[e.name for e in options.active_estimators()]}, "
          f"max_iterations {options.max_iterations}, tolerance {options.tolerance:g}, "
          f"covariance {options.compute_covariance}")

    options.threads = 1
    serial, serial_seconds, serial_cpu = timed(lambda: ctid.run_study(options))
    options.threads = arguments.workers
    threads, threads_seconds, threads_cpu = timed(lambda: ctid.run_study(options))
    options.threads = 1

    from dask.distributed import Client, LocalCluster

    cluster = None
    if arguments.scheduler:
        client = Client(arguments.scheduler)
    else:
        cluster = LocalCluster(n_workers=arguments.workers, threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address=None)
        client = Client(cluster)
    try:
        dask_workers = sum(client.nthreads().values())
        # Workers import ctid on their first task: warm them up outside the clock.
        client.run(lambda: __import__("ctid") and None)
        before = worker_cpu_seconds(client)
        on_dask, dask_seconds, dask_cpu = timed(
            lambda: ctid.study(options, client=client, chunk_runs=arguments.chunk_runs))
        after = worker_cpu_seconds(client)
        dask_cpu += sum(after[w] - before.get(w, 0.0) for w in after)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

    rows = [("serial (run_study, 1 thread)", 1, serial_seconds, serial_cpu),
            (f"threads (run_study, {arguments.workers} threads)", arguments.workers,
             threads_seconds, threads_cpu),
            (f"Dask ({dask_workers} workers x 1 thread, chunk {arguments.chunk_runs})",
             dask_workers, dask_seconds, dask_cpu)]
    print("load average (1, 5, 15 min) at the end: " +
          ", ".join(f"{x:.2f}" for x in os.getloadavg()) + f" on {os.cpu_count()} cores")
    print(f"{'mode':44} {'workers':>7} {'seconds':>8} {'runs/s':>8} {'speed-up':>8} "
          f"{'efficiency':>10} {'CPU s':>8}")
    for name, workers, seconds, cpu in rows:
        speed_up = serial_seconds / seconds
        print(f"{name:44} {workers:7d} {seconds:8.2f} {cases / seconds:8.1f} {speed_up:8.2f} "
              f"{speed_up / workers:10.2f} {cpu:8.2f}")
    same_threads = identical(threads, serial)
    same_dask = identical(on_dask, serial)
    print(f"threads vs serial: {'IDENTICAL' if same_threads else 'DIFFERENT'} "
          f"({len(serial.records)} records, {len(serial.mse)} MSE rows)")
    print(f"Dask vs serial:    {'IDENTICAL' if same_dask else 'DIFFERENT'}")
    return 0 if same_threads and same_dask else 1


if __name__ == "__main__":
    sys.exit(main())
